#!/usr/bin/env bash
# Installs the Debian packages kiln needs (only those missing), then configures and builds kiln.
# Usage: scripts/setup.sh [build-dir]   (default: build). Safe to run again: it does only what is missing.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-"$here/build"}

packages=(g++ cmake make git ca-certificates pkg-config
          libeigen3-dev libtomlplusplus-dev libcli11-dev libfmt-dev libvtk9-dev
          libgtest-dev libbenchmark-dev libccd-dev libfcl-dev libsuitesparse-dev libcgal-dev python3 python3-numpy python3-matplotlib)

missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done
if ((${#missing[@]})); then
    echo "kiln setup: installing ${missing[*]}" >&2
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        command -v sudo >/dev/null || { echo "kiln setup: need root or sudo to install packages" >&2; exit 1; }
        sudo="sudo"
    fi
    $sudo apt-get update -q
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

jobs=$(nproc 2>/dev/null || echo 2)
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$jobs"
