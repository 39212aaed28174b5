#!/usr/bin/env bash
# RTL lint: every file in rtl/ must be clean under
#   verilator --lint-only -Wall, iverilog -g2005, and Yosys (read, hierarchy, proc, check)
# with the file's own module as top. Exit non-zero on any warning or error.
set -uo pipefail
cd "$(dirname "$0")/.."
fail=0
log=$(mktemp)
trap 'rm -f "$log"' EXIT
files=(rtl/*.v)
for f in "${files[@]}"; do
  top=$(basename "$f" .v)
  if ! verilator --lint-only -Wall -Irtl --top-module "$top" "$f" >"$log" 2>&1 || [ -s "$log" ]; then
    echo "FAIL verilator: $f"; cat "$log"; fail=1
  fi
  if ! iverilog -g2005 -Wall -Wno-timescale -y rtl -Y .v -s "$top" -o /dev/null "$f" >"$log" 2>&1 || [ -s "$log" ]; then
    echo "FAIL iverilog: $f"; cat "$log"; fail=1
  fi
  if ! yosys -q -l "$log" -p "read_verilog ${files[*]}; hierarchy -check -top $top; proc; check -assert" >/dev/null 2>&1 \
      || grep -qi "warning" "$log"; then
    echo "FAIL yosys: $f"; grep -i -E "warning|error" "$log"; fail=1
  fi
done
if [ $fail -eq 0 ]; then
  echo "lint: ${#files[@]} files clean (verilator -Wall, iverilog -g2005, yosys check)"
fi
exit $fail
