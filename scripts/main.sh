#!/usr/bin/env bash
# The main job: install what is missing, build (release), and run the default
# scene (512 concave meshes falling on a plane, 5 s at 60 Hz) with `rtcd run`:
# steps.csv, summary.json, plots and snapshots land in runs/default-<time>/.
# Arguments go to `rtcd run` (a scene file, --backend, --steps, --out ...).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake --preset release >/dev/null
cmake --build --preset release
./build/release/bin/rtcd run "$@"
