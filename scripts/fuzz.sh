#!/usr/bin/env bash
# Builds and runs the libFuzzer targets of fuzz/ (clang, AddressSanitizer + UBSan).
#
#   scripts/fuzz.sh smoke [--time S]   each target S seconds (default 30) from the seed corpus
#                                      (fresh working corpus), fixed seed; `make fuzz`, a step
#                                      of .ci/run
#   scripts/fuzz.sh soak  [--time S]   each target S seconds (default 600), working corpus kept
#                                      between runs; `make fuzz-soak` / `make soak`
#   scripts/fuzz.sh build              configure and build only
#   options: --build-dir DIR (default build/fuzz), --seed N (default 1), --jobs N (build, 2),
#            TARGET... (default: every target built)
#
# Fails (exit 1) on any crash, sanitizer report, leak, timeout or out-of-memory; the input is
# kept as DIR/artifacts/TARGET-crash-* and the command to reproduce it is printed. Fails with a
# clear message when clang or the libFuzzer runtime is missing (scripts/install-deps.sh
# installs clang and libclang-rt-14-dev).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
MODE=${1:-smoke}
shift || true
BUILD="$ROOT/build/fuzz"
SEED=1
JOBS=2
TIME=""
TARGETS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --time) TIME=$2; shift 2 ;;
    --seed) SEED=$2; shift 2 ;;
    --build-dir) BUILD=$2; shift 2 ;;
    --jobs) JOBS=$2; shift 2 ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) TARGETS+=("$1"); shift ;;
  esac
done
case "$MODE" in
  smoke) TIME=${TIME:-30} ;;
  soak) TIME=${TIME:-600} ;;
  build) ;;
  *) echo "fuzz.sh: unknown mode '$MODE' (smoke, soak, build)" >&2; exit 2 ;;
esac

die() { echo "fuzz.sh: FAIL: $*" >&2; exit 1; }

# Toolchain: clang++ that can link a libFuzzer + ASan + UBSan program.
for t in clang clang++; do
  command -v "$t" >/dev/null 2>&1 ||
    die "$t not found: install clang and libclang-rt-14-dev (make deps, scripts/install-deps.sh)"
done
probe=$(mktemp -d)
trap 'rm -rf "$probe"' EXIT
printf 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }\n' \
  >"$probe/p.cpp"
if ! clang++ -fsanitize=fuzzer,address,undefined "$probe/p.cpp" -o "$probe/p" 2>"$probe/err"; then
  cat "$probe/err" >&2
  die "clang++ cannot link a libFuzzer program (-fsanitize=fuzzer,address,undefined): the" \
      "fuzzer runtime is missing; install libclang-rt-14-dev (make deps)"
fi

# Configure (with clang; reconfigure a build dir made with another compiler) and build.
if [ -f "$BUILD/CMakeCache.txt" ] &&
   ! grep -q "CMAKE_CXX_COMPILER:[A-Z]*=.*clang++" "$BUILD/CMakeCache.txt"; then
  rm -rf "$BUILD"
fi
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ cmake -S "$ROOT/fuzz" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    >"$BUILD.configure.log" 2>&1 || { cat "$BUILD.configure.log" >&2; die "configure failed"; }
else
  cmake "$BUILD" >"$BUILD.configure.log" 2>&1 ||
    { cat "$BUILD.configure.log" >&2; die "configure failed"; }
fi
grep "^-- fuzz:" "$BUILD.configure.log" || true
cmake --build "$BUILD" -j "$JOBS" >"$BUILD/build.log" 2>&1 ||
  { tail -50 "$BUILD/build.log" >&2; die "build failed (log: $BUILD/build.log)"; }
[ "$MODE" = build ] && { echo "fuzz.sh: built in $BUILD"; exit 0; }

ALL=(fuzz_gcode fuzz_v2_codec)
declare -A CORPUS=([fuzz_gcode]=gcode [fuzz_v2_codec]=v2_codec)
# Longest input: a G-code file of ~100 lines; a v2 stream of ~15 frames (decoders throw often,
# longer inputs only slow the search down).
declare -A MAXLEN=([fuzz_gcode]=4096 [fuzz_v2_codec]=1024)
if [ ${#TARGETS[@]} -eq 0 ]; then
  for t in "${ALL[@]}"; do
    if [ -x "$BUILD/$t" ]; then
      TARGETS+=("$t")
    else
      echo "fuzz.sh: NOTE: $t not built (no v2 codec sources: FPGACNC_HOST_V2_CODEC_SOURCES in" \
           "host/sources.cmake)"
    fi
  done
fi

mkdir -p "$BUILD/artifacts" "$BUILD/logs"
status=0
summary=()
for t in "${TARGETS[@]}"; do
  [ -x "$BUILD/$t" ] || die "$t: not built"
  seeds="$ROOT/fuzz/corpus/${CORPUS[$t]}"
  work="$BUILD/corpus/$t"
  [ "$MODE" = smoke ] && rm -rf "$work"
  mkdir -p "$work"
  log="$BUILD/logs/$t.$MODE.log"
  cmd=("$BUILD/$t" -seed="$SEED" -max_total_time="$TIME" -timeout=25 -rss_limit_mb=2048
       -max_len="${MAXLEN[$t]}" -print_final_stats=1 -artifact_prefix="$BUILD/artifacts/$t-" "$work" "$seeds")
  echo "fuzz.sh: $t for ${TIME} s (seed $SEED): ${cmd[*]}"
  rc=0
  "${cmd[@]}" >"$log" 2>&1 || rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  corp=$(sed -n 's/.* corp: \([0-9]*\/[0-9a-zA-Z]*\).*/\1/p' <<<"$last")
  secs=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "$log" | tail -1)
  line="$t: ${execs:-?} executions in ${secs:-?} s (${rate:-?}/s), coverage ${cov:-?} edges, ${ft:-?} features, corpus ${corp:-?}"
  if [ $rc -ne 0 ]; then
    status=1
    art=$(grep -o "Test unit written to [^ ]*" "$log" | tail -1 | sed 's/Test unit written to //')
    echo "fuzz.sh: $t FAILED (exit $rc); log $log; last 60 lines:" >&2
    tail -60 "$log" >&2
    [ -n "$art" ] && echo "fuzz.sh: reproduce with: $BUILD/$t $art" >&2
    summary+=("$line: FAILED ${art:+(input $art)}")
  else
    summary+=("$line: no crash")
  fi
done
echo "fuzz.sh: summary ($MODE, seed $SEED):"
printf '  %s\n' "${summary[@]}"
exit $status
