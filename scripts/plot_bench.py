#!/usr/bin/python3
"""Plots of one `rtcd bench` folder: Figure 2.12 (the whole step in the host,
rtcd against GIMPACT), 2.13 (ray time per step, every configuration), 2.14
(ray time against the body count, log scale) and accuracy against time.
Debian's python3-matplotlib; usage: plot_bench.py BENCH_DIR"""
import csv
import sys
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def read(path: Path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def figure_2_12(folder: Path) -> None:
    rows = read(folder / "host_steps.csv")
    stages = [("seconds_broad", "broad phase"), ("seconds_narrow", "narrow phase"),
              ("seconds_solver", "solver"), ("seconds_effects", "other")]
    hosts = ["rtcd", "GIMPACT"]
    means = {h: [0.0] * len(stages) for h in hosts}
    for h in hosts:
        mine = [r for r in rows if r["host"] == h]
        for i, (key, _) in enumerate(stages):
            means[h][i] = 1e3 * sum(float(r[key]) for r in mine) / max(1, len(mine))
    fig, ax = plt.subplots(figsize=(7, 3.2))
    left = [0.0, 0.0]
    for i, (_, name) in enumerate(stages):
        values = [means[h][i] for h in hosts]
        ax.barh(hosts, values, left=left, label=name)
        left = [a + b for a, b in zip(left, values)]
    for y, total in enumerate(left):
        ax.text(total, y, f" {total:.1f} ms", va="center")
    ax.set_xlabel("mean time per step (ms), one thread")
    ax.set_xlim(0, max(left) * 1.2)
    ax.legend(loc="lower right", fontsize=8)
    ax.set_title("Figure 2.12: the whole step, rtcd against GIMPACT in the same host")
    fig.tight_layout()
    fig.savefig(folder / "figure_2_12.png", dpi=110)
    plt.close(fig)


def by_config(rows):
    out = defaultdict(list)
    for r in rows:
        out[r["config"]].append(r)
    return out


def figure_2_13(folder: Path, configs) -> None:
    fig, ax = plt.subplots(figsize=(9, 5))
    for label, rows in configs.items():
        if rows[0]["engine"] in ("bullet-gimpact", "fcl") or "threshold" in label:
            continue
        ax.plot([float(r["time"]) for r in rows], [1e3 * float(r["seconds_rays"]) for r in rows], label=label,
                lw=1)
    phases = {}
    for r in next(iter(configs.values())):
        phases.setdefault(r["phase"], float(r["time"]))
    for p, t in phases.items():
        if p in "ABC":
            ax.axvline(t, color="grey", lw=0.6, ls=":")
            ax.text(t, 1.0, " " + p, transform=ax.get_xaxis_transform(), va="top")
    ax.set_yscale("log")
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel("ray time per step (ms), tracing + walking")
    ax.set_title("Figure 2.13: ray time per step")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(folder / "figure_2_13.png", dpi=110)
    plt.close(fig)


def figure_2_14(folder: Path, configs) -> None:
    fig, ax = plt.subplots(figsize=(8, 5))
    counts = {int(r["bodies"]) for rows in configs.values() for r in rows}
    if len(counts) == 1:
        ax.text(0.5, 0.5, f"The body count is constant ({counts.pop()}) in this scene:\n"
                "Figure 2.13 shows its ray time per step.", ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()
        fig.savefig(folder / "figure_2_14.png", dpi=110)
        plt.close(fig)
        return
    for label in ("full basic", "auto basic", "full embree", "auto embree"):
        rows = configs.get(label, [])
        ax.plot([int(r["bodies"]) for r in rows], [1e3 * float(r["seconds_rays"]) for r in rows], ".", ms=2,
                label=label)
    ax.set_yscale("log")
    ax.set_xlabel("bodies in the scene")
    ax.set_ylabel("ray time per step (ms), one thread")
    ax.set_title("Figure 2.14: ray time against the body count")
    ax.legend(fontsize=8, markerscale=4)
    fig.tight_layout()
    fig.savefig(folder / "figure_2_14.png", dpi=110)
    plt.close(fig)


def accuracy(folder: Path) -> None:
    """Each configuration a marker of its own, named in the legend: ray time
    when settled against missed rays and against interpenetration at the end."""
    rows = read(folder / "accuracy.csv")
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    markers = "osD^vP*Xh<>"
    for i, r in enumerate(rows):
        try:
            t = float(r["mean ray time, settled (ms)"])
        except ValueError:
            continue
        style = dict(marker=markers[i % len(markers)], ls="none", ms=7, label=r["configuration"])
        missed = r["missed rays (judged steps)"].rstrip("%")
        inter = r["interpenetration at the end (simulated)"]
        axes[0].plot([t], [float(missed)] if missed not in ("", "–") else [float("nan")], **style)
        axes[1].plot([t], [float(inter)] if inter not in ("", "–") else [float("nan")], **style)
    axes[0].set_ylabel("missed rays (%), exact reference on judged steps")
    axes[0].set_yscale("symlog", linthresh=0.01)
    axes[1].set_ylabel("interpenetration at the end (simulated)")
    axes[1].set_yscale("log")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xlabel("mean ray time when settled (ms), one thread")
        ax.grid(alpha=0.3)
    axes[1].legend(fontsize=7, loc="best")
    fig.suptitle("Accuracy against time on the scene")
    fig.tight_layout()
    fig.savefig(folder / "accuracy.png", dpi=110)
    plt.close(fig)


def main(folder: Path) -> None:
    figure_2_12(folder)
    configs = by_config(read(folder / "replay_steps.csv"))
    if configs:
        figure_2_13(folder, configs)
        figure_2_14(folder, configs)
    accuracy(folder)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
