# shellcheck shell=bash disable=SC2034
# The RTL's files and folders (rtl/cnc_core.v and rtl/<part>/*.v; rtl/include holds headers),
# sourced by scripts/lint.sh and config_guards.sh from the repository root:
#   FPGACNC_RTL_FILES    every module file
#   FPGACNC_RTL_VSEARCH  Verilator's module search path (-I per folder)
#   FPGACNC_RTL_ISEARCH  Icarus' library folders (-y per folder)
FPGACNC_RTL_FILES=(rtl/*.v rtl/*/*.v)
FPGACNC_RTL_VSEARCH=(-Irtl/include)
FPGACNC_RTL_ISEARCH=(-I rtl/include)
for _d in rtl rtl/*/; do
  _d=${_d%/}
  [ "$_d" = rtl/include ] && continue
  FPGACNC_RTL_VSEARCH+=("-I$_d")
  FPGACNC_RTL_ISEARCH+=(-y "$_d")
done
unset _d
