#!/usr/bin/python3
"""Piles of one shape: whether bodies dropped onto each other come apart.

Each kind of body in data/scenes/zoo.json, twelve of it dropped from a
2 x 2 x 3 grid (0.6 m apart) for 2 s, and columns of two knot tubes (eight
columns, each upper knot dropped 0.6 m onto the lower), over several seeds,
hosted by rtcd and by Bullet's GIMPACT. A run holds a pair when, from 1 s
on, some pair stays deeper than 2% of its smaller body's size for more than
30 steps (the zoo's floor). Writes piles.csv (one row per run), piles.md
(per pile and host: runs holding a pair, summed true penetration at the
end) into OUT; the scenes and runs go to a temporary folder.

    /usr/bin/python3 bench/piles.py OUT [--seeds N] [--jobs J] [--hosts rtcd,gimpact] [--piles P,Q] [--rtcd BINARY]
"""
from __future__ import annotations

import argparse
import copy
import csv
import json
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RTCD = ROOT / "build/release/bin/rtcd"
SETTLED = 1.0  # seconds: after the drops
HELD = 30      # steps


def scenes(zoo: dict) -> dict[str, dict]:
    """One pile per kind of the zoo, and the knot columns; mesh paths made absolute."""
    base = {k: v for k, v in zoo.items() if k != "bodies"}
    base["duration"] = 2.0
    out = {}
    for body in zoo["bodies"]:
        b = copy.deepcopy(body)
        if "mesh" in b:
            b["mesh"] = str((ROOT / "data/scenes" / b["mesh"]).resolve())
        b["count"] = 12
        b["grid"].update(cells=[2, 2, 3], origin=[-0.3, -0.3, 0.5])
        out[body["name"]] = dict(base, name=f"pile of {body['name']}", bodies=[b])
        if body["name"] == "knot":
            c = copy.deepcopy(b)
            c["count"] = 16
            c["grid"].update(cells=[4, 2, 2], origin=[-1.5, -0.5, 0.3], spacing=[1.0, 1.0, 0.6])
            out["knot columns"] = dict(base, name="columns of two knots", bodies=[c])
    return out


def run(binary: Path, scene: Path, host: str, out: Path) -> dict:
    command = [str(binary), "run", str(scene), "--no-plots", "--out", str(out)]
    if host == "gimpact":
        command += ["--backend", "gimpact"]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    with open(out / "steps.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["true_penetration"] != ""]
    late = [r for r in rows if float(r["time"]) >= SETTLED]
    longest = max(int(float(r["longest_deep_run"])) for r in late)
    return {"longest_deep_run": longest, "holds_a_pair": int(longest > HELD),
            "true_penetration_end": float(rows[-1]["true_penetration"]),
            "deepest_true_end": float(rows[-1]["deepest_true"])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--hosts", default="rtcd,gimpact")
    parser.add_argument("--piles", help="only these piles, comma-separated (knot,knot columns,gear,...)")
    parser.add_argument("--rtcd", type=Path, default=RTCD, help="the rtcd binary (another build, to compare)")
    args = parser.parse_args()
    hosts = args.hosts.split(",")
    zoo = json.loads((ROOT / "data/scenes/zoo.json").read_text())
    args.out.mkdir(parents=True, exist_ok=True)
    temporary = tempfile.TemporaryDirectory(prefix="rtcd_piles_")
    runs = Path(temporary.name)
    work = []
    for name, scene in scenes(zoo).items():
        if args.piles and name not in args.piles.split(","):
            continue
        for seed in range(1, args.seeds + 1):
            path = runs / f"{name.replace(' ', '_')}_{seed}.json"
            path.write_text(json.dumps(dict(scene, seed=seed), indent=1) + "\n")
            work += [(name, seed, host, path) for host in hosts]

    def one(item):
        name, seed, host, path = item
        return {"pile": name, "seed": seed, "host": host, **run(args.rtcd, path, host, runs / f"{path.stem}_{host}")}

    with ThreadPoolExecutor(args.jobs) as pool:
        rows = list(pool.map(one, work))
    with open(args.out / "piles.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = ["| pile | " + " | ".join(f"{h}: runs holding a pair | {h}: summed true penetration at the end"
                                          for h in hosts) + " |",
             "| :-- |" + " --: | --: |" * len(hosts)]
    for name in dict.fromkeys(r["pile"] for r in rows):
        cells = []
        for h in hosts:
            mine = [r for r in rows if r["pile"] == name and r["host"] == h]
            cells += [f"{sum(r['holds_a_pair'] for r in mine)} of {len(mine)}",
                      f"{sum(r['true_penetration_end'] for r in mine):.3f}"]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    (args.out / "piles.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
