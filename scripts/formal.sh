#!/usr/bin/env bash
# Formal checks: the `ifdef FORMAL` properties in rtl/ with Yosys + yosys-smtbmc + Z3.
# One Yosys script per property set in scripts/formal/<set>.ys (read + prep; this script writes
# <workdir>/<set>.smt2); each set is run
#   prove k : BMC of depth k from reset (base case) and then k-induction (yosys-smtbmc -i)
#   bmc d   : BMC of depth d from reset only (bounded result)
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

# set            method  depth
# scripts/formal/executor_laser.ys exists but is not run: Z3 4.8.12 does not finish its first BMC
# step on segment_executor's 64-bit DDA (> 10 min, 3 GB); see docs/synthesis.md "Formal".
# scripts/formal/frame_decoder_v1.ys (frame_decoder's v1 path, the packet_decoder_v1 properties
# carried over) is not run either: Z3 did not finish its base case within 17 minutes. The
# "decoder" set still proves packet_decoder_v1, kept in rtl/ for the block co-simulation.
JOBS=(
  "step_pulse        prove   6"
  "decoder           prove   14"
  "segment_fifo      prove   8"
)

want=("$@")
fail=0
rows=()
for job in "${JOBS[@]}"; do
  read -r set mode depth <<<"$job"
  if [ ${#want[@]} -gt 0 ] && [[ " ${want[*]} " != *" $set "* ]]; then continue; fi
  log="$work/$set.log"
  t0=$(date +%s.%N)
  result=PASS
  # The .ys scripts read the RTL (paths relative to the repository root) and run prep.
  if ! yosys -q -l "$work/$set.yosys.log" \
      -p "script scripts/formal/$set.ys; write_smt2 -wires $work/$set.smt2" >/dev/null 2>&1; then
    result=ERROR
  else
    smt="$work/$set.smt2"
    if ! yosys-smtbmc -s "$SOLVER" --presat -t "$depth" --dump-vcd "$work/$set.bmc.vcd" "$smt" \
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
  if [ "$mode" = prove ]; then method="prove k=$depth"; else method="bmc depth $depth"; fi
  rows+=("$(printf '%-18s %-16s %-16s %6s' "$set" "$method" "$result" "$secs")")
  [ "$result" = PASS ] || { echo "formal: $set $result, log $log"; grep -E "failed|Assert|ERROR|Error" "$log" "$work/$set.yosys.log" 2>/dev/null | head -10; }
done
printf '%-18s %-16s %-16s %6s\n' "property set" "method" "result" "time s"
printf '%s\n' "${rows[@]}"
exit $fail
