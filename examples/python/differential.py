"""Differential check of rtcd against its references, from Python.

Random poses of two generated meshes: rtcd's contacts are judged by FCL
(colliding or not) and by the exact double-precision reference (which ray
origins lie deep inside the other body), and a table of agreement is
printed, as the validation suite would.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/differential.py --pairs 200
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import rtcd
from rtcd import oracle

# Pairs of meshes from rtcd.gen, by name.
SHAPES = {
    "blobs": lambda: (rtcd.gen.concave_blob(902, 1), rtcd.gen.concave_blob(902, 2)),
    "blob-sphere": lambda: (rtcd.gen.concave_blob(300, 7), rtcd.gen.icosphere(1.0, 2)),
    "torus-blob": lambda: (rtcd.gen.torus(1.0, 0.35, 48, 24), rtcd.gen.concave_blob(902, 3, 0.7)),
    "boxes": lambda: (rtcd.gen.box([0.5, 0.5, 0.5]), rtcd.gen.box([0.6, 0.3, 0.4])),
    "u-box": lambda: (rtcd.gen.u_shape(), rtcd.gen.box([0.25, 0.25, 0.25])),
}

VERTEX = 0


def random_pose(rng: np.random.Generator, position) -> np.ndarray:
    q = rng.normal(size=4)  # four normal floats, normalised: a uniform rotation
    return np.concatenate([position, q / np.linalg.norm(q)])


def judge_side(contacts: rtcd.Rays, side: int, reference: dict) -> tuple[int, int, int]:
    """(deep, missed, false) for one side's vertex rays against the reference."""
    hit = np.zeros(len(reference["inside"]), dtype=bool)
    hit[contacts.vertex[(contacts.kind == VERTEX) & (contacts.source == side)]] = True
    deep = reference["inside"] & ~reference["near_surface"]
    far_outside = ~reference["inside"] & ~reference["near_surface"]
    return int(deep.sum()), int((deep & ~hit).sum()), int((far_outside & hit).sum())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=200, help="random pairs to judge (default 200)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--backend", default="embree", help="rtcd backend (default embree)")
    parser.add_argument("--mode", default="full", choices=["full", "iterative", "auto"])
    parser.add_argument("--shapes", default="blobs", choices=sorted(SHAPES), help="which pair of meshes")
    args = parser.parse_args()

    a, b = SHAPES[args.shapes]()
    # One narrow phase for the run, two bodies moved from pair to pair (what
    # rtcd.query does for a single pair, without rebuilding the shapes' trees).
    narrow = rtcd.NarrowPhase(args.backend, mode=args.mode)
    body_a, body_b = narrow.add_body(narrow.add_shape(a)), narrow.add_body(narrow.add_shape(b))
    pair = np.array([[body_a, body_b]], dtype=np.uint32)
    # The references are built once per shape, then queried at any pose.
    fcl_a, fcl_b = oracle.Fcl(a), oracle.Fcl(b)
    exact_a, exact_b = oracle.Exact(a), oracle.Exact(b)
    margin = 1e-5 * max(a.radius, b.radius)
    reach = a.radius + b.radius

    rng = np.random.default_rng(args.seed)
    both = neither = rtcd_only = fcl_only = 0
    deep = missed = false = 0
    seconds = {"rtcd": 0.0, "fcl": 0.0, "exact": 0.0}
    for _ in range(args.pairs):
        # B's centre at 0.3 to 1.1 times the sum of the radii from A's: most
        # pairs overlap a little, some a lot, some not at all.
        direction = rng.normal(size=3)
        offset = direction / np.linalg.norm(direction) * reach * rng.uniform(0.3, 1.1)
        pose_a, pose_b = random_pose(rng, np.zeros(3)), random_pose(rng, offset)

        t0 = time.perf_counter()
        narrow.set_poses([body_a, body_b], [pose_a, pose_b])
        mine = narrow.detect(pair)
        t1 = time.perf_counter()
        theirs = fcl_a.collide(pose_a, fcl_b, pose_b)["colliding"]
        t2 = time.perf_counter()
        for side, reference in ((0, exact_b.rays_from(a, pose_a, pose_b, margin)),
                                (1, exact_a.rays_from(b, pose_b, pose_a, margin))):
            d, m, f = judge_side(mine.contacts, side, reference)
            deep, missed, false = deep + d, missed + m, false + f
        t3 = time.perf_counter()
        seconds["rtcd"] += t1 - t0
        seconds["fcl"] += t2 - t1
        seconds["exact"] += t3 - t2

        colliding = bool(mine.pairs.colliding[0])
        both += colliding and theirs
        neither += not colliding and not theirs
        rtcd_only += colliding and not theirs
        fcl_only += theirs and not colliding

    n = max(args.pairs, 1)
    rows = [
        ("pairs", f"{args.pairs}", f"{args.shapes}, backend {args.backend}, mode {args.mode}, seed {args.seed}"),
        ("colliding (both)", f"{both}", f"{both / n:.1%}"),
        ("separated (both)", f"{neither}", f"{neither / n:.1%}"),
        ("rtcd only", f"{rtcd_only}", "touching pairs, or crossings FCL's BVH misses"),
        ("FCL only", f"{fcl_only}", "intersections no ray of rtcd sees"),
        ("FCL agreement", f"{both + neither}", f"{(both + neither) / n:.2%}"),
        ("deep origins", f"{deep}", "ray origins the exact reference puts inside, beyond the margin"),
        ("missed", f"{missed}", f"{missed / max(deep, 1):.3%} of the deep origins"),
        ("false rays", f"{false}", "contacts from origins well outside"),
        ("us per pair", f"{1e6 * seconds['rtcd'] / n:.0f}",
         f"FCL {1e6 * seconds['fcl'] / n:.0f}, exact {1e6 * seconds['exact'] / n:.0f}"),
    ]
    width = max(len(r[0]) for r in rows)
    print(f"{'':{width}}  {'count':>8}  note")
    for name, count, note in rows:
        print(f"{name:{width}}  {count:>8}  {note}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
