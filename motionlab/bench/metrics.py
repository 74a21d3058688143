"""Metric timings: FID on two 2000 x 30 feature sets and APD on 50 sampled 4-second clips of the default
skeleton."""

from __future__ import annotations

import numpy as np

from motionlab import config
from motionlab.bench._timing import best_seconds
from motionlab.metrics import apd, fid


def metric_timings() -> dict:
    config.set_threads()
    rng = np.random.default_rng(0)
    real, generated = rng.normal(size=(2000, 30)), rng.normal(size=(2000, 30)) + 0.1
    clips = rng.normal(size=(50, 120, 22 * 3))  # 50 samples of 4 s at 30 fps
    return {
        "fid_2000x30_seconds": best_seconds(lambda: fid(real, generated)),
        "apd_50x120x66_seconds": best_seconds(lambda: apd(clips)),
    }
