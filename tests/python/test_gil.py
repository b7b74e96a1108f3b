"""The GIL released while a step runs: a step and Python code on another
thread overlap in time. It measures the wall time, so ctest runs it alone
(RUN_SERIAL): other tests on the same cores would take the time it counts."""
from __future__ import annotations

import sys
import threading
import time

from conftest import resting_rig


def test_detect_releases_the_gil(blobs, resting_x):
    """A step on one core while a pure-Python loop counts on the other. The
    loop needs the GIL: held through detect(), the loop's time and the
    steps' time could not overlap and would add up to the wall time at
    most; released, they overlap (on two cores, nearly the whole time).
    Overlap, not speed-up, is what is shown."""
    narrow, pairs = resting_rig(blobs, resting_x, mode="full", copies=64, threads=1)
    narrow.detect(pairs)  # warm up: trees built

    def step_seconds(calls=5):
        times = []
        for _ in range(calls):
            start = time.perf_counter()
            narrow.detect(pairs)
            times.append(time.perf_counter() - start)
        return sorted(times)[calls // 2]

    counter = [0]

    def count_until(flag: threading.Event):
        while not flag.is_set():
            counter[0] += 1

    def counted_seconds(seconds):
        """The loop's pace alone: counts per second over `seconds`."""
        counter[0] = 0
        alone = threading.Event()
        timer = threading.Timer(seconds, alone.set)
        start = time.perf_counter()
        timer.start()
        count_until(alone)
        timer.join()
        return counter[0] / (time.perf_counter() - start)

    solo_rate = max(counted_seconds(0.05) for _ in range(3))
    step = step_seconds()

    calls = [0]
    stop = threading.Event()

    def detect_repeatedly():
        deadline = time.perf_counter() + 0.5
        while time.perf_counter() < deadline:
            narrow.detect(pairs)
            calls[0] += 1
        stop.set()

    # A short switch interval: a thread waiting for the GIL gets it soon.
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)
    try:
        counter[0] = 0
        start = time.perf_counter()
        worker = threading.Thread(target=detect_repeatedly)
        worker.start()
        count_until(stop)
        worker.join()
        wall = time.perf_counter() - start
    finally:
        sys.setswitchinterval(old)

    assert calls[0] >= 3, "each call should take a few ms"
    busy = (counter[0] / solo_rate + calls[0] * step) / wall
    # About 1 at most with the GIL held through the steps; near 2 released.
    assert busy > 1.4, f"the loop and the steps did not overlap: {busy:.2f} of the wall time busy"
