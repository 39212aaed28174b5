#!/usr/bin/env bash
# Checks the Quartus project against the RTL: constraints/fpgacnc.qsf must list exactly the RTL
# files of de1soc_top's hierarchy, and every top-level port of de1soc_top must have a pin location
# and an I/O standard in constraints/de1soc_pins.tcl (all bits of a bus). Names what is wrong and
# exits non-zero otherwise. Run by CTest (check_qsf) and `make synth`.
set -uo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/rtl_files.sh
source scripts/rtl_files.sh
t=$(mktemp)
trap 'rm -f "$t"' EXIT
if ! yosys -q -p "read_verilog -Irtl/include ${FPGACNC_RTL_FILES[*]}; hierarchy -top de1soc_top; tee -q -o $t ls; \
    tee -q -a $t select -list de1soc_top/i:* de1soc_top/o:*" >/dev/null 2>&1; then
  echo "check_qsf: yosys could not elaborate de1soc_top from ${FPGACNC_RTL_FILES[*]}"; exit 2
fi
fail=0
# Module names: plain, $paramod\NAME\PARAMS or $paramod$HASH\NAME.
# Each module's file: the one of FPGACNC_RTL_FILES named after it (one module per file).
used=$(awk '/modules:/{m=1; next} m && NF==1 && $1 !~ /\// {n=$1; if (n ~ /^\$paramod/) {sub(/^\$paramod(\$[0-9a-f]+)?\\/, "", n); sub(/\\.*/, "", n)}; print n}' "$t" |
  sort -u | while read -r m; do
    f=$(printf '%s\n' "${FPGACNC_RTL_FILES[@]}" | grep -E "(^|/)$m\.v$")
    echo "${f:-rtl/.../$m.v (no file named after the module)}"
  done | sort -u)
listed=$(sed -n 's#^set_global_assignment -name VERILOG_FILE \.\./\(rtl/\([A-Za-z0-9_]*/\)\{0,1\}[A-Za-z0-9_]*\.v\).*#\1#p' \
  constraints/fpgacnc.qsf | sort -u)
missing=$(comm -23 <(echo "$used") <(echo "$listed"))
extra=$(comm -13 <(echo "$used") <(echo "$listed"))
[ -z "$missing" ] || { echo "check_qsf: used by de1soc_top but not in constraints/fpgacnc.qsf:"; echo "$missing"; fail=1; }
[ -z "$extra" ] || { echo "check_qsf: in constraints/fpgacnc.qsf but not used by de1soc_top:"; echo "$extra"; fail=1; }
nports=0
for p in $(sed -n 's#^de1soc_top/##p' "$t"); do
  nports=$((nports + 1))
  # Bus ports: every bit; scalar ports: the name itself. Width from the declaration in de1soc_top.v.
  decl=$(grep -E "^\s*(input|output)\s+(wire|reg)?\s*(\[[0-9]+:0\])?\s*([A-Za-z0-9_]+\s*,\s*)*$p\b" rtl/board/de1soc_top.v | head -1)
  msb=$(echo "$decl" | sed -n 's/.*\[\([0-9]*\):0\].*/\1/p')
  if [ -n "$msb" ]; then names=$(seq 0 "$msb" | sed "s/.*/$p[&]/"); else names=$p; fi
  for n in $names; do
    re=$(printf '%s' "$n" | sed 's/[][]/\\&/g')
    grep -qE "^set_location_assignment PIN_[A-Z0-9]+ -to \{?$re\}?\s*$" constraints/de1soc_pins.tcl ||
      { echo "check_qsf: $n has no pin (set_location_assignment) in constraints/de1soc_pins.tcl"; fail=1; }
    grep -qE "^set_instance_assignment -name IO_STANDARD \"3.3-V LVTTL\" -to \{?($re|$p\[\*\])\}?\s*$" constraints/de1soc_pins.tcl ||
      { echo "check_qsf: $n has no IO_STANDARD in constraints/de1soc_pins.tcl"; fail=1; }
  done
done
[ $fail -eq 0 ] && echo "check_qsf: fpgacnc.qsf lists the $(echo "$used" | wc -l) RTL files of de1soc_top; all $nports top ports have pins and 3.3-V LVTTL"
exit $fail
