#!/usr/bin/python3
"""The zoo hosted by rtcd and by GIMPACT (bench/zoo.sh): true penetration
over time, side by side (zoo.png), and the floors judged from 1.5 s on
(zoo.json, printed): at every measured step rtcd's deepest true penetration
within 1.5x GIMPACT's + 2 mm and its summed within 2x + 0.05; no pair held
deeper than 2% of its smaller body's size for more than 30 steps.

    /usr/bin/python3 bench/plot_zoo.py FOLDER
"""
from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SETTLED = 1.5  # seconds: after the first impacts


def measured(folder: Path) -> list[dict[str, float]]:
    with open(folder / "steps.csv", newline="") as f:
        return [{k: float(v) for k, v in row.items() if v != ""} for row in csv.DictReader(f)
                if row["true_penetration"] != ""]


def main(folder: Path) -> None:
    runs = {host: measured(folder / host) for host in ("rtcd", "gimpact")}
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    for host, rows in runs.items():
        t = [r["time"] for r in rows]
        axes[0].plot(t, [r["true_penetration"] for r in rows], label=f"{host}-hosted")
        axes[1].plot(t, [1000 * r["deepest_true"] for r in rows], label=f"{host}-hosted")
    for ax, title, unit in ((axes[0], "summed true penetration", "m"), (axes[1], "deepest true penetration", "mm")):
        ax.axvline(SETTLED, color="grey", lw=0.8, ls=":")
        ax.set_xlabel("time (s)")
        ax.set_ylabel(unit)
        ax.set_title(f"zoo: {title}")
        ax.legend()
    fig.tight_layout()
    fig.savefig(folder / "zoo.png", dpi=110)

    ours = {r["step"]: r for r in runs["rtcd"] if r["time"] >= SETTLED}
    peers = {r["step"]: r for r in runs["gimpact"] if r["time"] >= SETTLED}
    steps = sorted(set(ours) & set(peers))
    deepest_over = [s for s in steps if ours[s]["deepest_true"] > 1.5 * peers[s]["deepest_true"] + 0.002]
    summed_over = [s for s in steps if ours[s]["true_penetration"] > 2 * peers[s]["true_penetration"] + 0.05]
    report = {
        "steps_judged": len(steps),
        "from_time": SETTLED,
        "deepest_true": {"rtcd_max": max(ours[s]["deepest_true"] for s in steps),
                         "gimpact_max": max(peers[s]["deepest_true"] for s in steps),
                         "steps_over_floor": len(deepest_over), "first_over": deepest_over[:5]},
        "summed_true": {"rtcd_max": max(ours[s]["true_penetration"] for s in steps),
                        "gimpact_max": max(peers[s]["true_penetration"] for s in steps),
                        "steps_over_floor": len(summed_over), "first_over": summed_over[:5]},
        "longest_deep_run_steps": {host: max(r["longest_deep_run"] for r in rows) for host, rows in runs.items()},
        "final": {host: {"true_penetration": rows[-1]["true_penetration"], "deepest_true": rows[-1]["deepest_true"]}
                  for host, rows in runs.items()},
    }
    report["floors_hold"] = (not deepest_over and not summed_over
                             and report["longest_deep_run_steps"]["rtcd"] <= 30)
    (folder / "zoo.json").write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
