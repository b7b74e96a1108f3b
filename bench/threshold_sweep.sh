#!/usr/bin/env bash
# What the displacement threshold costs and buys on a recorded scene: phase
# C of `rtcd replay RECORDING` (automatic mode, Embree, one thread, every
# 25th step judged by the exact reference) at each threshold, beside full
# mode's ray time. Writes OUT/threshold_sweep.{csv,png}. Needs a release build.
#   bench/threshold_sweep.sh RECORDING [OUT]
set -euo pipefail
cd "$(dirname "$0")/.."
recording=${1:?usage: bench/threshold_sweep.sh RECORDING [OUT]}
out=${2:-docs/results/threshold-sweep}
rtcd=./build/release/bin/rtcd
mkdir -p "$out"

# The phase C row of a replay's table, cells trimmed, '|' between them.
phase_c() { "$rtcd" replay "$recording" --threads 1 "$@" | awk -F'|' '$2 ~ /^ C $/ {
  for (i = 2; i < NF; ++i) { gsub(/^ +| +$/, "", $i); printf "%s%s", $i, (i < NF - 1 ? "|" : "\n") } }'; }

full=$(phase_c --mode full)
[ -n "$full" ] || { echo "threshold_sweep: $recording has no phase C (a scene that never settles)" >&2; exit 2; }
full_rays=$(echo "$full" | awk -F'|' '{ printf "%.3f", $6 + $7 }')
csv="$out/threshold_sweep.csv"
echo "threshold,detect_ms,full_tracing_ms,walks_ms,ray_ms,full_mode_ray_ms,traced_in_full_pct,judged_steps,deep,missed,false_rays" > "$csv"
for t in 0.01 0.015 0.02 0.025 0.03 0.035 0.04 0.05; do
  row=$(phase_c --displacement-threshold "$t" --judge-every 25)
  echo "$row" | awk -F'|' -v t="$t" -v full="$full_rays" '{
    pct = $10; sub(/%/, "", pct)
    split($14, j, /[: ]+/)  # "19: 0 of 27349 deep rays missed, 0 false"
    printf "%s,%s,%s,%s,%.3f,%s,%s,%s,%s,%s,%s\n", t, $3, $6, $7, $6 + $7, full, pct, j[1], j[4], j[2], j[8] }' >> "$csv"
done
/usr/bin/python3 bench/plot_threshold.py "$csv" "$out/threshold_sweep.png"  # Debian's python3-matplotlib
echo "wrote $csv and $out/threshold_sweep.png"
