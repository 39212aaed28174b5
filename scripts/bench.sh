#!/usr/bin/env bash
# Runs the benchmarks and prints their figures: ./scripts/bench.sh BUILD_DIR
#   BUILD_DIR/tb/bench_core          step timing accuracy, Verilator speed, maximum step rate
#   BUILD_DIR/host/host_plan_bench   host planner throughput on the corpus part (if built)
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
exit $status
