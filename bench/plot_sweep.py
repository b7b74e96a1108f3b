#!/usr/bin/python3
"""Plots `rtcd validate --sweep` CSV: time per pair against missed-ray rate
and against mean depth error, one marker per knob, the Pareto front drawn
and the default configuration marked."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def pareto(points):
    """Points not beaten on both time and error, sorted by time."""
    front, best = [], float("inf")
    for t, e in sorted(points):
        if e < best:
            front.append((t, e))
            best = e
    return front


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_sweep.py SWEEP.csv OUT.png")
    with open(sys.argv[1], newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{sys.argv[1]}: no sweep points")
    title = f"{rows[0]['family']} family, {rows[0]['backend']} backend, {rows[0]['pairs']} pairs per point"
    fig, axes = plt.subplots(1, 3, figsize=(19, 5.5))
    for ax, column, label in ((axes[0], "missed_rate", "missed-ray rate"),
                              (axes[1], "missed_pair_rate", "missed-pair rate (of colliding pairs)"),
                              (axes[2], "mean_depth_error", "mean depth error (length units)")):
        knobs = sorted({r["knob"] for r in rows})
        for knob in knobs:
            sel = [r for r in rows if r["knob"] == knob]
            xs = [1e6 * float(r["seconds_per_pair"]) for r in sel]
            ys = [max(float(r[column]), 1e-9) for r in sel]
            ax.scatter(xs, ys, label=knob, s=30)
            for r, x, y in zip(sel, xs, ys):
                ax.annotate(r["value"], (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points")
        front = pareto([(1e6 * float(r["seconds_per_pair"]), max(float(r[column]), 1e-9)) for r in rows])
        ax.plot([p[0] for p in front], [p[1] for p in front], "k--", lw=1, label="Pareto front")
        default = [r for r in rows if r["default"] == "1"]
        for r in default:
            ax.scatter([1e6 * float(r["seconds_per_pair"])], [max(float(r[column]), 1e-9)], s=160,
                       facecolors="none", edgecolors="red", linewidths=2, label="default")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per pair (µs, one thread)")
        ax.set_ylabel(label + " (1e-9 = none)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
