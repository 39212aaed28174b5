#!/usr/bin/env bash
# Per-block resource breakdown of a cnc_core build (Yosys synth_intel_alm -family cyclonev).
# The design is flattened and optimized as a whole first (so constant inputs and unread outputs
# of a block are removed as in the real, flattened build), then every cell is moved back into a
# submodule named after the RTL file it came from (its src attribute: the innermost file wins,
# e.g. dda_linear inside segment_executor), and each submodule is mapped separately (-noflatten).
# The per-block figures therefore add up to slightly more LUTs than the flattened build (ABC does
# not optimize across the block boundaries); registers match to within a few.
# Usage: scripts/synth_breakdown.sh [OUT_DIR] [CONFIGURATION]
#   a named configuration of spec/configs.toml (scripts/configs.sh), default v1-board; e.g.
#   scripts/synth_breakdown.sh build/synth v1-board-fixed
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/configs.sh
source scripts/configs.sh
out=${1:-build/synth}
cfg=${2:-v1-board}
fpgacnc_config_check "$cfg" synth_breakdown || exit 2
chp=$(fpgacnc_config_chparam "$cfg")
mkdir -p "$out"
command -v yosys >/dev/null || { echo "synth_breakdown: yosys not found (Debian: yosys)"; exit 2; }
blocks="front_v2 front_v1 answer_source machine_outputs estop_latch step_config status_counters
        segment_prep prep_profile prep_arc prep_dir_tracker segment_executor axis_channel dir_sequencer dda_linear step_pulse uart_rx uart_tx packet_decoder_v1
        frame_decoder segment_fifo response_encoder profile_gen dda_profile arc_dda heater_block
        heater_channel pid_incr pwm heater_safety ltc2308_spi temp_table crc16_ccitt"
attrs=""
# outer files first: a cell whose src names several files gets the innermost (last setattr wins)
for b in segment_executor heater_block heater_channel $blocks; do
  attrs="$attrs setattr -set submod \"bd_$b\" a:src=*/$b.v:*;"
done
stat="$out/breakdown_stat.txt"
yosys -q -l "$out/breakdown.log" -p "read_verilog -Irtl/include rtl/*.v rtl/*/*.v; chparam $chp cnc_core;
  hierarchy -top cnc_core; proc; flatten; opt -full; wreduce; opt_clean; $attrs submod;
  synth_intel_alm -family cyclonev -top cnc_core -noflatten; tee -q -o $stat stat" >/dev/null
echo "cnc_core $cfg ($chp): per-block Yosys synth_intel_alm figures (cnc_core = its own logic)"
awk '
  /^=== / { name = $2; sub(/^cnc_core_bd_/, "", name); if (name == "design") name = "total"; next }
  $1 ~ /^MISTRAL_ALUT/ { lut[name] += $2 }
  $1 == "MISTRAL_FF" { ff[name] += $2 }
  $1 ~ /^MISTRAL_MUL/ { dsp[name] += $2 }
  END {
    printf "%-22s %7s %7s %4s\n", "block", "LUTs", "FFs", "DSP"
    for (n in lut) if (n != "total") printf "%-22s %7d %7d %4d\n", n, lut[n], ff[n], dsp[n]
    printf "%-22s %7d %7d %4d\n", "total (sum of blocks)", lut["total"], ff["total"], dsp["total"]
  }' "$stat" | { read -r h; echo "$h"; sort -k2 -n -r; }
