#!/usr/bin/env bash
# Installs topotrack's build dependencies from Debian 12 packages. Needs root (or sudo).
#   bash tools/install-deps.sh          what the build and the tests need
#   bash tools/install-deps.sh --fuzz   also clang-14 with libFuzzer (tools/fuzz.sh)
set -euo pipefail
PKGS=(cmake g++ make pkg-config libeigen3-dev libtbb-dev libopenvdb-dev libboost-iostreams-dev libembree-dev
      libnanoflann-dev libbenchmark-dev libgtest-dev libcli11-dev nlohmann-json3-dev libfast-float-dev
      libpng-dev libsuitesparse-dev)
if [[ "${1:-}" == --fuzz ]]; then PKGS+=(clang-14 libclang-rt-14-dev); fi
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PKGS[@]} packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
