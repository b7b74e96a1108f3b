#!/usr/bin/python3
"""Plots bench/threshold_sweep.sh's CSV: phase C's ray time per step
(full tracing and walks stacked) and the share of pairs traced in full
against the displacement threshold, with full mode's ray time for scale
and what the judged steps found."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_threshold.py SWEEP.csv OUT.png")
    with open(sys.argv[1], newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{sys.argv[1]}: no sweep points")
    t = [float(r["threshold"]) for r in rows]
    full = [float(r["full_tracing_ms"]) for r in rows]
    walks = [float(r["walks_ms"]) for r in rows]
    share = [float(r["traced_in_full_pct"]) for r in rows]
    full_mode = float(rows[0]["full_mode_ray_ms"])

    fig, ax = plt.subplots(figsize=(7, 4.5))
    width = 0.6 * min(b - a for a, b in zip(t, t[1:])) if len(t) > 1 else 0.005
    ax.bar(t, full, width, label="full tracing (pairs sent back)", color="tab:red")
    ax.bar(t, walks, width, bottom=full, label="walks", color="tab:blue")
    for x, f, w, r in zip(t, full, walks, rows):
        ax.annotate(f"{f + w:.1f}" + (f"\n{r['missed']} missed" if int(r["missed"]) else ""), (x, f + w),
                    ha="center", va="bottom", fontsize=8)
    missed = sorted({int(r["missed"]) for r in rows})
    false_rays = sorted({int(r["false_rays"]) for r in rows})
    judged = (f"judged: {'-'.join(map(str, missed))} of {rows[0]['deep']} deep rays missed, "
              f"{'-'.join(map(str, false_rays))} false ({rows[0]['judged_steps']} steps)")
    ax.set_xlabel("displacement threshold")
    ax.set_ylabel("phase C ray time per step, ms (one thread)")
    ax.set_ylim(0, 1.35 * max(f + w for f, w in zip(full, walks)))
    ax.set_title(f"Avalanche phase C, automatic Embree; full mode: {full_mode:.1f} ms\n{judged}", fontsize=10)
    share_ax = ax.twinx()
    share_ax.plot(t, share, "k.-", label="pairs traced in full (%)")
    share_ax.set_ylabel("pairs traced in full, %")
    share_ax.set_ylim(0, 1.2 * max(share))
    lines, labels = ax.get_legend_handles_labels()
    more, more_labels = share_ax.get_legend_handles_labels()
    ax.legend(lines + more, labels + more_labels, loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
