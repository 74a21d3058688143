"""Synthetic data generation speed: the generator's command line writing 1,008 four-second clips.

The command ``python -m motionlab.data.synthetic --n-per-mode 84`` (12 modes x 84 clips, 120 frames each)
runs as a subprocess pinned to one CPU core with single-threaded BLAS, so the wall time includes process
start-up (importing numpy and torch) and writing the file. :func:`generation_speed` reports the wall time,
clips per second, the subprocess's peak memory, the file size, and the load average while measuring.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from motionlab.data.actions import MODE_NAMES

N_PER_MODE = 84
SECONDS = 4.0


def _pin_to_one_core() -> None:
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


def generation_speed() -> dict:
    """Measure one command-line run; numbers are keyed ``data.*``."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "bench.npz"
        command = [
            sys.executable,
            "-m",
            "motionlab.data.synthetic",
            "--out",
            str(out),
            "--seed",
            "0",
            "--n-per-mode",
            str(N_PER_MODE),
            "--seconds",
            str(SECONDS),
        ]
        load = os.getloadavg()[0]
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True, env=env, preexec_fn=_pin_to_one_core)
        seconds = time.perf_counter() - start
        size = out.stat().st_size
    clips = N_PER_MODE * len(MODE_NAMES)
    return {
        "data.clips": clips,
        "data.clip_seconds": SECONDS,
        "data.cli_wall_seconds": seconds,
        "data.clips_per_second": clips / seconds,
        "data.cli_peak_rss_mb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024,
        "data.file_mb": size / 2**20,
        "data.load_average": load,
    }
