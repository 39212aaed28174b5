#!/usr/bin/env bash
# Installs the Debian packages fpgacnc needs to build, test and demo.
# Run as root (or through sudo). Safe to run again: apt-get skips what is present.
set -euo pipefail
PKGS=(
  build-essential cmake ninja-build pkg-config make git clang-format
  clang libclang-rt-14-dev
  verilator zlib1g-dev
  libsystemc-dev
  libgtest-dev googletest
  yosys iverilog nextpnr-ice40 z3
  libserialport-dev libcli11-dev libfmt-dev libtoml11-dev
  python3 python3-serial librsvg2-bin time
  linuxcnc-uspace  # rs274, LinuxCNC's interpreter: the oracle test (docs/oracle.md)
)
# node and npm run CNCjs for the cncjs_stream test (host/test/cncjs). Debian's packages only where
# the commands are missing: a Node.js from elsewhere (NodeSource's nodejs bundles npm) is kept.
command -v node >/dev/null 2>&1 || PKGS+=(nodejs)
command -v npm >/dev/null 2>&1 || PKGS+=(npm)
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "install-deps: need root (or sudo) to install: ${PKGS[*]}" >&2; exit 1
  fi
fi
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  : # all packages present
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
