#!/usr/bin/env bash
# Formal checks: the `ifdef FORMAL` properties in rtl/ with Yosys + yosys-smtbmc + Z3.
# One Yosys script per property set in scripts/formal/<set>.ys (read + prep; this script writes
# <workdir>/<set>.smt2); each set is run
#   prove k : BMC of depth k from reset (base case) and then k-induction (yosys-smtbmc -i)
#   bmc d   : BMC of depth d from reset only (bounded result)
#   sat k   : Yosys's own SAT engine (`sat -tempinduct`, MiniSat on the bit-blasted design): base
#             case from the initial state and temporal induction, up to induction length k.
#             Z3 does not finish the base case of frame_decoder or segment_executor in 17 minutes;
#             the bit-level engine proves them in seconds.
#   satcover d : the set read with FORMAL_COVER has one assertion whose violation is the state
#             to reach; PASS when Yosys's SAT engine finds such a trace within d clocks from reset
#             (dumped to <workdir>/<set>.cover.vcd): a cover for blocks on which Z3 does not finish.
#   cover d : every cover statement reached within d clocks from reset (yosys-smtbmc -c; a trace
#             per cover in <workdir>/<set>.cover*.vcd); fails when one is unreachable.
# Usage: scripts/formal.sh [workdir] [set...]   (default workdir build/formal, all sets)
# Prints a table (set, method, result, seconds); exits non-zero when any set fails.
set -uo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
work=${1:-build/formal}
shift || true
mkdir -p "$work"
work=$(cd "$work" && pwd)
SOLVER=${FORMAL_SOLVER:-z3}

for tool in yosys yosys-smtbmc "$SOLVER"; do
  command -v "$tool" >/dev/null 2>&1 || { echo "formal: $tool not found (scripts/install-deps.sh)" >&2; exit 2; }
done

# set              method  depth
JOBS=(
  "step_pulse          prove   6"
  "decoder             sat     16"
  "frame_decoder_v1    sat     16"
  "frame_decoder_v2    sat     16"
  "executor_laser      sat     8"
  "executor_dir        sat     12"
  "segment_fifo        prove   8"
  "heater_channel      sat     6"
  "arc_stop            sat     4"
  "input_filter        prove   8"
  "input_filter        cover   16"
  "limit_guard         prove   4"
  "limit_guard         cover   8"
  "travel_guard        prove   4"
  "travel_guard        cover   8"
  "trigger_latch       sat     6"
  "trigger_latch       satcover 12"
  "position_offset     sat     4"
  "feed_rate           sat     6"
  "feed_rate           satcover 16"
  "laser_pwm           sat     4"
  "laser_pwm           satcover 270"
)

want=("$@")
fail=0
rows=()
for job in "${JOBS[@]}"; do
  read -r set mode depth <<<"$job"
  if [ ${#want[@]} -gt 0 ] && [[ " ${want[*]} " != *" $set "* ]]; then continue; fi
  log="$work/$set.log"
  [ "$mode" = cover ] || [ "$mode" = satcover ] && log="$work/$set.cover.log"
  t0=$(date +%s.%N)
  result=PASS
  # The .ys scripts read the RTL (paths relative to the repository root) and run prep.
  if [ "$mode" = satcover ]; then
    # the set's cover target is an assertion under FORMAL_COVER: reachable when yosys's SAT
    # solver finds a trace from reset (all registers 0, then the set's reset assumption) that
    # violates it within depth clocks; the trace is dumped
    if ! yosys -l "$log" -p "script scripts/formal/$set.ys; design -reset; \
        read_verilog -Irtl/include -formal -DFORMAL_COVER $(sed -n 's/^read_verilog .*-formal //p' \
        "scripts/formal/$set.ys"); $(grep '^chparam' "scripts/formal/$set.ys"); \
        prep -top $set; flatten; sat -seq $depth -prove-asserts -set-assumes -set-init-zero \
        -dump_vcd $work/$set.cover.vcd" >/dev/null 2>&1 && ! grep -q "model found: FAIL" "$log"; then
      result=ERROR
    elif ! grep -q "model found: FAIL" "$log"; then
      result="FAIL(cover)"
    fi
  elif [ "$mode" = sat ]; then
    if ! yosys -l "$log" -p "script scripts/formal/$set.ys; flatten; \
        sat -tempinduct -prove-asserts -set-assumes -maxsteps $depth" >/dev/null 2>&1; then
      result=ERROR
    elif ! grep -q "Induction step proven: SUCCESS" "$log"; then
      result=FAIL
    fi
  elif ! yosys -q -l "$work/$set.yosys.log" \
      -p "script scripts/formal/$set.ys; write_smt2 -wires $work/$set.smt2" >/dev/null 2>&1; then
    result=ERROR
  else
    smt="$work/$set.smt2"
    if [ "$mode" = cover ]; then
      if ! yosys-smtbmc -s "$SOLVER" -c -t "$depth" --dump-vcd "$work/$set.cover.vcd" "$smt" \
          >"$log" 2>&1; then
        result="FAIL(cover)"
      fi
    elif ! yosys-smtbmc -s "$SOLVER" --presat -t "$depth" --dump-vcd "$work/$set.bmc.vcd" "$smt" \
        >"$log" 2>&1; then
      result=FAIL
    elif [ "$mode" = prove ] && ! yosys-smtbmc -s "$SOLVER" -i -t "$depth" \
        --dump-vcd "$work/$set.induct.vcd" "$smt" >>"$log" 2>&1; then
      result="FAIL(induction)"
    fi
  fi
  t1=$(date +%s.%N)
  secs=$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}')
  [ "$result" = PASS ] || fail=1
  case $mode in
    prove) method="prove k=$depth" ;;
    sat) method="sat-induct k<=$depth" ;;
    cover) method="cover d=$depth" ;;
    satcover) method="sat-cover d=$depth" ;;
    *) method="bmc depth $depth" ;;
  esac
  rows+=("$(printf '%-18s %-16s %-16s %6s' "$set" "$method" "$result" "$secs")")
  [ "$result" = PASS ] || { echo "formal: $set $result, log $log"; grep -E "failed|Assert|ERROR|Error|FAIL" "$log" "$work/$set.yosys.log" 2>/dev/null | head -10; }
done
printf '%-18s %-16s %-16s %6s\n' "property set" "method" "result" "time s"
printf '%s\n' "${rows[@]}"
exit $fail
