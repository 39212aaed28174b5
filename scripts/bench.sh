#!/usr/bin/env bash
# Runs the benchmarks and prints their figures: ./scripts/bench.sh BUILD_DIR
#   BUILD_DIR/tb/bench_core          step timing accuracy, Verilator speed, maximum step rate
#   BUILD_DIR/host/host_plan_bench   host planner throughput on the corpus part (if built)
#   the make demo job (jsdc-laser, demo-machine.toml) split into host planning time and board
#   simulation time (the stream report's figures)
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

part="$root/../shared/gcode-corpus/part.gcode"
if [ -x "$build/host/host_plan_bench" ]; then
  echo "== host_plan_bench $part"
  "$build/host/host_plan_bench" "$part" || status=1
fi
fpgacnc="$build/host/fpgacnc"
if [ -x "$fpgacnc" ]; then
  job="$root/examples/jsdc-laser.gcode"
  cfg="$root/examples/demo-machine.toml"
  echo "== make demo job: $job"
  t0=$(date +%s.%N)
  "$fpgacnc" plan "$job" --config "$cfg" -q >/dev/null || status=1
  t1=$(date +%s.%N)
  out=$("$fpgacnc" stream "$job" --config "$cfg" 2>/dev/null) || status=1
  t2=$(date +%s.%N)
  echo "$out" | grep -E "^(streamed|simulated board)"
  sim=$(echo "$out" | sed -n 's/.*(\([0-9.]*\) s simulating.*/\1/p')
  awk -v p="$t0" -v q="$t1" -v r="$t2" -v s="$sim" 'BEGIN {
    printf "bench: demo job host planning %.3f s, stream wall %.2f s, of which board simulation %.2f s, host and link %.2f s\n", q - p, r - q, s, (r - q) - s }'
fi
exit $status
