#!/usr/bin/env bash
# Open-tool resource report for Cyclone V (Yosys synth_intel_alm -family cyclonev), checked against
# constraints/resource_budget.txt (keys <configuration>.<figure>), of named configurations of
# spec/configs.toml (scripts/configs.sh): cnc_core with the configuration's parameters (chparam),
# every status output a top-level port, or, for a configuration with a board top, that top
# (full-2axis: de1soc_top, the DE1-SoC board with its LEDs and displays). By default
#   v1-board    the original controller's feature set (2 axes, protocol v1 only, no FIFO), with
#               the cfg port
#   full-2axis  the DE1-SoC board (de1soc_top)
#   full-4axis  cnc_core with every feature and 4 axes
# make synth adds v1-board-fixed (the original's fixed step timing); CTest runs
# "v1-board full-2axis" (the 4-axis build is make synth's).
# Every run also fails on a Yosys warning (the former synth_smoke check; ABC's notes excepted).
# For each: LUTs (MISTRAL_ALUT* cells), an ALM estimate, registers (MISTRAL_FF), DSP blocks
# (MISTRAL_MUL*), RAM blocks and bits (MISTRAL_M10K 10240 bits, MISTRAL_MLAB 640 bits per block),
# and the longest combinational path in cells (Yosys ltp -noff on the flattened mapped netlist with
# the register and RAM cells removed, so every path starts and ends at a register, RAM or pin).
# ALM estimate (Yosys 0.23 prints none):
#   ALMs = max( ALUT6 + ceil((ALUT2..5 + NOT) / 2) + ceil(ALUT_ARITH / 2), ceil(FF / 4) )
# (an ALM holds one 6-input LUT, or two smaller LUTs, or two adder bits, and four registers; the
# fitter packs better or worse than this, Quartus' figure is the authority).
# Exits 1 when a figure exceeds its budget, 2 when Yosys fails or prints a warning.
# Usage: scripts/synth_report.sh [OUT_DIR]     env: BUDGET_FILE (default constraints/resource_budget.txt),
#                                                   CONFIGS (default "v1-board full-2axis full-4axis"),
#                                                   EXTRA (configurations after CONFIGS),
#                                                   SYNTH_NAMES (0: without Yosys's autoname pass,
#                                                   as the CTest runs it: the same figures, less
#                                                   readable path names)
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/configs.sh
source scripts/configs.sh
out=${1:-build/synth}
mkdir -p "$out"
budget_file=${BUDGET_FILE:-constraints/resource_budget.txt}
command -v yosys >/dev/null || { echo "synth_report: yosys not found (Debian: yosys)"; exit 2; }

# key value lookup in the budget file ('#' comments); empty when absent.
budget() { awk -v k="$1" '$1 == k { print $2; exit }' "$budget_file"; }

# Cell count of one type (or the sum over a regex of types) in a Yosys stat file.
cells() { awk -v re="^($2)\$" '$1 ~ re { n += $2 } END { print n + 0 }' "$1"; }

declare -A R   # R[config.key] = measured value
run() {
  local cfg=$1 top=$2 pre=$3
  local log="$out/report_$cfg.log" stat="$out/report_${cfg}_stat.txt" ltp="$out/report_${cfg}_ltp.txt"
  local t0=$SECONDS
  local synth="synth_intel_alm -family cyclonev -top $top"
  if [ "${SYNTH_NAMES:-1}" = 0 ]; then
    # synth_intel_alm's own steps without its autoname pass (about a sixth of the run on
    # full-2axis): the same cells; only the longest path's endpoints keep Yosys's internal names.
    synth="$synth -run :map_luts; techmap -map +/intel_alm/common/abc9_map.v; \
      abc9 -maxlut 6 -W 600; techmap -map +/intel_alm/common/abc9_unmap.v; \
      techmap -map +/intel_alm/common/alm_map.v; opt -fast; clean; \
      synth_intel_alm -family cyclonev -top $top -run check:quartus"
  fi
  if ! yosys -q -l "$log" -p "read_verilog -Irtl/include rtl/*.v rtl/*/*.v; $pre $synth; \
      tee -q -o $stat stat; delete t:MISTRAL_FF t:MISTRAL_M10K t:MISTRAL_MLAB; tee -q -o $ltp ltp -noff" \
      >/dev/null; then
    echo "synth_report: Yosys failed for $cfg (see $log)"; exit 2
  fi
  R[$cfg.seconds]=$((SECONDS - t0))
  if grep -i "^warning" "$log" | grep -v -i "ABC: "; then
    echo "synth_report: Yosys printed warnings for $cfg (above; log $log)"; exit 2
  fi
  local a2 a3 a4 a5 a6 arith nots ff
  a2=$(cells "$stat" MISTRAL_ALUT2); a3=$(cells "$stat" MISTRAL_ALUT3)
  a4=$(cells "$stat" MISTRAL_ALUT4); a5=$(cells "$stat" MISTRAL_ALUT5)
  a6=$(cells "$stat" MISTRAL_ALUT6); arith=$(cells "$stat" MISTRAL_ALUT_ARITH)
  nots=$(cells "$stat" MISTRAL_NOT); ff=$(cells "$stat" MISTRAL_FF)
  R[$cfg.luts]=$((a2 + a3 + a4 + a5 + a6 + arith))
  R[$cfg.not]=$nots
  local alm=$((a6 + (a2 + a3 + a4 + a5 + nots + 1) / 2 + (arith + 1) / 2))
  local alm_ff=$(((ff + 3) / 4))
  R[$cfg.alms]=$((alm > alm_ff ? alm : alm_ff))
  R[$cfg.registers]=$ff
  R[$cfg.dsp]=$(cells "$stat" 'MISTRAL_MUL.*')
  R[$cfg.m10k]=$(cells "$stat" MISTRAL_M10K)
  R[$cfg.mlab]=$(cells "$stat" MISTRAL_MLAB)
  R[$cfg.ram_bits]=$((${R[$cfg.m10k]} * 10240 + ${R[$cfg.mlab]} * 640))
  R[$cfg.ltp_cells]=$(sed -nE 's/.*Longest topological path in .*\(length=([-0-9]+)\).*/\1/p' "$ltp" | sort -n | tail -1)
  R[$cfg.ltp_from]=$(awk '/Longest topological path/ {getline; sub(/^ *0: */, ""); print; exit}' "$ltp")
  R[$cfg.ltp_to]=$(awk '/^ *[0-9]+: / {l=$0} END {sub(/^ *[0-9]+: */, "", l); print l}' "$ltp")
}

cfgs=""
for cfg in ${CONFIGS:-v1-board full-2axis full-4axis} ${EXTRA:-}; do
  fpgacnc_config_check "$cfg" synth_report || exit 2
  board=${FPGACNC_CONFIG_BOARD_TOP[$cfg]}
  if [ -n "$board" ]; then
    run "$cfg" "$board" ""
  else
    run "$cfg" cnc_core "chparam $(fpgacnc_config_chparam "$cfg") cnc_core;"
  fi
  cfgs="$cfgs $cfg"
done

keys="luts alms registers dsp m10k mlab ram_bits ltp_cells"
declare -A LABEL=([luts]="LUTs (MISTRAL_ALUT*)" [alms]="ALMs (estimate)" [registers]="registers (MISTRAL_FF)"
  [dsp]="DSP blocks (MISTRAL_MUL*)" [m10k]="M10K blocks (10240 bits)" [mlab]="MLAB blocks (640 bits)"
  [ram_bits]="RAM bits total" [ltp_cells]="longest comb. path (cells)")

echo "Cyclone V (Yosys $(yosys -V | awk '{print $2}') synth_intel_alm -family cyclonev), budgets from $budget_file"
fmt='%-28s %10s'
h1=("" "original")
h2=("" "(2 axes)")
for cfg in $cfgs; do
  w=${#cfg}; [ "$w" -lt 12 ] && w=12
  fmt="$fmt %${w}s %7s"
  h1+=("$cfg" "budget")
  h2+=("${FPGACNC_CONFIG_BOARD_TOP[$cfg]:-cnc_core}" "")
done
fmt="$fmt\n"
printf "$fmt" "${h1[@]}"
printf "$fmt" "${h2[@]}"
fail=0
for k in $keys; do
  ref=$(budget "ref.$k"); ref=${ref:--}
  row=()
  for cfg in $cfgs; do
    v=${R[$cfg.$k]}; b=$(budget "$cfg.$k"); mark=""
    if [ -n "$b" ] && [ "$v" -gt "$b" ]; then mark=" OVER"; fail=1; fi
    row+=("$v$mark" "${b:--}")
  done
  printf "$fmt" "${LABEL[$k]}" "$ref" "${row[@]}"
done
for cfg in $cfgs; do
  echo "$cfg: ${R[$cfg.not]} MISTRAL_NOT cells besides the LUTs; Yosys ${R[$cfg.seconds]} s"
  echo "$cfg: longest path ${R[$cfg.ltp_cells]} cells, from ${R[$cfg.ltp_from]}"
  echo "$cfg:   to ${R[$cfg.ltp_to]}"
done
echo "ALMs = max(ALUT6 + ceil((ALUT2..5 + NOT)/2) + ceil(ALUT_ARITH/2), ceil(FF/4)); logs and stat in $out"
if [ "$fail" -ne 0 ]; then
  echo "synth_report: a resource budget is exceeded (OVER above)"; exit 1
fi
echo "synth_report: within budget"
