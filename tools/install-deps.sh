#!/usr/bin/env bash
# Installs topotrack's build dependencies from Debian 12 packages. Needs root (or sudo).
set -euo pipefail
PKGS=(cmake g++ make pkg-config libeigen3-dev libtbb-dev libopenvdb-dev libboost-iostreams-dev libembree-dev
      libnanoflann-dev libbenchmark-dev libgtest-dev libcli11-dev nlohmann-json3-dev libfast-float-dev
      libpng-dev libsuitesparse-dev)
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
