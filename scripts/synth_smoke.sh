#!/usr/bin/env bash
# Synthesis smoke test: Yosys synth_intel_alm for Cyclone V on the DE1-SoC top.
# Fails when Yosys reports an error or a warning; prints the resource summary.
# Usage: scripts/synth_smoke.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/synth}
mkdir -p "$out"
log="$out/synth_cyclonev.log"
yosys -q -l "$log" -p "read_verilog rtl/*.v; synth_intel_alm -family cyclonev -top de1soc_top; \
  tee -o $out/synth_cyclonev_stat.txt stat" >/dev/null
if grep -i "^warning" "$log" | grep -v -i "ABC: " ; then
  echo "synth: Yosys printed warnings (above)"; exit 1
fi
echo "synth_intel_alm -family cyclonev -top de1soc_top:"
grep -E "Number of cells|MISTRAL_ALUT|MISTRAL_FF|MISTRAL_MUL|MISTRAL_M10K|ALUT_ARITH" "$out/synth_cyclonev_stat.txt" | sed 's/^/  /'
