#!/usr/bin/python3
"""The README's results table, generated from the files in docs/results.

Every figure is read from a file a tool wrote (CSV, JSON, a benchmark's
console output) and every row names the commit and date of its folder's
meta.json. Standard library only.

  scripts/results_table.py                 print the results table
  scripts/results_table.py --write FILE    replace FILE's generated blocks
  scripts/results_table.py --check FILE    exit 1, naming the row, where FILE's
                                           blocks differ from what the files give
  scripts/results_table.py --stale         list folders measured on a commit
                                           whose code differs from HEAD's

Generated blocks lie between `<!-- NAME:begin -->` and `<!-- NAME:end -->`:
`results` (the headline table), `run-console` (the main job's console output,
docs/results/run/console.txt) and `folders` (the folders and their meta.json,
for docs/results/README.md).
"""

import argparse
import csv
import difflib
import json
import os
import re
import statistics
import subprocess
import sys
import textwrap

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RESULTS = os.path.join("docs", "results")

# The folders, in the order docs/results/README.md lists them.
FOLDERS = ["run", "avalanche", "stream", "stream-end", "validation", "truth", "zoo", "piles", "opencl", "gpu", "threshold-sweep",
           "accuracy-sweep",
           "edges", "python", "campaign", "judged", "floors", "view"]
META_KEYS = ("experiment", "command", "machine", "date", "commit", "note")


class ResultError(Exception):
    """A result file is missing or does not hold what the table needs."""


# ---------------------------------------------------------------- reading

def path_of(*parts):
    return os.path.join(ROOT, RESULTS, *parts)


def read_text(*parts):
    p = path_of(*parts)
    try:
        with open(p, encoding="utf-8") as f:
            return f.read()
    except OSError as e:
        raise ResultError(f"cannot read {os.path.relpath(p, ROOT)}: {e.strerror}") from e


def read_json(*parts):
    text = read_text(*parts)
    try:
        return json.loads(text)
    except ValueError as e:
        raise ResultError(f"{os.path.join(RESULTS, *parts)}: not JSON ({e})") from e


def read_csv(*parts):
    """Rows as dicts keyed by the header, and the header itself."""
    rows = list(csv.reader(read_text(*parts).splitlines()))
    if not rows:
        raise ResultError(f"{os.path.join(RESULTS, *parts)} is empty")
    return [dict(zip(rows[0], r)) for r in rows[1:]], rows[0]


def row_named(rows, header, name, where):
    for r in rows:
        if r[header[0]] == name:
            return r
    raise ResultError(f"{where}: no row '{name}'")


def number(text, where):
    try:
        return float(str(text).replace("%", "").replace("×", "").strip())
    except ValueError as e:
        raise ResultError(f"{where}: '{text}' is not a number") from e


def meta(folder):
    m = read_json(folder, "meta.json")
    missing = [k for k in META_KEYS if not m.get(k)]
    if missing:
        raise ResultError(f"{RESULTS}/{folder}/meta.json lacks {', '.join(missing)}")
    return m


def bench_runs(folder):
    """The runs of one bench experiment: the folder itself, and any subfolder
    holding another run (a second recording made from scratch)."""
    runs = []
    if os.path.exists(path_of(folder, "table_2_1.csv")):
        runs.append(folder)
    base = path_of(folder)
    if os.path.isdir(base):
        for name in sorted(os.listdir(base)):
            if os.path.exists(os.path.join(base, name, "table_2_1.csv")):
                runs.append(os.path.join(folder, name))
    if not runs:
        raise ResultError(f"{RESULTS}/{folder}: no bench run (table_2_1.csv)")
    return runs


# ---------------------------------------------------------------- formatting

def span(values, fmt):
    """One value, or 'least – most' over several runs."""
    lo, hi = min(values), max(values)
    return fmt(lo) if fmt(lo) == fmt(hi) else f"{fmt(lo)} – {fmt(hi)}"


def f2(x):
    return f"{x:.2f}"


def g(x):
    """As the tool wrote it (3.88, 11.3)."""
    return f"{x:g}"


def short_commit(c):
    return c[:7] if re.fullmatch(r"[0-9a-f]{40}", c) else c


class Row:
    def __init__(self, figure, value, folder, source, metas):
        self.figure, self.value, self.folder, self.source = figure, value, folder, source
        commits = sorted({short_commit(m["commit"]) for m in metas})
        dates = sorted({m["date"] for m in metas})
        self.when = f"{', '.join(commits)} · {', '.join(dates)}"
        if len(metas) > 1:
            self.value += f" ({len(metas)} recordings)"


# ---------------------------------------------------------------- the figures

def avalanche_rows():
    runs = bench_runs("avalanche")
    metas = [meta(r) for r in runs]
    full_c, auto_c, speedup, peak, peak_step, missed, false_rays = [], [], [], [], [], [], []
    gimpact1, fcl1, gimpact2, fcl2, predictive, speculative = [], [], [], [], [], []
    for run in runs:
        where = f"{RESULTS}/{run}/table_2_1.csv"
        rows, header = read_csv(run, "table_2_1.csv")
        c_col = next((h for h in header if h.startswith("mean in C")), None)
        if c_col is None:
            raise ResultError(f"{where}: no phase C column")
        full_c.append(number(row_named(rows, header, "full embree", where)[c_col], where))
        auto_c.append(number(row_named(rows, header, "auto embree", where)[c_col], where))
        missed_col = next(h for h in header if h.startswith("missed rays"))
        false_col = next((h for h in header if h.startswith("false rays")), None)
        if false_col is None:
            raise ResultError(f"{where}: no false-ray column")
        missed.append(max(number(r[missed_col], where) for r in rows))
        false_rays.append(sum(number(r[false_col], where) for r in rows))

        where = f"{RESULTS}/{run}/table_2_1_speedups.csv"
        rows, header = read_csv(run, "table_2_1_speedups.csv")
        speedup.append(number(row_named(rows, header, "embree", where)["C (mean)"], where))

        where = f"{RESULTS}/{run}/peak_step.csv"
        rows, header = read_csv(run, "peak_step.csv")
        total = sum(number(r["ms"], where) for r in rows)
        report = read_text(run, "report.md")
        m = re.search(r"peak ([0-9.]+) ms at step ([0-9]+)", report)
        if not m:
            raise ResultError(f"{RESULTS}/{run}/report.md: no 'peak ... ms at step ...'")
        if abs(float(m.group(1)) - total) > 0.02:
            raise ResultError(f"{where}: the stages add up to {total:.2f} ms, report.md says {m.group(1)}")
        peak.append(float(m.group(1)))
        peak_step.append(int(m.group(2)))

        where = f"{RESULTS}/{run}/peers.csv"
        rows, header = read_csv(run, "peers.csv")
        one = row_named(rows, header, "auto embree", where)
        two = row_named(rows, header, "auto embree, 2 threads", where)
        gimpact1.append(number(one["GIMPACT ÷ it, median"], where))
        fcl1.append(number(one["FCL ÷ it, median"], where))
        gimpact2.append(number(two["GIMPACT ÷ it, median"], where))
        fcl2.append(number(two["FCL ÷ it, median"], where))

        where = f"{RESULTS}/{run}/table_2_3.csv"
        rows, header = read_csv(run, "table_2_3.csv")
        decreases = [h for h in header if h == "decrease"]
        if len(rows) != 1 or len(decreases) != 2:
            raise ResultError(f"{where}: expected one scene row and two 'decrease' columns")
        cells = list(csv.reader([read_text(run, "table_2_3.csv").splitlines()[1]]))[0]
        predictive.append(number(cells[3], where))
        speculative.append(number(cells[5], where))

    report = "avalanche/report.md"
    steps = ", ".join(str(s) for s in sorted(set(peak_step)))
    return [
        Row("avalanche: phase C ray time, full Embree → automatic (1 thread)",
            f"{span(full_c, f2)} → {span(auto_c, f2)} ms: {span(speedup, f2)}×", "avalanche", report, metas),
        Row("avalanche: peak narrow-phase step, automatic, 2 threads",
            f"{span(peak, f2)} ms (step {steps})", "avalanche", report, metas),
        Row("avalanche: missed / false rays, judged steps, every configuration",
            f"{span(missed, lambda x: f'{x:.3f}%')} / {span(false_rays, lambda x: f'{x:.0f}')}",
            "avalanche", report, metas),
        Row("avalanche: GIMPACT ÷ rtcd, FCL ÷ rtcd, median step",
            f"{span(gimpact1, g)}×, {span(fcl1, g)}× "
            f"(rtcd on 2 threads: {span(gimpact2, g)}×, {span(fcl2, g)}×)",
            "avalanche", report, metas),
        Row("avalanche: predictive rays cut the interpenetration at the end by",
            f"{span(predictive, f2)}% ({span(speculative, f2)}% with speculative contacts)",
            "avalanche", report, metas),
    ]


def stream_rows():
    runs = bench_runs("stream")
    metas = [meta(r) for r in runs]
    speedup, full, auto, gimpact, fcl, steps, bodies = [], [], [], [], [], set(), set()
    for run in runs:
        where = f"{RESULTS}/{run}/figure_2_14_speedups.csv"
        rows, header = read_csv(run, "figure_2_14_speedups.csv")
        r = row_named(rows, header, "embree", where)
        speedup.append(number(r["speedup"], where))
        full.append(number(r["full: mean ray time (ms)"], where))
        auto.append(number(r["automatic (ms)"], where))
        steps.add(r["steps"])
        bodies.add(r["bodies"].replace(" – ", "–"))
        where = f"{RESULTS}/{run}/peers.csv"
        rows, header = read_csv(run, "peers.csv")
        one = row_named(rows, header, "auto embree", where)
        gimpact.append(number(one["GIMPACT ÷ it, median"], where))
        fcl.append(number(one["FCL ÷ it, median"], where))
    report = "stream/report.md"
    return [
        Row("stream: ray time, full Embree → automatic, the last 300 steps full Embree reached in the bench's "
            "budget (1 thread)",
            f"{span(full, f2)} → {span(auto, f2)} ms: {span(speedup, f2)}× "
            f"(steps {', '.join(sorted(steps))}, {', '.join(sorted(bodies))} bodies)",
            "stream", report, metas),
        Row("stream: GIMPACT ÷ rtcd, FCL ÷ rtcd, median step (1 thread)",
            f"{span(gimpact, g)}×, {span(fcl, g)}×", "stream", report, metas),
    ]


def replay_ray_time(folder, name, label):
    """Ray time (full tracing + walks, ms) and pairs of one row of an
    `rtcd replay` table, the row whose first cell is label."""
    where = f"{RESULTS}/{folder}/{name}"
    for line in read_text(folder, name).splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells[0] == label:
            if len(cells) < 9:
                raise ResultError(f"{where}: row '{label}' is short")
            return number(cells[5], where) + number(cells[6], where), number(cells[8], where)
    raise ResultError(f"{where}: no row '{label}'")


def stream_end_rows():
    """The stream's own last 300 steps: rounds of a full and an automatic
    replay run back to back (full_K.txt, auto_K.txt); the row gives the
    round whose full ÷ automatic is the median, so its three figures agree."""
    folder = "stream-end"
    m = meta(folder)
    rounds = sorted(n[len("full_"):-len(".txt")] for n in os.listdir(path_of(folder))
                    if n.startswith("full_") and n.endswith(".txt"))
    if not rounds:
        raise ResultError(f"{RESULTS}/{folder}: no full_K.txt")
    measured = []  # (ratio, full, auto, pairs) per round
    for k in rounds:
        full, pairs = replay_ray_time(folder, f"full_{k}.txt", "last 300")
        auto, _ = replay_ray_time(folder, f"auto_{k}.txt", "last 300")
        measured.append((full / auto, full, auto, pairs))
    ratio, full, auto, pairs = sorted(measured)[(len(measured) - 1) // 2]
    return [Row("stream: ray time, full Embree → automatic, the recording's last 300 steps (1 thread)",
                f"{full:.2f} → {auto:.2f} ms: {ratio:.2f}× (the median of {len(rounds)} rounds, "
                f"{min(r[0] for r in measured):.2f}–{max(r[0] for r in measured):.2f}×; {pairs:.0f} pairs a step)",
                folder, f"{folder}/README.md", [m])]


def validation_rows():
    """One row over every family: each family's own figures are in
    validation/README.md."""
    m = meta("validation")
    full = read_json("validation", "full.json")
    iterative = {s["family"]: s for s in read_json("validation", "iterative.json")}
    if not full:
        raise ResultError(f"{RESULTS}/validation/full.json: no family")
    for s in full:
        if s["family"] not in iterative:
            raise ResultError(f"{RESULTS}/validation/iterative.json: no run of family {s['family']}")
        if not s.get("oracles"):
            raise ResultError(f"{RESULTS}/validation/full.json: family {s['family']} ran without the oracles")
    worst = lambda runs, key: max(runs, key=lambda r: r[key])
    full_missed, it_missed = worst(full, "missed_rate"), worst(iterative.values(), "missed_rate")
    it_pairs = worst(iterative.values(), "missed_pair_rate")
    def missed(run):
        return (f"worst {100 * run['missed_rate']:.3f}% ({run['family']})" if run["missed_rate"] > 0
                else "0.000% in every family")
    value = (f"full: {missed(full_missed)}, "
             f"{sum(s['false_rays'] for s in full)} false, {sum(s['missed_pairs'] for s in full)} pairs missed; "
             f"iterative: {missed(it_missed)}, "
             f"{sum(s['false_rays'] for s in iterative.values())} false, "
             f"pairs missed at most {100 * it_pairs['missed_pair_rate']:.2f}%")
    return [Row(f"validation, {len(full)} families ({', '.join(s['family'] for s in full)}): rays missed, "
                "false rays and colliding pairs missed against the exact reference",
                value, "validation", "validation/README.md", [m])]


def truth_rows():
    m = meta("truth")
    runs = {name: read_json("truth", f"{name}.json") for name in ("on", "off")}
    rows = []
    for name, label in (("on", "nearest surface (default)"), ("off", "ray contacts (thesis)")):
        summaries = runs[name]
        if not summaries:
            raise ResultError(f"{RESULTS}/truth/{name}.json: no family")
        contacts = sum(s["truth"]["contacts"] for s in summaries)
        over = sum(s["truth"]["over_reports"] for s in summaries)
        worst = max(s["truth"]["depth_ratio"]["max"] for s in summaries)
        angle = max(s["truth"]["push_angle_degrees"]["p95"] for s in summaries)
        rows.append(Row(f"contacts against the true penetration, {len(summaries)} families, full mode, {label}: "
                        "deeper than 1.25× it; worst depth over it; worst family's push-angle p95",
                        f"{over} of {contacts}; {worst:.3g}×; {angle:.1f}°", "truth", "truth/README.md", [m]))
    cost = [on["seconds_per_pair"]["ours"] / off["seconds_per_pair"]["ours"]
            for on, off in zip(runs["on"], runs["off"]) if off["seconds_per_pair"]["ours"] > 0]
    rows.append(Row("nearest-surface contacts' cost, time per pair on ÷ off (random deep poses)",
                    span(cost, lambda x: f"{x:.2f}×"), "truth", "truth/README.md", [m]))
    return rows


def zoo_rows():
    m = meta("zoo")
    z = read_json("zoo", "zoo.json")
    for key in ("deepest_true", "summed_true", "longest_deep_run_steps"):
        if key not in z:
            raise ResultError(f"{RESULTS}/zoo/zoo.json: no {key}")
    d, s, run = z["deepest_true"], z["summed_true"], z["longest_deep_run_steps"]
    return [Row(f"zoo scene from {z['from_time']} s: deepest true penetration, rtcd- / GIMPACT-hosted (most over "
                "the steps)", f"{1000 * d['rtcd_max']:.1f} / {1000 * d['gimpact_max']:.1f} mm", "zoo",
                "zoo/README.md", [m]),
            Row(f"zoo scene from {z['from_time']} s: summed true penetration, rtcd- / GIMPACT-hosted (most)",
                f"{s['rtcd_max']:.3g} / {s['gimpact_max']:.3g}", "zoo", "zoo/README.md", [m]),
            Row("zoo scene: longest a pair stays deeper than 2% of its smaller body, rtcd- / GIMPACT-hosted "
                "(goal ≤ 30 steps)", f"{run['rtcd']:.0f} / {run['gimpact']:.0f} steps", "zoo", "zoo/README.md", [m])
            ] + zoo_seed_rows(m)


def zoo_seed_rows(m):
    rows, header = read_csv("zoo", "seeds/seeds.csv")
    for key in ("seed", "host", "ground_depth_fraction_max", "longest_deep_run_steps"):
        if key not in header:
            raise ResultError(f"{RESULTS}/zoo/seeds/seeds.csv: no column {key}")
    out = []
    for host in ("rtcd", "gimpact"):
        runs = [r for r in rows if r["host"] == host]
        if not runs:
            raise ResultError(f"{RESULTS}/zoo/seeds/seeds.csv: no {host} run")
        ground = [100 * number(r["ground_depth_fraction_max"], "seeds.csv") for r in runs]
        held = [number(r["longest_deep_run_steps"], "seeds.csv") for r in runs]
        out.append(Row(f"zoo scene, seeds 1–{len(runs)}, {host}-hosted, from 1.5 s: deepest body in the ground ÷ its "
                       "size (goal ≤ 1%); longest deep pair (goal ≤ 30 steps)",
                       f"{min(ground):.2f}–{max(ground):.2f}%; {min(held):.0f}–{max(held):.0f} steps", "zoo",
                       "zoo/seeds/seeds.csv", [m]))
    return out


def piles_rows():
    m = meta("piles")
    rows, header = read_csv("piles", "piles.csv")
    for key in ("pile", "host", "holds_a_pair"):
        if key not in header:
            raise ResultError(f"{RESULTS}/piles/piles.csv: no column {key}")
    held = {}
    for r in rows:
        h = held.setdefault(r["host"], [0, 0])
        h[0] += int(number(r["holds_a_pair"], f"{RESULTS}/piles/piles.csv"))
        h[1] += 1
    if set(held) != {"rtcd", "gimpact"}:
        raise ResultError(f"{RESULTS}/piles/piles.csv: hosts {sorted(held)}, not rtcd and gimpact")
    piles = len({r["pile"] for r in rows})
    return [Row(f"piles of one zoo kind ({piles} piles, 2 s each): runs in which a pair stays deeper than 2% of its "
                "smaller body for more than 30 steps after 1 s, rtcd- / GIMPACT-hosted",
                f"{held['rtcd'][0]} / {held['gimpact'][0]} of {held['rtcd'][1]}", "piles", "piles/README.md", [m])]


def benchmark_medians(folder, name):
    """Median real time (µs) of each benchmark in Google Benchmark's JSON
    (NAME.json) or, failing that, its console output (NAME.txt)."""
    units = {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}
    medians = {}
    if os.path.exists(path_of(folder, name + ".json")):
        for b in read_json(folder, name + ".json").get("benchmarks", []):
            if b.get("aggregate_name") == "median":
                medians[b["run_name"]] = b["real_time"] * units[b.get("time_unit", "ns")]
        return medians, f"{folder}/{name}.json"
    for line in read_text(folder, name + ".txt").splitlines():
        m = re.match(r"(\S+)_median\s+([0-9.]+) (ns|us|ms|s)\s", line)
        if m:
            medians[m.group(1)] = float(m.group(2)) * units[m.group(3)]
    return medians, f"{folder}/{name}.txt"


def opencl_rows():
    m = meta("opencl")
    medians, source = benchmark_medians("opencl", "bench_pocl_basic")

    def scaling(kind):
        one = f"opencl_{kind}/64/1/real_time"
        two = f"opencl_{kind}/64/2/real_time"
        if one not in medians or two not in medians:
            raise ResultError(f"{RESULTS}/{source}: no median of {one} and {two}")
        return medians[one] / medians[two]

    value = (f"brute force {scaling('full_basic'):.2f}×, BVH {scaling('full_bvh'):.2f}×, "
             f"walks {scaling('iterative'):.2f}×")
    steady = []
    for name in ("full_embree/64", "iterative/64"):
        if name not in medians:
            raise ResultError(f"{RESULTS}/{source}: no median of {name}")
        steady.append(medians[name])
    return [Row("OpenCL: two PoCL `basic` devices against one, 64 pairs", value, "opencl", source, [m]),
            Row("steady contact, 64 pairs of 902-triangle meshes: full Embree → iterative step (1 thread)",
                f"{steady[0]:.0f} → {steady[1]:.0f} µs: {steady[0] / steady[1]:.2f}×", "opencl", source, [m])]


def pocl_avalanche_rows():
    """Phase C of the avalanche replays on PoCL: detect against Embree (and
    the peers, where the file replayed them), and the bytes a step each way,
    from a file whose header names its date, commit and machine."""
    source = "opencl/device_jobs.txt"
    where = f"{RESULTS}/{source}"
    text = read_text("opencl", "device_jobs.txt")
    stamp = {}
    for key in ("date", "commit", "machine"):
        found = re.search(rf"^# {key}: (.+)$", text, re.M)
        if not found:
            raise ResultError(f"{where}: no '# {key}:' line")
        stamp[key] = found.group(1).strip()
    detect = {"new": [], "embree": [], "gimpact": [], "fcl": []}
    to_floor = "KB to the devices, floor \\(64 × bodies \\+ 16 × pairs\\)"
    traffic = {"KB to the devices": [], "KB from the devices": [], "KB recovery reads": [],
               "reports \\(contacts \\+ predictive rays\\)": [], to_floor: []}
    pairs = {"A": [], "B": [], "C": []}
    for section in re.split(r"^## ", text, flags=re.M)[1:]:
        who = section.split()[0]
        row = re.search(r"^\| C \| \d+ \| ([0-9.]+) \|", section, re.M)
        if who in detect:
            if not row:
                raise ResultError(f"{where}: section '{section.splitlines()[0]}' has no phase C row")
            detect[who].append(float(row.group(1)))
        if who == "new":
            for phase, values in pairs.items():
                values.append(float(re.search(rf"^\| {phase} \| \d+ \| (?:[^|]+\|){{6}} ([0-9.]+) \|", section,
                                              re.M).group(1)))
            for name, values in traffic.items():
                kb = re.search(rf"^\| {name} \| ([0-9.]+) \| ([0-9.]+) \| ([0-9.]+) \|", section, re.M)
                if not kb:
                    raise ResultError(f"{where}: section '{section.splitlines()[0]}' has no '{name}' row")
                values.append(tuple(float(kb.group(k)) for k in (1, 2, 3)))  # phases A, B and C
    if not detect["new"] or not detect["embree"]:
        raise ResultError(f"{where}: no 'new' or 'embree' replay")
    opencl, embree = statistics.median(detect["new"]), statistics.median(detect["embree"])
    value = f"{opencl:.1f} ÷ {embree:.1f} ms: {opencl / embree:.2f}×"
    peers = [f"{name} {statistics.median(detect[key]):.1f} ms" for key, name in (("gimpact", "GIMPACT"), ("fcl", "FCL"))
             if detect[key]]
    if peers:
        value += " (one thread, the same steps: " + ", ".join(peers) + ")"
    by_phase = {phase: {name: statistics.median(v[k] for v in values) for name, values in traffic.items()}
                for k, phase in enumerate("ABC")}
    _, down, recovery, reports, _ = by_phase["C"].values()
    bound = (64 * reports + 16 * statistics.median(pairs["C"])) / 1e6

    def from_device(phase):
        """Phase A's or B's bytes from the device a step and their floor, in MB."""
        t = by_phase[phase]
        floor = (64 * t["reports \\(contacts \\+ predictive rays\\)"] + 16 * statistics.median(pairs[phase])) / 1e6
        return f"{phase} {t['KB from the devices'] / 1000:.2f}, floor {floor:.2f}"

    def to_device(phase):
        """A phase's bytes to the device a step and their floor, in MB."""
        t = by_phase[phase]
        return f"{t['KB to the devices'] / 1000:.2f}, floor {t[to_floor] / 1000:.2f}"

    return [Row("avalanche phase C detect on PoCL: OpenCL on one `basic` device ÷ Embree on one thread (floor 1.5×)",
                value, "opencl", source, [stamp]),
            Row("avalanche phase C, bytes a step on PoCL: from the device (floor: 64 × (contacts + predictive rays) + "
                "16 × pairs, from the same run; phases B and A beside it); the walk starts' recovery reads, apart; to the "
                "device (floor: 64 × bodies + 16 × pairs; B and A beside it)",
                f"{down / 1000:.2f} MB (floor {bound:.2f} MB; {from_device('B')}; {from_device('A')}); "
                f"{recovery / 1000:.2f} MB; {to_device('C')} MB (B {to_device('B')}; A {to_device('A')})",
                "opencl", source, [stamp])]


def gpu_rows():
    m = meta("gpu")
    phase_c = {}
    for name in ("replay_gpu_threads2", "replay_gpu_vertex_threads2", "replay_embree2"):
        where = f"{RESULTS}/gpu/{name}.txt"
        row = re.search(r"^\| C \| \d+ \| ([0-9.]+) \| [^|]+\| [0-9.]+ \| ([0-9.]+) \| ([0-9.]+) \|",
                        read_text("gpu", f"{name}.txt"), re.M)
        if not row:
            raise ResultError(f"{where}: no phase C row")
        phase_c[name] = (float(row.group(2)) + float(row.group(3)), float(row.group(1)))
    source = "gpu/README.md"
    gpu, vertex, embree = phase_c["replay_gpu_threads2"], phase_c["replay_gpu_vertex_threads2"], phase_c["replay_embree2"]
    return [Row("avalanche phase C ray time (detect), 2 host threads: OpenCL on an NVIDIA H100; Embree on the same machine",
                f"{gpu[0]:.2f} ms ({gpu[1]:.2f}); {embree[0]:.2f} ms ({embree[1]:.2f})", "gpu", source, [m]),
            Row("OpenCL on an NVIDIA H100, 2 host threads: avalanche phase C ray time, vertex rays only (thesis' goal: "
                "2.27 ms on a GTX 660)",
                f"{vertex[0]:.2f} ms", "gpu", source, [m])]


def run_rows():
    m = meta("run")
    s = read_json("run", "summary.json")
    t = s.get("totals", {})
    for key in ("steps", "wall_seconds", "mean_contacts", "final_kinetic_energy"):
        if key not in t:
            raise ResultError(f"{RESULTS}/run/summary.json: no totals.{key}")
    steps, wall = t["steps"], t["wall_seconds"]
    scene = s.get("scene", {}).get("name", "?")
    source = "run/console.txt"
    return [
        Row(f"`rtcd run` ({scene} scene): wall time",
            f"{steps} steps in {wall:.2f} s ({steps / wall:.1f} steps/s), {s.get('threads', '?')} threads, "
            f"{s.get('backend', '?')}", "run", source, [m]),
        Row(f"`rtcd run` ({scene} scene): contacts per step, mean", f"{t['mean_contacts']:.1f}", "run", source, [m]),
        Row(f"`rtcd run` ({scene} scene): final kinetic energy", f"{t['final_kinetic_energy']:.4g} J",
            "run", source, [m]),
    ]


def python_rows():
    m = meta("python")
    source = "python/overhead.json"
    rows = read_json("python", "overhead.json").get("rows", [])
    by = {(r.get("mode"), r.get("pairs")): r for r in rows}
    for key in (("full", 1), ("iterative", 1), ("full", 64), ("iterative", 64)):
        if key not in by:
            raise ResultError(f"{RESULTS}/{source}: no row for {key[0]} mode, {key[1]} pairs")
    one = "; ".join(f"{mode} {by[(mode, 1)]['overhead_us']:.1f} µs" for mode in ("full", "iterative"))
    many = "; ".join(f"{mode} {by[(mode, 64)]['overhead_percent']:.1f}%" for mode in ("full", "iterative"))
    return [Row("Python `detect()` beyond the C++ call, 1 resting pair (goal < 5 µs)", one, "python", source, [m]),
            Row("Python `detect()` beyond the C++ call, 64 pairs, share of the C++ time (goal ≤ 10%)", many,
                "python", source, [m])]


def view_rows():
    m = meta("view")
    page = read_json("view", "page.json")
    for key in ("folder_bytes", "first_frame_ms"):
        if key not in page:
            raise ResultError(f"{RESULTS}/view/page.json: no {key}")
    return [Row("the default scene's page (`rtcd run --view`): folder size (goal ≤ 32 MB); first frame in headless "
                "Chromium, software WebGL", f"{page['folder_bytes'] / 1e6:.1f} MB; {page['first_frame_ms']:.0f} ms",
                "view", "view/page.json", [m])]


def campaign_rows():
    m = meta("campaign")
    source = "campaign/times.json"
    t = read_json("campaign", "times.json")
    for key in ("pairs", "pairs_per_second", "reports_equal"):
        if key not in t:
            raise ResultError(f"{RESULTS}/{source}: no {key}")
    rate = t["pairs_per_second"]
    if "1" not in rate or "2" not in rate:
        raise ResultError(f"{RESULTS}/{source}: pairs_per_second lacks 1 or 2 ranks")
    same = "reports equal" if t["reports_equal"] else "reports DIFFER"
    return [Row(f"validation campaign, {t['pairs']} concave pairs with the oracles: pairs per second on 1 / 2 MPI ranks",
                f"{rate['1']:.0f} / {rate['2']:.0f} ({rate['2'] / rate['1']:.2f}×; {same})", "campaign", source, [m])]


def judged_rows():
    """The judged replays' verdict over every step, from each replay's "all" row."""
    m = meta("judged")
    rows = []
    for scene, label in (("avalanche", "avalanche"), ("default", "default scene")):
        cells = []
        for suffix, what in (("", "defaults"), ("_certified", "pairs certified apart")):
            source = f"judged/judged_{scene}{suffix}.txt"
            line = next((l for l in read_text("judged", f"judged_{scene}{suffix}.txt").splitlines()
                         if l.startswith("| all |")), None)
            found = line and re.search(r"(\d+): (\d+) of (\d+) deep rays missed, (\d+) false; (\d+) pairs missed; "
                                       r"(\d+) of (\d+) contacts over the truth", line)
            if not found:
                raise ResultError(f"{RESULTS}/{source}: no judged 'all' row")
            steps, missed, deep, false, pairs, over, contacts = found.groups()
            cells.append(f"{what}: {pairs} pairs missed, {missed} of {deep} deep origins, {false} false, "
                         f"{over} of {contacts} contacts over the truth")
        rows.append(Row(f"{label}, every step judged by the exact reference ({steps} steps, 2 threads)",
                        "; ".join(cells), "judged", "judged/README.md", [m]))
    return rows


def all_rows():
    return (run_rows() + avalanche_rows() + stream_rows() + stream_end_rows() + validation_rows() + truth_rows()
            + zoo_rows() + piles_rows() + opencl_rows() + pocl_avalanche_rows() + gpu_rows() + python_rows() + campaign_rows() + judged_rows()
            + view_rows())


# ---------------------------------------------------------------- blocks

def link(target, doc_dir):
    rel = os.path.relpath(os.path.join(ROOT, RESULTS, target), doc_dir)
    return rel.replace(os.sep, "/")


def results_block(doc_dir):
    rows = all_rows()
    refs = {}
    for r in rows:
        refs.setdefault(r.source, f"r{len(refs) + 1}")
    lines = ["| figure | value | source | commit · date |", "|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r.figure} | {r.value} | [{r.source}][{refs[r.source]}] | {r.when} |")
    lines.append("")
    for source, ref in refs.items():
        lines.append(f"[{ref}]: {link(source, doc_dir)}")
    return lines


def folders_block(doc_dir):
    lines = []
    for folder in FOLDERS:
        m = meta(folder)
        lines.append(f"### [{folder}/]({link(folder, doc_dir)}/)")
        lines.append("")
        what = m["experiment"]
        lines.extend(textwrap.wrap(what[0].upper() + what[1:] + ".", 100))
        lines.append("")
        for key in META_KEYS[1:]:
            text = f"- {key}: " + (f"`{m[key]}`" if key == "command" else str(m[key]))
            lines.extend(textwrap.wrap(text, 100, subsequent_indent="  ", break_long_words=False,
                                       break_on_hyphens=False))
        lines.append("")
    return lines[:-1]


def run_console_block(doc_dir):
    """The main job's console output as committed, progress lines elided."""
    command = meta("run")["command"].split(" > ")[0]  # the redirection into console.txt is not shown
    lines = ["```", "$ " + command]
    elided = False
    for line in read_text("run", "console.txt").splitlines():
        if re.match(r"steps \d+/\d+ ", line):  # progress, when not on a terminal
            if not elided:
                lines.append("...")
            elided = True
            continue
        lines.append(line.rstrip())
    return lines + ["```"]


def validation_block(doc_dir):
    """Every family of the validation run, every figure of its JSON."""
    meta("validation")
    full = read_json("validation", "full.json")
    iterative = {s["family"]: s for s in read_json("validation", "iterative.json")}
    lines = ["Full mode, with the oracles (`full.json`):", "",
             "| family | backend | pairs | colliding | deep origins | missed | false | max rel. depth error "
             "| pairs missed / false | only edges cross | pairs under their deepest point "
             "| FCL agreement | FCL blind (contained) | FCL-colliding missed | GIMPACT agreement "
             "| µs per pair: ours / exact / FCL / FCL contacts / GIMPACT |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for s in full:
        t = s["seconds_per_pair"]
        fcl = s["fcl"]
        lines.append(
            f"| {s['family']} | {s['backend']} | {s['pairs']:,} | {100 * s['colliding_fraction']:.1f}% "
            f"| {s['deep_origins']:,} | {100 * s['missed_rate']:.3f}% | {s['false_rays']} "
            f"| {s['depth_error']['max_relative']:.1e} | {s['missed_pairs']} / {s['false_pairs']} "
            f"| {s['crossing_pairs']} | {s['truth'].get('under_reported_pairs', '–')} | {100 * fcl['agreement']:.1f}% "
            f"| {fcl['blind_contained']} of {fcl['contained']} | {fcl['missed_pairs']} "
            f"| {100 * s['gimpact']['agreement']:.1f}% "
            f"| {1e6 * t['ours']:.1f} / {1e6 * t['exact']:.1f} / {1e6 * t['fcl']:.1f} / "
            f"{1e6 * t['fcl_contacts']:.1f} / {1e6 * t['gimpact']:.1f} |")
    ccd = [s for s in full if s["ccd"]["pairs"]]
    if ccd:
        lines.append("")
        lines.append("Convex families, our largest projected depth against libccd's EPA depth: " + "; ".join(
            f"{s['family']} {s['ccd']['mean_ratio']:.3f}× on average over {s['ccd']['pairs']} pairs" for s in ccd) + ".")
    lines += ["", "Iterative mode at the defaults, the exact reference alone (`iterative.json`):", "",
              "| family | backend | deep origins | missed | not tracked | false | pairs missed / false "
              "| pairs under their deepest point | full steps "
              "| µs per pair and step |", "|---|---|---|---|---|---|---|---|---|---|"]
    for name, s in iterative.items():
        lines.append(
            f"| {name} | {s['backend']} | {s['deep_origins']:,} | {100 * s['missed_rate']:.3f}% "
            f"| {s['missed_untracked']} | {s['false_rays']} | {s['missed_pairs']} / {s['false_pairs']} "
            f"| {s['truth'].get('under_reported_pairs', '–')} | {100 * s['full_step_rate']:.1f}% "
            f"| {1e6 * s['seconds_per_pair']['ours']:.1f} |")
    return lines


BLOCKS = {"results": results_block, "folders": folders_block, "run-console": run_console_block,
          "validation": validation_block}


def generate(path):
    """FILE's text with every generated block replaced."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    doc_dir = os.path.dirname(os.path.abspath(path))
    found = False
    for name, make in BLOCKS.items():
        begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
        if begin not in text:
            continue
        if text.count(begin) != 1 or text.count(end) != 1 or text.index(end) < text.index(begin):
            raise ResultError(f"{path}: one '{begin}' before one '{end}' expected")
        found = True
        head, rest = text.split(begin, 1)
        _, tail = rest.split(end, 1)
        text = head + begin + "\n" + "\n".join(make(doc_dir)) + "\n" + end + tail
    if not found:
        raise ResultError(f"{path}: no generated block (<!-- NAME:begin --> for NAME in {', '.join(BLOCKS)})")
    return text


def first_cell(line):
    cells = [c.strip() for c in line.split("|")]
    return cells[1] if line.startswith("|") and len(cells) > 2 else line.strip()


def check(path):
    with open(path, encoding="utf-8") as f:
        have = f.read()
    want = generate(path)
    if have == want:
        print(f"{path}: the generated blocks match the result files")
        return 0
    have_lines, want_lines = have.splitlines(), want.splitlines()
    print(f"{path}: differs from what the result files give "
          f"(run scripts/results_table.py --write {path}):", file=sys.stderr)
    matcher = difflib.SequenceMatcher(a=have_lines, b=want_lines, autojunk=False)
    for op, a0, a1, b0, b1 in matcher.get_opcodes():
        if op == "equal":
            continue
        named = {first_cell(l) for l in have_lines[a0:a1] + want_lines[b0:b1]}
        for name in sorted(named):
            print(f"  row '{name}':", file=sys.stderr)
        for l in have_lines[a0:a1]:
            print(f"    - {l}", file=sys.stderr)
        for l in want_lines[b0:b1]:
            print(f"    + {l}", file=sys.stderr)
    return 1


# ---------------------------------------------------------------- staleness

CODE = ["core", "backends", "sim", "cli", "experiments", "validation", "oracle", "data", "bench", "CMakeLists.txt"]


def stale():
    """Folders whose commit's code differs from HEAD's (informational)."""
    out = 0
    for folder in FOLDERS:
        c = meta(folder)["commit"]
        if not re.fullmatch(r"[0-9a-f]{7,40}", c):
            print(f"{folder}: commit {c}")
            out = 1
            continue
        diff = subprocess.run(["git", "-C", ROOT, "diff", "--stat", c, "HEAD", "--"] + CODE,
                              capture_output=True, text=True)
        if diff.returncode != 0:
            print(f"{folder}: cannot compare {c} with HEAD: {diff.stderr.strip()}")
            out = 1
        elif diff.stdout.strip():
            summary = diff.stdout.strip().splitlines()[-1].strip()
            print(f"{folder}: measured at {c[:7]}; the code has changed since ({summary})")
            out = 1
        else:
            print(f"{folder}: measured at {c[:7]}; the code is the same at HEAD")
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--write", metavar="FILE", nargs="+", help="replace each FILE's generated blocks")
    group.add_argument("--check", metavar="FILE", nargs="+", help="exit 1 where a FILE's blocks differ from the files")
    group.add_argument("--stale", action="store_true", help="folders measured on older code")
    args = parser.parse_args()
    try:
        if args.stale:
            return stale()
        if args.check:
            return max(check(path) for path in args.check)
        if args.write:
            for path in args.write:
                text = generate(path)
                with open(path, "w", encoding="utf-8") as f:
                    f.write(text)
                print(f"wrote {path}")
            return 0
        print("\n".join(results_block(ROOT)))
        return 0
    except ResultError as e:
        print(f"results_table: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
