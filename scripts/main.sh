#!/usr/bin/env bash
# The main job: install what is missing, build (release), and query two
# committed concave meshes in contact, printing the contact table.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake --preset release >/dev/null
cmake --build --preset release
./build/release/bin/rtcd query data/meshes/blob_902.obj data/meshes/stream_2130.obj \
  --pose-b "1.2 0.1 0 1 0 0 0" "$@"
