#!/usr/bin/env bash
# What accuracy costs in time: sweeps the knobs on one family and writes
# docs/results/accuracy-sweep/<family>.{csv,png}. Needs a release build.
set -euo pipefail
cd "$(dirname "$0")/.."
family=${1:-concave}
pairs=${2:-1000}
out=docs/results/accuracy-sweep/${family}
mkdir -p docs/results/accuracy-sweep
./build/release/bin/rtcd validate --sweep --family "$family" --backend embree --pairs "$pairs" --csv "$out.csv"
/usr/bin/python3 bench/plot_sweep.py "$out.csv" "$out.png"  # Debian's python3-matplotlib
echo "wrote $out.csv and $out.png"
