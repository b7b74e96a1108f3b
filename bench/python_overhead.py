#!/usr/bin/python3
"""What calling detect() from Python costs beyond the C++ call.

The benchmarks' steady contact (bench/narrow_phase_bench.cpp): copies of
two 902-triangle concave blobs resting in a shallow overlap, B jittering by
1e-3 each step, Embree, full and iterative mode, 1 and 64 pairs. One
iteration is what the C++ benchmark times: every B posed, then detect().
Python's time (set_poses + detect; and again with every contact column
read) minus rtcd_bench's for the same case run just before it: the median
over rounds of that difference, and its share of the median C++ time.

  PYTHONPATH=build/release/python /usr/bin/python3 bench/python_overhead.py \\
      --bench build/release/bench/rtcd_bench --out docs/results/python
"""
import argparse
import json
import os
import platform
import statistics
import subprocess
import time

import numpy as np

import rtcd

CASES = [("full", "full_embree"), ("iterative", "iterative")]
COUNTS = [1, 64]


def resting_offset(a, b):
    """B's x offset where the pair first has 20 contacts (bench_scene.hpp)."""
    narrow = rtcd.NarrowPhase("embree")
    sa, sb = narrow.add_shape(a), narrow.add_shape(b)
    pair = np.array([[narrow.add_body(sa), narrow.add_body(sb, [3.0, 0.1, 0.05, 1, 0, 0, 0])]], dtype=np.uint32)
    x = 3.0
    while x > 0.5:
        narrow.set_pose(int(pair[0, 1]), [x, 0.1, 0.05, 1, 0, 0, 0])
        if len(narrow.detect(pair).contacts) >= 20:
            return x
        x -= 0.005
    raise RuntimeError("the blobs never reached 20 contacts")


def python_time(a, b, offset, mode, count, seconds, read_arrays):
    """Seconds per iteration: the median of five timed runs."""
    narrow = rtcd.NarrowPhase("embree", mode=mode)
    sa, sb = narrow.add_shape(a), narrow.add_shape(b)
    a_poses = np.zeros((count, 7))
    a_poses[:, 0] = 10.0 * np.arange(count)
    a_poses[:, 3] = 1.0
    b_poses = a_poses.copy()
    b_poses[:, :3] += [offset, 0.1, 0.05]
    ids_a = narrow.add_bodies(sa, a_poses)
    ids_b = narrow.add_bodies(sb, b_poses)
    pairs = np.stack([ids_a, ids_b], axis=1)
    jittered = b_poses.copy()
    jittered[:, 1] += 1e-3
    narrow.detect(pairs)  # the first, full step

    def iterations(n):
        start = time.perf_counter()
        for i in range(n):
            narrow.set_poses(ids_b, jittered if i % 2 else b_poses)
            r = narrow.detect(pairs)
            if read_arrays:
                r.contacts.depth  # builds every column
        return (time.perf_counter() - start) / n

    n = 10
    while iterations(n) * n < 0.2:
        n *= 2
    n = max(n, int(seconds / iterations(n)))
    return statistics.median(iterations(n) for _ in range(5))


def cpp_time(bench, name, seconds):
    """rtcd_bench's real time per iteration of one case, in seconds."""
    out = subprocess.run([bench, f"--benchmark_filter=^{name}$", "--benchmark_format=json",
                          f"--benchmark_min_time={seconds}"], check=True, capture_output=True, text=True).stdout
    report = json.loads(out[out.index("{"):])  # after the line naming the backends
    (b,) = report["benchmarks"]
    return b["real_time"] * 1e-6  # reported in microseconds


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bench", default="build/release/bench/rtcd_bench")
    p.add_argument("--rounds", type=int, default=3, help="interleaved rounds of C++ then Python")
    p.add_argument("--seconds", type=float, default=1.0, help="time per case and round")
    p.add_argument("--out", help="folder for overhead.json and overhead.md")
    args = p.parse_args()

    a, b = rtcd.gen.concave_blob(902, 1), rtcd.gen.concave_blob(902, 2)
    offset = resting_offset(a, b)
    runs = {}
    # Each case's C++ and Python runs back to back, round after round: this
    # VM's speed drifts over minutes, and a difference of two runs far apart
    # would measure the drift.
    for _ in range(args.rounds):
        for mode, case in CASES:
            for count in COUNTS:
                r = runs.setdefault(f"{case}/{count}", {"mode": mode, "pairs": count, "cpp": [], "python": [],
                                                        "python_arrays": []})
                r["cpp"].append(cpp_time(args.bench, f"{case}/{count}", args.seconds))
                r["python"].append(python_time(a, b, offset, mode, count, args.seconds, False))
                r["python_arrays"].append(python_time(a, b, offset, mode, count, args.seconds, True))

    rows = []
    for name, r in runs.items():
        cpp = statistics.median(r["cpp"])
        # The median over rounds of each round's difference.
        over = statistics.median(p - c for p, c in zip(r["python"], r["cpp"]))
        over_arrays = statistics.median(p - c for p, c in zip(r["python_arrays"], r["cpp"]))
        rows.append({"case": name, "mode": r["mode"], "pairs": r["pairs"], "cpp_us": 1e6 * cpp,
                     "python_us": 1e6 * statistics.median(r["python"]), "overhead_us": 1e6 * over,
                     "overhead_percent": 100 * over / cpp,
                     "python_with_arrays_us": 1e6 * statistics.median(r["python_arrays"]),
                     "arrays_overhead_us": 1e6 * over_arrays, "runs": r})
    lines = ["| mode | pairs | C++ µs | Python µs | overhead µs | overhead % | Python + arrays µs | overhead µs |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['mode']} | {r['pairs']} | {r['cpp_us']:.1f} | {r['python_us']:.1f} | "
                     f"{r['overhead_us']:.1f} | {r['overhead_percent']:.1f}% | {r['python_with_arrays_us']:.1f} | "
                     f"{r['arrays_overhead_us']:.1f} |")
    table = "\n".join(lines)
    print(table)
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, "overhead.json"), "w") as f:
            json.dump({"offset": offset, "rounds": args.rounds, "seconds": args.seconds,
                       "machine": platform.processor() or platform.machine(), "rows": rows}, f, indent=2)
        with open(os.path.join(args.out, "overhead.md"), "w") as f:
            f.write(table + "\n")


if __name__ == "__main__":
    main()
