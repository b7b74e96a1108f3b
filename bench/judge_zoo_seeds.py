#!/usr/bin/python3
"""The pile's floors per zoo run (bench/zoo_seeds.sh): from 1.5 s on, the
deepest body in the ground over its size (floor: 1%), the longest a pair
stays deeper than 2% of its smaller body (floor: 30 steps), and the deepest
true penetration; written to OUT/seeds.csv and printed as a table.

  judge_zoo_seeds.py OUT
"""

import csv
import glob
import os
import re
import sys

FROM = 1.5
out = sys.argv[1]
rows = []
for steps in sorted(glob.glob(os.path.join(out, "seed*", "*", "steps.csv"))):
    host = os.path.basename(os.path.dirname(steps))
    seed = int(re.search(r"seed(\d+)", steps).group(1))
    late = [r for r in csv.DictReader(open(steps)) if float(r["time"]) >= FROM - 1e-9 and r["true_penetration"] != ""]
    if not late:
        sys.exit(f"{steps}: no measured step from {FROM} s")
    ground = max(float(r["ground_depth_fraction"]) for r in late)
    longest = max(int(float(r["longest_deep_run"])) for r in late)
    deepest = max(float(r["deepest_true"]) for r in late)
    rows.append({"seed": seed, "host": host, "ground_depth_fraction_max": f"{ground:.4f}",
                 "longest_deep_run_steps": longest, "deepest_true_mm": f"{1000 * deepest:.1f}",
                 "ground_holds": int(ground <= 0.01), "pairs_hold": int(longest <= 30)})
with open(os.path.join(out, "seeds.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0]))
    w.writeheader()
    w.writerows(rows)
print(f"| seed | host | deepest in the ground ÷ size (≤ 1%) | longest deep pair, steps (≤ 30) | deepest true, mm |")
print("| --: | :-- | --: | --: | --: |")
for r in rows:
    print(f"| {r['seed']} | {r['host']} | {100 * float(r['ground_depth_fraction_max']):.2f}% | "
          f"{r['longest_deep_run_steps']} | {r['deepest_true_mm']} |")
