#!/usr/bin/env bash
# The zoo (data/scenes/zoo.json) with its seed set to 1..5, hosted by rtcd
# and by Bullet's GIMPACT; bench/judge_zoo_seeds.py judges the pile's floors
# per run into OUT/seeds.csv.
#   bash bench/zoo_seeds.sh [OUT] [SCENE]   (default docs/results/zoo/seeds, data/scenes/zoo.json)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/results/zoo/seeds}
scene=${2:-data/scenes/zoo.json}
bin=build/release/bin/rtcd
mkdir -p "$out"
for seed in 1 2 3 4 5; do
  # The scene with its seed set, its mesh paths made absolute so it runs from anywhere.
  /usr/bin/python3 - "$scene" "$seed" > "$out/zoo_seed$seed.json" <<'PY'
import json, os, sys
path, seed = sys.argv[1], int(sys.argv[2])
scene = json.load(open(path))
scene["seed"] = seed
scene["name"] = f"{scene.get('name', 'zoo')}_seed{seed}"
for body in scene["bodies"]:
    if "mesh" in body:
        body["mesh"] = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(path)), body["mesh"]))
json.dump(scene, sys.stdout, indent=1)
PY
  for host in rtcd gimpact; do
    backend=()
    [ "$host" = gimpact ] && backend=(--backend gimpact)
    mkdir -p "$out/seed$seed/$host"
    "$bin" run "$out/zoo_seed$seed.json" "${backend[@]}" --no-plots --out "$out/seed$seed/$host" \
      > "$out/seed$seed/$host/console.txt" 2>&1 || { tail -3 "$out/seed$seed/$host/console.txt"; exit 1; }
    rm -f "$out/seed$seed/$host"/snapshot_*.png
  done
done
/usr/bin/python3 bench/judge_zoo_seeds.py "$out"
