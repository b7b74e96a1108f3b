"""Shared fixtures and helpers of the rtcd Python tests.

Run with the freshly built package on the path:

    PYTHONPATH=build/release/python /usr/bin/python3 -m pytest tests/python

RTCD_DATA names the data folder (meshes/, scenes/, defects/) and RTCD_CLI the
command-line binary; both fall back to this checkout's own.
"""
from __future__ import annotations

import functools
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import rtcd

REPO = Path(__file__).resolve().parents[2]

# [tx, ty, tz, qw, qx, qy, qz], the package's pose order.
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])


def data_root() -> Path:
    env = os.environ.get("RTCD_DATA")
    return Path(env) if env else REPO / "data"


def cli_path() -> Path:
    env = os.environ.get("RTCD_CLI")
    return Path(env) if env else REPO / "build" / "release" / "bin" / "rtcd"


def cli_error(*args: str) -> str:
    """The message the CLI prints for a failing command, without "rtcd: "."""
    done = subprocess.run([str(cli_path()), *args], capture_output=True, text=True, timeout=60)
    assert done.returncode != 0, f"rtcd {' '.join(args)} succeeded: {done.stdout[-500:]}"
    # Warnings ("rtcd: warning: ...") may precede the error line.
    lines = [l for l in done.stderr.splitlines() if l.startswith("rtcd: ") and not l.startswith("rtcd: warning:")]
    assert lines, f"no error line in: {done.stderr!r}"
    return lines[-1][len("rtcd: "):]


def pose(t=(0.0, 0.0, 0.0), q=(1.0, 0.0, 0.0, 0.0)) -> np.ndarray:
    return np.array([*t, *q], dtype=np.float64)


def rotation_matrix(q) -> np.ndarray:
    """The rotation of the unit quaternion q = (w, x, y, z) (normalised here)."""
    w, x, y, z = np.asarray(q, dtype=np.float64) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def transform(p, points) -> np.ndarray:
    """Points (n, 3) of a body's local frame in the world, the body at pose p."""
    p = np.asarray(p, dtype=np.float64)
    return np.asarray(points, dtype=np.float64) @ rotation_matrix(p[3:]).T + p[:3]


def random_quaternion(rng: np.random.Generator) -> np.ndarray:
    """A uniformly random rotation: four normal floats, normalised."""
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


@functools.lru_cache(maxsize=None)
def blob_pair() -> tuple[rtcd.Mesh, rtcd.Mesh]:
    """The benchmarks' two 902-triangle concave blobs (meshes are immutable: shared)."""
    return rtcd.gen.concave_blob(902, 1), rtcd.gen.concave_blob(902, 2)


@functools.lru_cache(maxsize=None)
def resting_offset() -> float:
    """x of blob B at (x, 0.1, 0.05) resting in a shallow overlap with blob A at the origin.

    As bench/bench_scene.hpp finds it: slide B toward A from x = 3 in steps of
    0.005 until the pair has at least 20 contacts.
    """
    a, b = blob_pair()
    narrow = rtcd.NarrowPhase("embree")
    sa, sb = narrow.add_shape(a), narrow.add_shape(b)
    pair = np.array([[narrow.add_body(sa), narrow.add_body(sb, IDENTITY)]], dtype=np.uint32)
    x = 3.0
    while x > 0.5:
        narrow.set_pose(int(pair[0, 1]), pose((x, 0.1, 0.05)))
        if len(narrow.detect(pair).contacts) >= 20:
            return x
        x -= 0.005  # accumulated as the C++ helper does, so the two agree
    raise AssertionError("the blobs never reached 20 contacts")


@pytest.fixture(scope="session")
def data_dir() -> Path:
    root = data_root()
    assert (root / "meshes").is_dir(), f"no meshes under {root} (set RTCD_DATA)"
    return root


@pytest.fixture(scope="session")
def meshes_dir(data_dir: Path) -> Path:
    return data_dir / "meshes"


@pytest.fixture(scope="session")
def scenes_dir(data_dir: Path) -> Path:
    return data_dir / "scenes"


@pytest.fixture(scope="session")
def cli() -> Path:
    path = cli_path()
    assert path.is_file(), f"no rtcd binary at {path} (set RTCD_CLI)"
    return path


@pytest.fixture(scope="session")
def blobs() -> tuple[rtcd.Mesh, rtcd.Mesh]:
    return blob_pair()


@pytest.fixture(scope="session")
def resting_x() -> float:
    return resting_offset()


def resting_rig(blobs, x: float, mode: str = "auto", copies: int = 1, threads: int = 0):
    """`copies` of the resting blob pair, 10 apart along y; returns the
    narrow phase and the (copies, 2) pairs array."""
    narrow = rtcd.NarrowPhase("embree", mode=mode, threads=threads)
    sa, sb = narrow.add_shape(blobs[0]), narrow.add_shape(blobs[1])
    offsets = 10.0 * np.arange(copies)
    a = narrow.add_bodies(sa, [pose((0, y, 0)) for y in offsets])
    b = narrow.add_bodies(sb, [pose((x, y + 0.1, 0.05)) for y in offsets])
    return narrow, np.column_stack([a, b]).astype(np.uint32)
