#!/usr/bin/env bash
# What edge contacts cost: every validation family, full and iterative, with
# edge contacts on (the default) and off, 1,000 pairs each on Embree, the
# exact reference alone. Writes docs/results/edges/{on,off}_{full,iterative}.json
# and the table in docs/results/edges/README.md. Needs a release build.
set -euo pipefail
cd "$(dirname "$0")/.."
pairs=${1:-1000}
out=docs/results/edges
mkdir -p "$out"
for mode in full iterative; do
  ./build/release/bin/rtcd validate --backend embree --pairs "$pairs" --mode "$mode" --no-oracles --json >"$out/on_$mode.json"
  ./build/release/bin/rtcd validate --backend embree --pairs "$pairs" --mode "$mode" --no-oracles --json \
    --no-edge-contacts >"$out/off_$mode.json"
done
/usr/bin/python3 bench/edge_table.py "$out" >"$out/table.md"
echo "wrote $out"
