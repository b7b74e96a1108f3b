"""The table of docs/results/edges/README.md from the four runs of
bench/edge_costs.sh: rays and time per pair, and the pairs missed, with edge
contacts on and off, per family and mode."""
import json
import os
import sys


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: edge_table.py RESULTS_DIR")
    folder = sys.argv[1]
    runs = {}
    for edges in ("on", "off"):
        for mode in ("full", "iterative"):
            with open(os.path.join(folder, f"{edges}_{mode}.json"), encoding="utf-8") as f:
                for s in json.load(f):
                    runs[(s["family"], mode, edges)] = s
    families = []
    for (family, _, _) in runs:
        if family not in families:
            families.append(family)
    lines = ["| family | mode | edges | rays per pair: vertex + edge | edges tested per pair | µs per pair "
             "| time × | colliding pairs | missed pairs |",
             "|---|---|---|---|---|---|---|---|---|"]
    for family in families:
        for mode in ("full", "iterative"):
            off = runs[(family, mode, "off")]
            for edges in ("on", "off"):
                s = runs[(family, mode, edges)]
                r = s["rays_per_pair"]
                colliding = round(s["colliding_fraction"] * s["pairs"])
                ratio = s["seconds_per_pair"]["ours"] / off["seconds_per_pair"]["ours"]
                lines.append(f"| {family} | {mode} | {edges} | {r['vertex']:.1f} + {r['edge']:.1f} "
                             f"| {r['edges_tested']:.1f} | {1e6 * s['seconds_per_pair']['ours']:.1f} "
                             f"| {ratio:.2f} | {colliding} | {s['missed_pairs']} |")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
