#!/usr/bin/env bash
# cnc_core's elaboration guards (rtl/cnc_core.v "build option guards"): every illegal combination
# of build options below must fail to elaborate in Verilator (--lint-only) and Icarus (-g2005),
# naming the missing module cnc_core_illegal_<rule> that says what is wrong; one of them in Yosys
# too. A parameter cnc_core passes on unchecked is guarded by the block that takes it
# (<block>_illegal_<rule>): three of those too. A few legal combinations (the defaults,
# PROTO_V2 = 0 alone, which relies on the options' defaults following PROTO_V2, and ARCS without
# PROFILES) must elaborate without that error.
# Every named configuration of spec/configs.toml is elaborated by scripts/lint.sh. Exits non-zero
# when any case does not behave (each is reported). CTest lint_config_guards (label lint).
set -uo pipefail
cd "$(dirname "$0")/.." || exit 2
# shellcheck source=scripts/rtl_files.sh
source scripts/rtl_files.sh
log=$(mktemp)
trap 'rm -f "$log"' EXIT
fail=0
checked=0

# elaborate TOOL "P=V ..." -> exit status of the tool, its output in $log
elaborate() {
  local tool=$1 params=$2 args=() pv
  case $tool in
    verilator)
      for pv in $params; do args+=("-G$pv"); done
      verilator --lint-only -Wall "${FPGACNC_RTL_VSEARCH[@]}" --top-module cnc_core "${args[@]}" \
        rtl/cnc_core.v >"$log" 2>&1 ;;
    iverilog)
      for pv in $params; do args+=("-Pcnc_core.$pv"); done
      iverilog -g2005 -Wall -Wno-timescale "${FPGACNC_RTL_ISEARCH[@]}" -Y .v -s cnc_core "${args[@]}" \
        -o /dev/null rtl/cnc_core.v >"$log" 2>&1 ;;
    yosys)
      local chp=""
      for pv in $params; do chp="$chp -set ${pv%=*} ${pv#*=}"; done
      yosys -q -p "read_verilog -Irtl/include ${FPGACNC_RTL_FILES[*]}; ${chp:+chparam$chp cnc_core;} hierarchy -check -top cnc_core" \
        >"$log" 2>&1 ;;
  esac
}

# illegal TOOLS "P=V ..." RULE [BLOCK]: every tool fails and names BLOCK_illegal_RULE (BLOCK
# cnc_core by default)
illegal() {
  local tool guard=${4:-cnc_core}_illegal_$3
  for tool in $1; do
    checked=$((checked + 1))
    if elaborate "$tool" "$2"; then
      echo "FAIL $tool: cnc_core ($2) elaborated; expected $guard"; fail=1
    elif ! grep -q "$guard\\b" "$log"; then
      echo "FAIL $tool: cnc_core ($2) failed without naming $guard:"; cat "$log"; fail=1
    fi
  done
}

# legal TOOLS "P=V ...": every tool elaborates, no guard fires
legal() {
  local tool
  for tool in $1; do
    checked=$((checked + 1))
    if ! elaborate "$tool" "$2" || grep -q "cnc_core_illegal_" "$log"; then
      echo "FAIL $tool: cnc_core ($2) did not elaborate:"; cat "$log"; fail=1
    fi
  done
}

both="verilator iverilog"
illegal "$both" "PROTO_V2=2" PROTO_V2_not_0_or_1
illegal "$both" "PROFILES=2" PROFILES_not_0_or_1
illegal "$both" "ARCS=3" ARCS_not_0_or_1
illegal "$both" "HEATERS=2" HEATERS_not_0_or_1
illegal "$both" "OUTPUTS=2" OUTPUTS_not_0_or_1
illegal "$both" "PROTO_V2=0 LEAN_TRIM=2" LEAN_TRIM_not_0_or_1
illegal "$both" "STEP_CFG=2" STEP_CFG_not_0_or_1
illegal "$both" "N_AXES=1" N_AXES_not_2_to_15
illegal "$both" "N_AXES=16" N_AXES_not_2_to_15
illegal "$both yosys" "PROTO_V2=0 PROFILES=1" PROFILES_needs_PROTO_V2_1
illegal "$both" "PROTO_V2=0 ARCS=1" ARCS_needs_PROTO_V2_1
illegal "$both" "PROTO_V2=0 HEATERS=1" HEATERS_needs_PROTO_V2_1
illegal "$both" "PROTO_V2=0 OUTPUTS=1" OUTPUTS_needs_PROTO_V2_1
illegal "$both" "LEAN_TRIM=1" LEAN_TRIM_needs_PROTO_V2_0
illegal "$both" "N_AXES=2 STEP_CFG=0" STEP_CFG_0_needs_PROTO_V2_0
illegal "$both" "LIMIT_FILTER_CLKS=16777216" LIMIT_FILTER_CLKS_not_0_to_2p24m1
illegal "$both" "TRIGGER=2" TRIGGER_not_0_or_1
illegal "$both" "PROTO_V2=0 TRIGGER=1" TRIGGER_needs_PROTO_V2_1
illegal "$both" "PROBE_ENABLE=2" PROBE_ENABLE_not_0_or_1
illegal "$both" "PROBE_ACTIVE_LOW=2" PROBE_ACTIVE_LOW_not_0_or_1
illegal "$both" "PROBE_FILTER_CLKS=16777216" PROBE_FILTER_CLKS_not_0_to_2p24m1
illegal "$both" "FIFO_DEPTH=48" FIFO_DEPTH_not_power_of_2_in_2_to_32768 front_v2
illegal "$both" "STEP_HIGH=65536" timing_not_0_to_65535 step_config
illegal "$both" "FAN_PWM_HZ=0" FAN_PWM_HZ_out_of_range machine_outputs
illegal "$both" "LASER_PWM_HZ=300000" LASER_PWM_HZ_out_of_range machine_outputs

legal "$both" ""
legal "$both yosys" "PROTO_V2=0"
legal "$both" "N_AXES=2 PROTO_V2=0 LEAN_TRIM=0 STEP_CFG=0"
legal "$both" "N_AXES=3 PROFILES=0 ARCS=1 HEATERS=0 OUTPUTS=0"
legal "$both" "N_AXES=3 LIMIT_FILTER_CLKS=0 LIMIT_ENABLE=458759 LIMIT_ACTIVE_LOW=65537"
legal "$both" "FIFO_DEPTH=2 STEP_HIGH=65535"
legal "$both" "TRIGGER=0 PROBE_ENABLE=1"
legal "$both" "N_AXES=3 PROBE_ENABLE=1 PROBE_ACTIVE_LOW=1 PROBE_FILTER_CLKS=0"

if [ $fail -eq 0 ]; then
  echo "config_guards: $checked elaborations as expected (24 illegal combinations refused by name, 8 legal ones accepted)"
fi
exit $fail
