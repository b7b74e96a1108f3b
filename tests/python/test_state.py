"""Pair state from one detect() to the next, and determinism across objects
and threads."""
from __future__ import annotations

import threading

import numpy as np
import pytest

import rtcd
from conftest import pose, resting_rig

FULL, ITERATIVE = 0, 1
NO_PAIRS = np.zeros((0, 2), dtype=np.uint32)


def columns(r: rtcd.StepResult) -> dict[str, np.ndarray]:
    """Every array of a step (its timings left out: they differ run to run)."""
    out = {f"pairs.{k}": np.asarray(r.pairs[k]) for k in r.pairs.keys()}
    out.update({f"rays.{k}": np.asarray(r.rays[k]) for k in r.rays.keys()})
    return out


def assert_same_steps(got: list[dict], want: list[dict]):
    assert len(got) == len(want)
    for step, (g, w) in enumerate(zip(got, want)):
        assert g.keys() == w.keys()
        for key in w:
            assert g[key].dtype == w[key].dtype, (step, key)
            np.testing.assert_array_equal(g[key], w[key], err_msg=f"step {step}, {key}")


def five_steps(blobs, x: float) -> list[dict]:
    """B sliding and turning a little on A: full, then walking steps."""
    narrow, pairs = resting_rig(blobs, x)
    out = []
    for k in range(5):
        angle = 0.01 * k
        narrow.set_pose(int(pairs[0, 1]), pose((x - 0.003 * k, 0.1 + 0.002 * k, 0.05),
                                               (np.cos(angle / 2), 0, 0, np.sin(angle / 2))))
        out.append(columns(narrow.detect(pairs)))
    return out


def test_pair_state_across_calls(blobs, resting_x):
    narrow, pairs = resting_rig(blobs, resting_x)
    b = int(pairs[0, 1])
    first = narrow.detect(pairs)
    assert first.pairs.mode[0] == FULL, "a new pair is traced in full"
    assert len(first.contacts) >= 20
    narrow.set_pose(b, pose((resting_x, 0.1 + 1e-3, 0.05)))
    second = narrow.detect(pairs)
    assert second.pairs.mode[0] == ITERATIVE, "a small motion walks"
    assert second.stats["pairs_iterative"] == 1
    assert len(second.contacts) >= 20
    # A step without the pair evicts its state: it starts over in full.
    empty = narrow.detect(NO_PAIRS)
    assert len(empty.pairs) == 0 and len(empty.contacts) == 0
    third = narrow.detect(pairs)
    assert third.pairs.mode[0] == FULL
    assert third.stats["pairs_full"] == 1


def test_same_steps_from_a_fresh_narrow_phase(blobs, resting_x):
    first, second = five_steps(blobs, resting_x), five_steps(blobs, resting_x)
    modes = [int(step["pairs.mode"][0]) for step in first]
    assert modes[0] == FULL and ITERATIVE in modes, modes
    assert sum(len(step["rays.depth"]) for step in first) > 50
    assert_same_steps(second, first)


def test_removed_body_is_unknown(blobs, resting_x):
    narrow, pairs = resting_rig(blobs, resting_x)
    narrow.detect(pairs)
    narrow.remove_body(int(pairs[0, 0]))
    with pytest.raises(rtcd.UsageError, match=f"body {int(pairs[0, 0])}"):
        narrow.detect(pairs)


def test_same_steps_on_four_threads(blobs, resting_x):
    serial = five_steps(blobs, resting_x)
    results: list = [None] * 4
    errors: list = []

    def work(i: int):
        try:
            results[i] = five_steps(blobs, resting_x)
        except BaseException as e:  # reported by the main thread
            errors.append(e)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert not errors, errors
    for r in results:
        assert r is not None
        assert_same_steps(r, serial)
