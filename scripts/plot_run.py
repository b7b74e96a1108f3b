#!/usr/bin/python3
"""Plots of one `rtcd run` folder: time per step by stage, pairs and rays per
step, and interpenetration over time when it was measured. Debian's
python3-matplotlib; usage: plot_run.py RUN_DIR"""
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main(folder: Path) -> None:
    with open(folder / "steps.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return
    step = [int(r["step"]) for r in rows]

    def col(name):
        return [float(r[name]) * 1e3 for r in rows]

    fig, ax = plt.subplots(figsize=(8, 4.5))
    stages = [("seconds_broad", "broad phase"), ("seconds_narrow", "narrow phase"),
              ("seconds_solver", "solver"), ("seconds_effects", "other effects")]
    ax.stackplot(step, *[col(k) for k, _ in stages], labels=[n for _, n in stages])
    ax.set_xlabel("step")
    ax.set_ylabel("time per step (ms)")
    ax.set_title(f"{folder.name}: time per step by stage")
    ax.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(folder / "time_per_step.png", dpi=110)
    plt.close(fig)

    fig, ax1 = plt.subplots(figsize=(8, 4.5))
    ax1.plot(step, [int(r["pairs"]) for r in rows], label="pairs", color="black")
    ax1.plot(step, [int(r["pairs_iterative"]) for r in rows], label="pairs iterative", color="grey")
    ax1.set_xlabel("step")
    ax1.set_ylabel("pairs")
    ax2 = ax1.twinx()
    for key, colour in (("rays_full", "tab:blue"), ("rays_predictive", "tab:orange"), ("rays_iterative", "tab:green")):
        ax2.plot(step, [int(r[key]) for r in rows], label=key.replace("_", " "), color=colour, alpha=0.8)
    ax2.plot(step, [int(r["contacts"]) for r in rows], label="contacts", color="tab:red", alpha=0.8)
    ax2.set_ylabel("rays, contacts")
    lines = ax1.get_legend_handles_labels()
    more = ax2.get_legend_handles_labels()
    ax1.legend(lines[0] + more[0], lines[1] + more[1], loc="upper left", fontsize=8)
    ax1.set_title(f"{folder.name}: pairs and rays per step")
    fig.tight_layout()
    fig.savefig(folder / "pairs_and_rays.png", dpi=110)
    plt.close(fig)

    measured = [r for r in rows if r["interpenetration"] != ""]
    if measured:
        fig, ax = plt.subplots(figsize=(8, 4.5))
        t = [float(r["time"]) for r in measured]
        ax.plot(t, [float(r["interpenetration"]) for r in measured], marker="o", label="summed ray depth")
        ax.plot(t, [float(r["projected_interpenetration"]) for r in measured], marker="^",
                label="summed projected depth")
        ax.plot(t, [float(r["deepest"]) for r in measured], marker="s", label="deepest (projected)")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("length (m)")
        ax.set_title(f"{folder.name}: interpenetration")
        ax.legend()
        fig.tight_layout()
        fig.savefig(folder / "interpenetration.png", dpi=110)
        plt.close(fig)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
