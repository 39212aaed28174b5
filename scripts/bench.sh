#!/usr/bin/env bash
# Runs the benchmarks and prints their figures: ./scripts/bench.sh BUILD_DIR
#   BUILD_DIR/tb/bench_core          step timing accuracy, Verilator speed, maximum step rate
#   BUILD_DIR/tb/bench_protocol      v1 against v2 through the pins: segments/s, bytes, line use
#   BUILD_DIR/host/host_plan_bench   host planner throughput on the corpus part (if built)
#   the make demo job: the whole jsdc-laser job at real feeds on the twin board (host planning and
#   board simulation time), then its first 100 moves on both boards, compared
#   fpgacnc grbl-bench: a grbl sender streaming 0.1 mm laser moves at 115200 baud into `fpgacnc
#   grbl` on the twin board (moves/s delivered and executed, executor gaps)
#   the virtual platform on octocat.gcode and part.gcode at their real feeds (wall, max RSS)
#   a fresh clone's `make demo` and `make test` (BENCH_FRESH=0 skips them)
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
status=0

if [ -x "$build/tb/bench_core" ]; then
  echo "== bench_core"
  "$build/tb/bench_core" || status=1
else
  echo "bench.sh: $build/tb/bench_core not built" >&2
  status=1
fi

# Protocol v1 against v2 through the pins (built by `make bench`): segments per second at 115 200
# and 1 000 000 baud, bytes per segment, v2 line utilisation.
if [ -x "$build/tb/bench_protocol" ]; then
  echo "== bench_protocol"
  "$build/tb/bench_protocol" "${PROTOCOL_MOVES:-1000}" || status=1
fi

part="$root/corpus/cncjs/part.gcode"
if [ -x "$build/host/host_plan_bench" ]; then
  echo "== host_plan_bench $part"
  "$build/host/host_plan_bench" "$part" || status=1
fi
fpgacnc="$build/host/fpgacnc"
if [ -x "$fpgacnc" ]; then
  job="$root/examples/jsdc-laser.gcode"
  echo "== make demo, step 1: fpgacnc stream examples/jsdc-laser.gcode (real feeds, twin board behind the pty)"
  t0=$(date +%s.%N)
  "$fpgacnc" plan "$job" -q >/dev/null || status=1
  t1=$(date +%s.%N)
  out=$("$fpgacnc" stream "$job" 2>/dev/null) || status=1
  t2=$(date +%s.%N)
  echo "$out" | grep -E "^(streamed|simulated board)"
  sim=$(echo "$out" | sed -n 's/.*(\([0-9.]*\) s simulating.*/\1/p')
  awk -v p="$t0" -v q="$t1" -v r="$t2" -v s="$sim" 'BEGIN {
    printf "bench: demo job host planning %.3f s, stream wall %.2f s, of which board simulation %.2f s, host and link %.2f s\n", q - p, r - q, s, (r - q) - s }'
  echo "== make demo, step 2: fpgacnc stream examples/jsdc-laser.gcode --model both --max-moves 100 --config examples/demo-machine.toml"
  t3=$(date +%s.%N)
  "$fpgacnc" stream "$job" --model both --max-moves 100 --config "$root/examples/demo-machine.toml" 2>/dev/null | grep -E "^(tlm board|rtl board|rtl vs tlm)" || status=1
  t4=$(date +%s.%N)
  awk -v p="$t1" -v q="$t4" -v r="$t3" 'BEGIN {
    printf "bench: make demo after the build: %.1f s wall for both steps (bar <= 60 s), of which the twin/RTL comparison %.1f s\n", q - p, q - r }'
fi
# Sender-side throughput of `fpgacnc grbl` (docs/grbl.md, "Throughput"): a character-counting
# sender streams GRBL_MOVES 0.1 mm laser moves at 115200 baud (simulated line time); the
# executor's idle clocks between segments must be 0. Run 1: the default machine (host -> FPGA
# link 115200 baud) at F1500, within that link; run 2: F3000 with the FPGA link at 1 Mbaud; run 3:
# F3000 on the 115200 FPGA link, which carries fewer moves/s than that feed needs (the bench says
# so; its gaps are the expected figure, not a failure).
if [ -x "$fpgacnc" ]; then
  GRBL_MOVES=${GRBL_MOVES:-300}
  for args in "--feed 1500" "--feed 3000 --board-baud 1000000"; do
    echo "== fpgacnc grbl-bench --moves $GRBL_MOVES $args"
    "$fpgacnc" grbl-bench --moves "$GRBL_MOVES" $args 2>/dev/null | grep -v "^simulated board" || status=1
  done
  echo "== fpgacnc grbl-bench --moves $GRBL_MOVES --feed 3000 (FPGA link 115200: expected to show its limit)"
  "$fpgacnc" grbl-bench --moves "$GRBL_MOVES" --feed 3000 2>/dev/null | grep -v "^simulated board" || true
fi
# Virtual platform (SystemC twins, systemc/) against the Verilated RTL on the same job: the first
# $VP_MOVES moves of the demo job with the same host schedule, simulated clocks per wall second
# of each and their ratio (the run also checks that both give identical edges); then the wall
# time of the two large corpus jobs, whole, at their real feeds, on the virtual platform.
if [ -x "$fpgacnc" ]; then
  VP_MOVES=${VP_MOVES:-20}
  job="$root/examples/jsdc-laser.gcode"
  echo "== virtual platform vs RTL: $job, first $VP_MOVES moves"
  out=$("$fpgacnc" sim "$job" --model both --max-moves "$VP_MOVES" 2>&1) || status=1
  echo "$out" | grep -E "^(simulated board|rtl vs tlm)"
  rtl=$(echo "$out" | sed -n 's/^simulated board (rtl): \([0-9]*\) cycles.* \([0-9.]*\) M clocks\/s.*/\1 \2/p')
  tlm=$(echo "$out" | sed -n 's/^simulated board (tlm): \([0-9]*\) cycles.* \([0-9.]*\) M clocks\/s.*/\1 \2/p')
  echo "$rtl $tlm" | awk '{ if ($2 > 0) printf "bench: virtual platform %.0f M clocks/s, Verilated RTL %.2f M clocks/s on the same %d clocks: %.0fx\n", $4, $2, $1, $4 / $2 }'
  for f in octocat part; do
    g="$root/corpus/cncjs/$f.gcode"
    echo "== virtual platform, whole job at its real feeds: fpgacnc sim corpus/cncjs/$f.gcode --model tlm"
    out=$(/usr/bin/time -f "time: %e s wall, %M KB max RSS" "$fpgacnc" sim "$g" --model tlm 2>&1) || status=1
    line=$(echo "$out" | grep "^simulated board (tlm)")
    echo "$line"
    echo "$out" | grep "^time:" | tail -1 | awk -v f="$f.gcode" '{
      printf "bench: %s on the virtual platform: %.2f s wall including planning (bar <= 5 s), %.0f MB max RSS (bar <= 1024 MB)\n", f, $2, $5 / 1024 }'
  done
fi
# The README's two commands on a fresh clone of this repository's HEAD (BENCH_FRESH=0 skips this
# section; it takes as long as a first `make demo` plus a first `make test`): each in its own clone,
# so each builds from nothing.
if [ "${BENCH_FRESH:-1}" = 1 ]; then
  tmp=$(mktemp -d)
  for target in demo test; do
    git clone -q "$root" "$tmp/$target"
    echo "== fresh clone: git clone $root && make $target (log: $tmp/$target.log)"
    t0=$(date +%s.%N)
    if (cd "$tmp/$target" && make "$target") >"$tmp/$target.log" 2>&1; then verdict=passed; else verdict=FAILED; status=1; fi
    t1=$(date +%s.%N)
    awk -v p="$t0" -v q="$t1" -v t="$target" -v v="$verdict" 'BEGIN {
      bar = t == "test" ? " (bar <= 600 s on 2 cores)" : ""
      printf "bench: fresh clone make %s: %.0f s wall, build included%s, %s\n", t, q - p, bar, v }'
    if [ "$target" = test ]; then grep -E "tests passed|tests failed" "$tmp/$target.log" | tail -1; fi
  done
fi
exit $status
