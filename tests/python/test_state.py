"""Pair state from one detect() to the next, determinism across objects and
threads, and the GIL released while a step runs."""
from __future__ import annotations

import sys
import threading
import time

import numpy as np
import pytest

import rtcd
from conftest import pose

FULL, ITERATIVE = 0, 1
NO_PAIRS = np.zeros((0, 2), dtype=np.uint32)


def resting_rig(blobs, x: float, mode: str = "auto", copies: int = 1):
    """`copies` of the resting blob pair, 10 apart along y; returns the
    narrow phase and the (copies, 2) pairs array."""
    narrow = rtcd.NarrowPhase("embree", mode=mode)
    sa, sb = narrow.add_shape(blobs[0]), narrow.add_shape(blobs[1])
    offsets = 10.0 * np.arange(copies)
    a = narrow.add_bodies(sa, [pose((0, y, 0)) for y in offsets])
    b = narrow.add_bodies(sb, [pose((x, y + 0.1, 0.05)) for y in offsets])
    return narrow, np.column_stack([a, b]).astype(np.uint32)


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


def test_detect_releases_the_gil(blobs, resting_x):
    """While one thread runs detect(), a pure-Python loop on another keeps
    counting. With the GIL held through a call, the loop could only advance
    in the moment between two calls; released, it advances during the call."""
    # 64 copies of the resting pair, more on a machine fast enough to trace
    # them in under 3 ms: a call must be long against a thread switch.
    copies = 64
    while True:
        narrow, pairs = resting_rig(blobs, resting_x, mode="full", copies=copies)
        narrow.detect(pairs)  # warm up: shapes' trees built, threads started
        start = time.perf_counter()
        narrow.detect(pairs)
        if time.perf_counter() - start > 3e-3 or copies >= 1024:
            break
        copies *= 4

    counter = [0]
    calls: list[tuple[float, float, int, int]] = []  # (t0, t1, counter at t0, at t1)
    stop = threading.Event()

    def count_until(flag: threading.Event):
        while not flag.is_set():
            counter[0] += 1

    def detect_repeatedly():
        deadline = time.perf_counter() + 0.5
        while time.perf_counter() < deadline:
            c0, t0 = counter[0], time.perf_counter()
            narrow.detect(pairs)
            t1, c1 = time.perf_counter(), counter[0]
            calls.append((t0, t1, c0, c1))
        stop.set()

    # A short switch interval: with the GIL held through a call, the loop
    # would get only a sliver of time after each call returns.
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)
    try:
        # The loop's own pace, alone (a timer thread ends it).
        alone = threading.Event()
        timer = threading.Timer(0.05, alone.set)
        start = time.perf_counter()
        timer.start()
        count_until(alone)
        solo_rate = counter[0] / (time.perf_counter() - start)
        timer.join()

        worker = threading.Thread(target=detect_repeatedly)
        worker.start()
        count_until(stop)
        worker.join()
    finally:
        sys.setswitchinterval(old)

    assert len(calls) >= 3, "each call should take a few ms"
    assert counter[0] > 0
    # The loop advanced during calls: by a good share of its solo pace over
    # a whole call, which a sliver after the call's return cannot give.
    shares = [(c1 - c0) / (solo_rate * (t1 - t0)) for t0, t1, c0, c1 in calls if t1 - t0 > 2e-3]
    assert shares, "no call lasted 2 ms"
    assert any(c1 > c0 for _, _, c0, c1 in calls)
    # Held, the best share over calls of 2 ms or more stays under 0.15.
    assert max(shares) > 0.3, f"the loop hardly ran during detect(): best share {max(shares):.3f}"
