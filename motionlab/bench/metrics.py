"""Metric timings: FID on two 2000 x 30 feature sets and APD on 50 sampled 4-second clips of the default skeleton."""

from __future__ import annotations

import time
from typing import Callable

import numpy as np

from motionlab import config
from motionlab.metrics import apd, fid

REPEATS = 5


def _best_seconds(call: Callable[[], float]) -> float:
    """Fastest of :data:`REPEATS` runs (the least disturbed by other processes)."""
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return min(times)


def run() -> dict:
    config.set_threads()
    rng = np.random.default_rng(0)
    real, generated = rng.normal(size=(2000, 30)), rng.normal(size=(2000, 30)) + 0.1
    clips = rng.normal(size=(50, 120, 22 * 3))  # 50 samples of 4 s at 30 fps
    return {
        "fid_2000x30_seconds": _best_seconds(lambda: fid(real, generated)),
        "apd_50x120x66_seconds": _best_seconds(lambda: apd(clips)),
    }
