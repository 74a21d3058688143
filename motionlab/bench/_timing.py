"""Shared timing helpers for the generator benchmarks (real-time factor, batched throughput)."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any

import torch


def best_seconds(call: Callable[[], Any], repeats: int = 5) -> float:
    """Fastest of ``repeats`` runs of ``call()`` (the one least disturbed by other processes)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return min(times)


def median_seconds(fn: Callable[[], Any], repeats: int = 5, warmup: int = 1) -> float:
    """Median wall time of ``fn()`` over ``repeats`` calls after ``warmup`` untimed ones (no autograd)."""
    with torch.inference_mode():
        for _ in range(warmup):
            fn()
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            fn()
            times.append(time.perf_counter() - start)
    return statistics.median(times)


def generator_speed(
    generate: Callable[[int], Any], n_frames: int, fps: int, large_batch: int = 256, repeats: int = 5
) -> dict[str, float]:
    """Speed of a motion generator ``generate(batch_size)`` that makes ``n_frames`` frames per clip.

    Returns ``rtf_b1_1thread`` (seconds of motion per second of compute, one clip, one thread),
    ``seconds_b1`` and ``frames_per_second_batched`` (frames per second at ``large_batch`` clips).
    The caller sets the thread count (the course default is one thread).
    """
    if torch.get_num_threads() != 1:
        raise RuntimeError("generator_speed: set torch to one thread first (motionlab.config.set_threads(1))")
    seconds_b1 = median_seconds(lambda: generate(1), repeats)
    seconds_batched = median_seconds(lambda: generate(large_batch), max(2, repeats // 2))
    return {
        "rtf_b1_1thread": (n_frames / fps) / seconds_b1,
        "seconds_b1": seconds_b1,
        "frames_per_second_batched": large_batch * n_frames / seconds_batched,
        "large_batch": float(large_batch),
    }
