#!/usr/bin/env bash
# A validation campaign on one rank and on two (mpirun): pairs per second
# of each, and the two reports compared field by field (they must be equal
# but for the seconds).
#   bash bench/campaign.sh [PAIRS] [OUT]     (defaults 20000, docs/results/campaign)
set -euo pipefail
cd "$(dirname "$0")/.."
pairs=${1:-20000}
out=${2:-docs/results/campaign}
bin=$PWD/build/release/bin/rtcd
args=(validate --family concave --backend embree --mode full --pairs "$pairs" --shard-pairs 500)
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
for ranks in 1 2; do
  date +%s.%N > "$scratch/start-$ranks"
  mpirun -n "$ranks" "$bin" "${args[@]}" --campaign "$scratch/ranks-$ranks" > "$out/ranks-$ranks.txt"
  date +%s.%N > "$scratch/end-$ranks"
  cp "$scratch/ranks-$ranks/report.json" "$out/report-$ranks.json"
done
/usr/bin/python3 - "$out" "$pairs" "$scratch" <<'PY'
import json, sys
out, pairs, scratch = sys.argv[1], int(sys.argv[2]), sys.argv[3]
reports = {}
for r in (1, 2):
    runs = json.load(open(f"{out}/report-{r}.json"))["runs"]
    for run in runs:
        run.pop("seconds_per_pair")
    reports[r] = runs
seconds = {r: float(open(f"{scratch}/end-{r}").read()) - float(open(f"{scratch}/start-{r}").read()) for r in (1, 2)}
result = {"pairs": pairs, "seconds": seconds, "pairs_per_second": {r: pairs / s for r, s in seconds.items()},
          "reports_equal": reports[1] == reports[2]}
json.dump(result, open(f"{out}/times.json", "w"), indent=2)
print(json.dumps(result, indent=2))
sys.exit(0 if result["reports_equal"] else 1)
PY
