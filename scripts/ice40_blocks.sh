#!/usr/bin/env bash
# Open timing proxy for the full design's blocks: each block alone (the parameters cnc_core gives it
# in the full 2-axis build) placed and routed on an iCE40 HX8K (ct256) at 50 MHz with nextpnr-ice40.
# The full design does not fit an HX8K; a block that meets 50 MHz on the slower iCE40 fabric is
# strong evidence for the Cyclone V (Quartus decides).
# The placed top is a generated wrapper (OUT_DIR/ice40_blk_<name>.v): every input bit of the block
# except clk / rst comes from a 97-bit shift register loaded from one pin (bit i from stage i mod 97:
# the inputs are registers, as in cnc_core, and the synthesizer cannot treat them as constants),
# every output is captured into a load/shift register read out on one pin (one LUT level per bit,
# keeps all output logic alive). The block keeps its hierarchy (synth_ice40 -noflatten), so inputs
# that share a stage are not merged inside it; a one-flop-per-input wrapper would fill a third of
# the part for arc_dda (948 input bits) and make the proxy measure congestion.
# Reports the post-route Fmax per block and seed and, below FREQ, the critical path's ends (whole
# path in OUT_DIR/ice40_blk_<name>.s<seed>.critical.txt). Each block is synthesized once and placed
# and routed once per seed of SEEDS (nextpnr's result moves by a few MHz with the placement seed).
# A report by default: exits 0 when a block is below FREQ (the known figures are in
# docs/synthesis.md); with STRICT=1 (`make synth`) it exits 1 when any block on any seed is below
# FREQ or does not fit. Exits non-zero when the flow fails.
# Usage: scripts/ice40_blocks.sh [OUT_DIR]
#   env: BLOCKS="arc_dda profile_gen ..." FREQ=50 SEEDS="1 2 3" (default SEED, 1) STRICT=0
# shellcheck source=scripts/ice40_env.sh
source "$(dirname "$0")/ice40_env.sh" "$@"
# block -> "file(s)|chparam" (parameters as cnc_core's full 2-axis build passes them)
declare -A BLK=(
  [arc_dda]="rtl/motion/arc_dda.v|"
  [profile_gen]="rtl/motion/profile_gen.v|"
  [dda_profile]="rtl/motion/dda_profile.v|"
  [dda_linear]="rtl/motion/dda_linear.v|"
  [pid_incr]="rtl/heater/pid_incr.v|"
  [heater_channel]="rtl/heater/heater_channel.v rtl/heater/pid_incr.v rtl/heater/heater_safety.v rtl/machine/pwm.v|"
  [frame_decoder]="rtl/protocol/frame_decoder.v rtl/protocol/frame_fields.v rtl/protocol/entry_pack.v rtl/protocol/crc16_ccitt.v rtl/machine/travel_guard.v|-set N_AXES 2 -set TRIGGER 1"
  [response_encoder]="rtl/protocol/response_encoder.v rtl/protocol/crc16_ccitt.v|-set N_AXES 2 -set HEAT_BYTES 16"
  [segment_prep]="rtl/motion/segment_prep.v rtl/motion/prep_profile.v rtl/motion/prep_arc.v rtl/motion/prep_dir_tracker.v|-set N_AXES 2"
  [step_pulse]="rtl/motion/step_pulse.v|"
  [uart_rx]="rtl/protocol/uart_rx.v|"
  [uart_tx]="rtl/protocol/uart_tx.v|"
  [input_filter]="rtl/machine/input_filter.v|-set N 4 -set FILTER_CLKS 50000"
  [limit_guard]="rtl/machine/limit_guard.v|-set N_AXES 2"
  [trigger_latch]="rtl/machine/trigger_latch.v|-set N_AXES 2"
  [position_offset]="rtl/machine/position_offset.v|-set N_AXES 2"
  [travel_guard]="rtl/machine/travel_guard.v|-set N_AXES 2"
  [step_config]="rtl/motion/step_config.v|-set N_AXES 2"
  [feed_rate]="rtl/motion/feed_rate.v|"
  [status_counters]="rtl/protocol/status_counters.v|"
  [estop_latch]="rtl/machine/estop_latch.v|"
  [machine_outputs]="rtl/machine/machine_outputs.v rtl/machine/pwm.v rtl/machine/laser_scale.v rtl/machine/laser_pwm.v|"
  [answer_source]="rtl/protocol/answer_source.v rtl/protocol/response_encoder.v rtl/protocol/crc16_ccitt.v|-set N_AXES 2"
  # the v1-only builds' front end (v1-board's parameters; those builds are timed whole by
  # ice40_timing.sh): only on request
  [front_v1]="rtl/protocol/front_v1.v rtl/protocol/packet_decoder_v1.v|-set N_AXES 2"
  [pwm]="rtl/machine/pwm.v|-set PWM_BITS 8 -set PWM_DIV 195"
  [ltc2308_spi]="rtl/heater/ltc2308_spi.v|"
  [heater_safety]="rtl/heater/heater_safety.v|"
  [heater_block]="rtl/heater/heater_block.v rtl/heater/heater_channel.v rtl/heater/pid_incr.v rtl/heater/heater_safety.v rtl/machine/pwm.v rtl/heater/ltc2308_spi.v rtl/heater/temp_table.v|"
  # the 775-bit entry of the full 2-axis build needs 49 RAM blocks of the HX8K's 32: 512 bits
  [segment_fifo]="rtl/protocol/segment_fifo.v|-set WIDTH 512 -set DEPTH 64"
  # with arc_dda (measured alone above) the executor does not fit: ARCS 0
  [segment_executor]="rtl/motion/segment_executor.v rtl/motion/axis_channel.v rtl/motion/dir_sequencer.v rtl/motion/dda_linear.v rtl/motion/dda_profile.v rtl/motion/profile_gen.v rtl/motion/step_pulse.v rtl/motion/arc_dda.v|-set N_AXES 2 -set ARCS 0"
)
# segment_prep (2 axes, full build) does not fit the HX8K with the wrapper; only on request
blocks=${BLOCKS:-"arc_dda segment_executor profile_gen dda_profile dda_linear step_pulse frame_decoder
  segment_fifo response_encoder heater_block heater_channel pid_incr heater_safety ltc2308_spi pwm uart_rx uart_tx input_filter limit_guard trigger_latch
  position_offset travel_guard step_config feed_rate status_counters estop_latch machine_outputs answer_source"}
for tool in yosys nextpnr-ice40 python3; do
  command -v "$tool" >/dev/null || { echo "ice40_blocks: $tool not found"; exit 2; }
done

seeds=${SEEDS:-$seed}
status=0
summary=()
for b in $blocks; do
  [ -n "${BLK[$b]:-}" ] || { echo "ice40_blocks: unknown block $b (${!BLK[*]})"; exit 2; }
done
for b in $blocks; do
  files=${BLK[$b]%%|*}
  chp=${BLK[$b]#*|}
  tag="ice40_blk_$b"
  pre=""
  [ -n "$chp" ] && pre="chparam $chp $b;"
  # the block's ports (after parameters) -> wrapper
  yosys -q -p "read_verilog -Irtl/include $files; $pre hierarchy -top $b; proc; write_json $out/$tag.ports.json" >/dev/null
  python3 - "$out/$tag.ports.json" "$b" "$chp" >"$out/$tag.v" <<'PYEOF'
import json, sys
d = json.load(open(sys.argv[1])); name = sys.argv[2]; chp = sys.argv[3].split()
mods = d["modules"]
top = [m for m in mods if m == name or m.endswith("\\" + name) or name in m and "paramod" in m]
ports = mods[top[0]]["ports"]
params = [(chp[i + 1], chp[i + 2]) for i in range(0, len(chp), 3)]
ins = [(p, len(v["bits"])) for p, v in ports.items() if v["direction"] == "input" and p not in ("clk", "rst")]
outs = [(p, len(v["bits"])) for p, v in ports.items() if v["direction"] == "output"]
wi = sum(w for _, w in ins); wo = sum(w for _, w in outs)
print("// Generated by scripts/ice40_blocks.sh: iCE40 wrapper around %s (inputs from a shift register," % name)
print("// outputs into a load/shift register).")
print("`default_nettype none")
print("module ice40_blk_top (input wire clk, input wire rst, input wire scan_in, input wire scan_load,")
print("                      output wire scan_out);")
ws = max(min(wi, 97), 2)
print("  reg [%d:0] in_reg = %d'd0;" % (ws - 1, ws))
print("  always @(posedge clk) in_reg <= {in_reg[%d:0], scan_in};" % (ws - 2))
off = 0
for p, w in ins:
    bits = ", ".join("in_reg[%d]" % ((off + k) % ws) for k in reversed(range(w)))
    print("  wire [%d:0] i_%s = {%s};" % (w - 1, p, bits)); off += w
for p, w in outs:
    print("  wire [%d:0] o_%s;" % (w - 1, p))
pstr = ", ".join(".%s(%s)" % (k, v) for k, v in params)
print("  %s %s u_blk (" % (name, ("#(" + pstr + ")") if pstr else ""))
conns = [".clk(clk)", ".rst(rst)"] + [".%s(i_%s)" % (p, p) for p, _ in ins] + [".%s(o_%s)" % (p, p) for p, _ in outs]
if "rst" not in ports: conns.remove(".rst(rst)")
print("      " + ",\n      ".join(conns) + ");")
cat = ", ".join("o_%s" % p for p, _ in outs)
print("  wire [%d:0] status = {%s};" % (wo - 1, cat))
print("  reg [%d:0] scan_reg = %d'd0;" % (wo, wo + 1))
print("  always @(posedge clk) scan_reg <= scan_load ? {1'b0, status} : {scan_reg[%d:0], 1'b0};" % (wo - 1))
print("  assign scan_out = scan_reg[%d];" % wo)
print("endmodule")
PYEOF
  t0=$(date +%s)
  if ! yosys -q -l "$out/$tag.yosys.log" -p "read_verilog -Irtl/include $files $out/$tag.v; \
      synth_ice40 -noflatten -top ice40_blk_top -json $out/$tag.json" >/dev/null; then
    echo "ice40_blocks: Yosys failed for $b (see $out/$tag.yosys.log)"; status=1; continue
  fi
  t1=$(date +%s)
  ty=$((t1 - t0))
  for sd in $seeds; do
    log="$out/$tag.s$sd.nextpnr.log"
    if ! nextpnr-ice40 --hx8k --package ct256 --freq "$freq" --seed "$sd" \
        --pcf-allow-unconstrained --timing-allow-fail --json "$out/$tag.json" \
        --log "$log" -q >/dev/null 2>&1; then
      echo "ice40_blocks: nextpnr-ice40 failed for $b seed $sd (see $log)"
      grep -E "ERROR|Device utilisation|ICESTORM_LC|ICESTORM_RAM" "$log" | tail -3 || true
      summary+=("$(printf '  %-18s seed %-3s does not place/fit (see log)' "$b" "$sd")"); status=1; continue
    fi
    t2=$(date +%s)
    fmax=$(grep "Max frequency for clock" "$log" | tail -1 | sed -E 's/.*: *([0-9.]+) MHz.*/\1/')
    lcs=$(grep -E "ICESTORM_LC: +[0-9]+/" "$log" | tail -1 | sed -E 's/.*ICESTORM_LC: *//')
    verdict=PASS
    if awk -v f="$fmax" -v r="$freq" 'BEGIN { exit !(f < r) }'; then
      verdict=FAIL
      [ "${STRICT:-0}" = 1 ] && status=1
    fi
    summary+=("$(printf '  %-18s seed %-3s Fmax %7s MHz (%s)  LCs %s  time: yosys %ds, nextpnr %ds' \
      "$b" "$sd" "$fmax" "$verdict" "$lcs" "$ty" $((t2 - t1)))")
    crit="$out/$tag.s$sd.critical.txt"
    awk '/Critical path report for clock/ {buf=""; p=1} p {buf = buf $0 "\n"} p && /ns logic/ {p=0; last=buf}
         END {printf "%s", last}' "$log" >"$crit"
    if [ "$verdict" = FAIL ]; then
      echo "ice40_blocks: $b below $freq MHz on seed $sd; critical path:"
      grep -m1 "Source" "$crit" | sed -E 's/^Info: *[0-9.]+ +[0-9.]+ +Source /  from /'
      grep "Sink" "$crit" | tail -1 | sed -E 's/^Info: *Sink /  to   /'
      grep "ns logic" "$crit" | sed 's/^Info: */  /'
    fi
    t1=$(date +%s)
  done
done
echo "iCE40 HX8K ct256 blocks, nextpnr-ice40 --freq $freq, seeds $seeds (post-route; wrapper LCs included):"
printf '%s\n' "${summary[@]}"
[ "${STRICT:-0}" = 1 ] && [ "$status" != 0 ] && echo "ice40_blocks: STRICT=1: a block is below $freq MHz or does not fit"
exit $status
