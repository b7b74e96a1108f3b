"""The GIL released while a step runs: Python code on another thread keeps
running while a step is in C++. Judged by the CPU time that thread gets
while the steps run, not by the wall clock, so other work on the machine
slows both sides and leaves the verdict alone."""
from __future__ import annotations

import sys
import threading
import time

from conftest import resting_rig


def test_detect_releases_the_gil(blobs, resting_x):
    """Steps repeated for half a second on one thread while a pure-Python
    loop spins on another. The loop needs the GIL: held through detect(),
    the loop runs only between steps (a few microseconds of Python each)
    and gets a small share of the steps' time in CPU; released, it runs
    beside them and gets most of it (less only where other processes take
    the cores)."""
    narrow, pairs = resting_rig(blobs, resting_x, mode="full", copies=64, threads=1)
    narrow.detect(pairs)  # warm up: trees built

    inside = [0.0]
    calls = [0]
    stop = threading.Event()

    def detect_repeatedly():
        deadline = time.perf_counter() + 0.5
        while time.perf_counter() < deadline:
            start = time.perf_counter()
            narrow.detect(pairs)
            inside[0] += time.perf_counter() - start
            calls[0] += 1
        stop.set()

    # A short switch interval: a thread waiting for the GIL gets it soon.
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)
    try:
        worker = threading.Thread(target=detect_repeatedly)
        begin = time.thread_time()
        worker.start()
        while not stop.is_set():
            pass
        loop_cpu = time.thread_time() - begin
        worker.join()
    finally:
        sys.setswitchinterval(old)

    assert calls[0] >= 3 and inside[0] / calls[0] > 1e-3, "each call should take a few ms"
    share = loop_cpu / inside[0]
    # Near 1 on an idle machine when released; a few percent when held.
    assert share > 0.3, f"the loop got {share:.2f} of the steps' time in CPU: the GIL was held through them"


def test_detect_begin_lets_python_run_until_detect_end(blobs, resting_x):
    """detect_begin returns while the step runs on the narrow phase's own
    thread: Python polls detect_done and finds it still running at least
    once over the steps; detect_end returns the same step detect() gives
    a twin narrow phase, and any call in between raises."""
    import numpy as np
    import pytest

    import rtcd

    begun, pairs = resting_rig(blobs, resting_x, mode="full", copies=64, threads=1)
    twin, _ = resting_rig(blobs, resting_x, mode="full", copies=64, threads=1)
    running_polls = 0
    for _ in range(3):
        begun.detect_begin(pairs)
        while not begun.detect_done():
            running_polls += 1
        with pytest.raises(rtcd.UsageError, match="detect_end first"):
            begun.detect(pairs)
        got, expected = begun.detect_end(), twin.detect(pairs)
        assert len(got.contacts) > 0
        for column in ("depth", "vertex", "triangle"):
            assert np.array_equal(got.contacts[column], expected.contacts[column])
    assert running_polls > 0, "each step had ended before Python looked"
    with pytest.raises(rtcd.UsageError, match="no step begun"):
        begun.detect_end()
