#!/usr/bin/python3
"""Contacts against the true penetration, nearest surface on and off
(bench/truth.sh): a table (table.md) and a plot (truth.png) per family of
the over-reported contacts (deeper than 1.25x the true penetration + 1e-3
of the smaller body), the worst depth over the truth, the push's angle to
the way out, and the time per pair.

    /usr/bin/python3 bench/plot_truth.py FOLDER
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(folder: Path) -> None:
    runs = {name: {s["family"]: s for s in json.loads((folder / f"{name}.json").read_text())} for name in ("on", "off")}
    families = list(runs["on"])
    lines = ["| family | contacts | over-reported, on | off | depth / true max, on | off | push angle p95 (deg), on "
             "| off | µs per pair, on | off | cost |",
             "| :-- | --: | --: | --: | --: | --: | --: | --: | --: | --: | --: |"]
    for f in families:
        on, off = runs["on"][f], runs["off"][f]
        t_on, t_off = 1e6 * on["seconds_per_pair"]["ours"], 1e6 * off["seconds_per_pair"]["ours"]
        lines.append(f"| {f} | {on['truth']['contacts']} | {on['truth']['over_reports']} | "
                     f"{off['truth']['over_reports']} | {on['truth']['depth_ratio']['max']:.3f} | "
                     f"{off['truth']['depth_ratio']['max']:.1f} | {on['truth']['push_angle_degrees']['p95']:.1f} | "
                     f"{off['truth']['push_angle_degrees']['p95']:.1f} | {t_on:.1f} | {t_off:.1f} | "
                     f"{t_on / t_off:.2f}× |")
    (folder / "table.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 4.5))
    x = range(len(families))
    for shift, name, colour in ((-0.2, "off", "tab:red"), (0.2, "on", "tab:blue")):
        label = "nearest surface" if name == "on" else "ray contacts (thesis)"
        over = [100 * runs[name][f]["truth"]["over_reports"] / max(runs[name][f]["truth"]["contacts"], 1)
                for f in families]
        ax1.bar([i + shift for i in x], over, width=0.4, color=colour, label=label)
        ax2.bar([i + shift for i in x], [1e6 * runs[name][f]["seconds_per_pair"]["ours"] for f in families],
                width=0.4, color=colour, label=label)
    for ax, title in ((ax1, "contacts deeper than 1.25x the true penetration (%)"), (ax2, "µs per pair (Embree, one thread)")):
        ax.set_xticks(list(x))
        ax.set_xticklabels(families, rotation=45, ha="right")
        ax.set_title(title)
        ax.legend()
    ax2.set_yscale("log")
    fig.tight_layout()
    fig.savefig(folder / "truth.png", dpi=110)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
