#!/usr/bin/env bash
# Quartus flow for the DE1-SoC: compile constraints/fpgacnc.qpf and print the resource and timing
# summaries. Needs Quartus (13.1 or later, any edition with Cyclone V) with quartus_sh on the PATH.
set -euo pipefail
cd "$(dirname "$0")/../constraints"
if ! command -v quartus_sh >/dev/null 2>&1; then
  cat >&2 <<'MSG'
make quartus: quartus_sh is not on the PATH.
  Install Intel Quartus Prime (Lite is enough for the Cyclone V 5CSEMA5F31C6), then e.g.
    export PATH=$HOME/intelFPGA_lite/<version>/quartus/bin:$PATH
  and run `make quartus` again. Without Quartus, `make synth` gives the open-tool reports.
MSG
  exit 2
fi
quartus_sh --flow compile fpgacnc
echo "== fit summary"
cat output_files/fpgacnc.fit.summary
echo "== timing summary (50 MHz clock)"
cat output_files/fpgacnc.sta.summary
if grep -q "Slack : -" output_files/fpgacnc.sta.summary; then
  echo "quartus: negative slack: the design misses 50 MHz" >&2
  exit 1
fi
echo "bitstream: constraints/output_files/fpgacnc.sof"
