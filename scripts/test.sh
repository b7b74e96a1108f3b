#!/usr/bin/env bash
# Every test: install what is missing, build (release), run ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh --tests
# PoCL's CPU driver as two OpenCL devices: the OpenCL backend's multi-device
# paths run in every run (ctest sets the same on its tests).
export POCL_DEVICES=${POCL_DEVICES:-"pthread pthread"}
cmake --preset release >/dev/null
cmake --build --preset release
ctest --preset release -j2 "$@"
