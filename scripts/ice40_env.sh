# Shared set-up of scripts/ice40_timing.sh and scripts/ice40_blocks.sh (sourced with the script's
# arguments): strict mode, the repository root as working folder, out (OUT_DIR, absolute, created),
# freq (FREQ, MHz, default 50) and seed (SEED, nextpnr placement seed, default 1).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
out=${1:-build/synth}
mkdir -p "$out"
out=$(cd "$out" && pwd)
freq=${FREQ:-50}
seed=${SEED:-1}
