#!/usr/bin/env bash
# Shared by scripts/demo and scripts/test: install missing Debian packages, configure and build.
# Usage (sourced): rs_setup [extra cmake args...]; sets RS_BUILD_DIR.
set -euo pipefail

RS_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
RS_PACKAGES=(build-essential cmake pkg-config libglm-dev libopenimageio-dev libtbb-dev
             libbenchmark-dev libgtest-dev libgmock-dev nlohmann-json3-dev libcli11-dev fonts-dejavu-core
             libegl1 libegl-mesa0 libgl1-mesa-dri libegl-dev libgl-dev libopengl-dev openimageio-tools
             python3-matplotlib)

rs_install() {
    local missing=()
    for p in "${RS_PACKAGES[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if ((${#missing[@]})); then
        echo "reliefsim: installing ${missing[*]}"
        local sudo=""
        [ "$(id -u)" -ne 0 ] && sudo="sudo"
        $sudo apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
    fi
}

rs_build() {
    local build_dir="$1"; shift
    cmake -S "$RS_ROOT" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
    cmake --build "$build_dir" -j "$(nproc)"
}
