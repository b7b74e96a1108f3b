#!/usr/bin/env bash
# The zoo (data/scenes/zoo.json: knot tubes, gears, cacti, coarse polyhedra,
# rings, blobs, spheres and boxes dropped in a pile), hosted by rtcd and by
# Bullet's GIMPACT, each measured by the same interpenetration pass; the true
# penetration over time plotted side by side, and the floors judged.
#   bash bench/zoo.sh [OUT]        (default docs/results/zoo)
# Extra arguments after OUT go to both runs (--steps N, --threads N).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/results/zoo}
shift || true
bin=build/release/bin/rtcd
mkdir -p "$out"
for host in rtcd gimpact; do
  backend=()
  [ "$host" = gimpact ] && backend=(--backend gimpact)
  mkdir -p "$out/$host"
  "$bin" run data/scenes/zoo.json "${backend[@]}" --no-plots --out "$out/$host" "$@" | grep -v '^steps ' | tee "$out/$host/console.txt"
  rm -f "$out/$host"/snapshot_*.png
done
/usr/bin/python3 bench/plot_zoo.py "$out"
