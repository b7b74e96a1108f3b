#!/usr/bin/env bash
# What the contacts measured to the nearest surface buy and cost: every
# validation family in full mode, judged against the true penetration, with
# Config::nearest_surface on (the default) and off (the thesis' ray
# contacts); over-reports and time per pair plotted per family.
#   bash bench/truth.sh [PAIRS] [OUT]     (defaults 300, docs/results/truth)
set -euo pipefail
cd "$(dirname "$0")/.."
pairs=${1:-300}
out=${2:-docs/results/truth}
bin=build/release/bin/rtcd
mkdir -p "$out"
"$bin" validate --backend embree --pairs "$pairs" --no-oracles --json > "$out/on.json"
"$bin" validate --backend embree --pairs "$pairs" --no-oracles --no-nearest-surface --json > "$out/off.json"
/usr/bin/python3 bench/plot_truth.py "$out"
