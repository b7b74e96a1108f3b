#!/usr/bin/env bash
# Installs the Debian 12 packages rtcd, its oracles and its plots need, only
# when some are missing; with --tests, what the tests need besides (Chromium).
set -euo pipefail
packages=(
  cmake ninja-build g++ clang libclang-rt-14-dev pkg-config
  libeigen3-dev libtbb-dev libembree-dev libassimp-dev libtinyobjloader-dev libjs-three libb64-dev
  libcli11-dev nlohmann-json3-dev pybind11-dev python3-dev python3-numpy python3-pytest python3-hypothesis
  libgtest-dev libbenchmark-dev
  libfcl-dev libccd-dev libbullet-dev libstb-dev python3-matplotlib
  pocl-opencl-icd opencl-clhpp-headers opencl-c-headers ocl-icd-opencl-dev clinfo
  libopenmpi-dev openmpi-bin
)
# The tests also drive the page `rtcd view` writes in a headless browser.
[ "${1:-}" = "--tests" ] && packages+=(chromium python3-pil)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
