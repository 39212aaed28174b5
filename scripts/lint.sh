#!/usr/bin/env bash
# RTL lint: every file in rtl/ must be clean under
#   verilator --lint-only -Wall, iverilog -g2005, and Yosys (read, hierarchy, proc, check)
# with the file's own module as top, and cnc_core in every named configuration of
# spec/configs.toml (scripts/configs.sh) elaborated the same three ways, so an illegal entry there
# (rtl/cnc_core.v's elaboration guards) fails too; and every rtl/... .v path named in the sources,
# scripts and docs must exist. Exit non-zero on any warning or error.
set -uo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/configs.sh
source scripts/configs.sh
# shellcheck source=scripts/rtl_files.sh
source scripts/rtl_files.sh
fail=0
log=$(mktemp)
trap 'rm -f "$log"' EXIT
files=("${FPGACNC_RTL_FILES[@]}")
for f in "${files[@]}"; do
  top=$(basename "$f" .v)
  if ! verilator --lint-only -Wall "${FPGACNC_RTL_VSEARCH[@]}" --top-module "$top" "$f" >"$log" 2>&1 || [ -s "$log" ]; then
    echo "FAIL verilator: $f"; cat "$log"; fail=1
  fi
  if ! iverilog -g2005 -Wall -Wno-timescale "${FPGACNC_RTL_ISEARCH[@]}" -Y .v -s "$top" -o /dev/null "$f" >"$log" 2>&1 || [ -s "$log" ]; then
    echo "FAIL iverilog: $f"; cat "$log"; fail=1
  fi
done
# Yosys: one run elaborates every module with its default parameters (hierarchy without a top
# keeps them all) and a wrapper instantiates cnc_core once per named configuration, so each
# distinct parametrisation is processed and checked once; only when that run fails or warns is
# each top run alone, so the failure names its file or configuration.
yosys_one() {  # top, chparam arguments ("" for the default build)
  local chp=""
  [ -n "$2" ] && chp="chparam$2 $1;"
  echo "read_verilog -Irtl/include ${files[*]}; $chp hierarchy -check -top $1; proc; check -assert"
}
wrapper=$(mktemp --suffix=.v)
trap 'rm -f "$log" "$wrapper"' EXIT
declare -A ygs=()
# cnc_core's named configurations (the default build is checked above).
configs=("${FPGACNC_CONFIGS[@]}")
echo "module lint_configs;" >"$wrapper"
i=0
for name in "${configs[@]}"; do
  params=${FPGACNC_CONFIG_PARAMS[$name]}
  vg=() ig=() yg="" wp=""
  for pv in $params; do
    vg+=("-G$pv"); ig+=("-Pcnc_core.$pv"); yg="$yg -set ${pv%=*} ${pv#*=}"
    wp="$wp${wp:+, }.${pv%=*}(${pv#*=})"
  done
  if ! verilator --lint-only -Wall "${FPGACNC_RTL_VSEARCH[@]}" --top-module cnc_core "${vg[@]}" rtl/cnc_core.v >"$log" 2>&1 || [ -s "$log" ]; then
    echo "FAIL verilator: cnc_core $name ($params)"; cat "$log"; fail=1
  fi
  if ! iverilog -g2005 -Wall -Wno-timescale "${FPGACNC_RTL_ISEARCH[@]}" -Y .v -s cnc_core "${ig[@]}" -o /dev/null rtl/cnc_core.v >"$log" 2>&1 || [ -s "$log" ]; then
    echo "FAIL iverilog: cnc_core $name ($params)"; cat "$log"; fail=1
  fi
  ygs[$name]="$yg"
  echo "  cnc_core #($wp) config_$i ();" >>"$wrapper"
  i=$((i + 1))
done
echo "endmodule" >>"$wrapper"
if ! yosys -q -l "$log" -p "read_verilog -Irtl/include ${files[*]} $wrapper; hierarchy -check; proc; check -assert" >/dev/null 2>&1 \
    || grep -qi "warning" "$log"; then
  for f in "${files[@]}"; do
    if ! yosys -q -l "$log" -p "$(yosys_one "$(basename "$f" .v)" "")" >/dev/null 2>&1 \
        || grep -qi "warning" "$log"; then
      echo "FAIL yosys: $f"; grep -i -E "warning|error" "$log"; fail=1
    fi
  done
  for name in "${configs[@]}"; do
    params=${FPGACNC_CONFIG_PARAMS[$name]}
    if ! yosys -q -l "$log" -p "$(yosys_one cnc_core "${ygs[$name]}")" >/dev/null 2>&1 \
        || grep -qi "warning" "$log"; then
      echo "FAIL yosys: cnc_core $name ($params)"; grep -i -E "warning|error" "$log"; fail=1
    fi
  done
  [ $fail -ne 0 ] || { echo "FAIL yosys: the run of every module and configuration together (log below)"; cat "$log"; fail=1; }
fi
# Every RTL path the sources, scripts and docs name (rtl/<folder>/<module>.v) exists.
while read -r p; do
  [ -f "$p" ] || { echo "FAIL path: $p is named in $(grep -rlF "$p" rtl scripts docs tb systemc host models constraints spec CMakeLists.txt Makefile README.md | head -3 | tr '\n' ' ')but does not exist"; fail=1; }
done < <(grep -rhoE "\brtl/[A-Za-z0-9_/]+\.v\b" rtl scripts docs tb systemc host models constraints spec \
  CMakeLists.txt Makefile README.md | sort -u)
if [ $fail -eq 0 ]; then
  echo "lint: ${#files[@]} files clean (verilator -Wall, iverilog -g2005, yosys check), and cnc_core in its ${#configs[@]} named configurations (spec/configs.toml)"
fi
exit $fail
