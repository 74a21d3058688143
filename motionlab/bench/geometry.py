"""Speed of the rotation kernels on one thread: quaternions to matrices, and geodesic distances.

For each kernel on ``n_items`` rotations (float32, 10⁶ by default): items per second and the effective
memory bandwidth, i.e. the bytes the kernel cannot avoid moving (its inputs read once plus its output
written once) per second. As a reference, a plain memory copy (``torch.clone``) of a buffer half that
size moves the same number of bytes (read + write); ``fraction_of_copy_bandwidth`` is the kernel's
bandwidth over the copy's: 1.0 would mean the kernel is as fast as just moving its data, i.e. memory
bound. Both include allocating their output, as real use does. Kernel and copy are timed alternately
(so background load on the shared machine hits both alike); each reported time is the median.

Eager PyTorch writes every intermediate of a formula to memory, so the eager kernels reach only a fraction
of the copy bandwidth. ``pipeline.compiled`` runs the whole pipeline (quaternions to matrices plus their
geodesic distances) through ``torch.compile``, which fuses it into one pass over memory: that is the
memory-bound speed the same code reaches when fused (compile time reported separately).
"""

from __future__ import annotations

import os
import statistics
import time
from collections.abc import Callable

import torch

from motionlab import config
from motionlab.geometry import matrix_geodesic, quat_geodesic, quat_to_matrix

FLOAT_BYTES = 4  # float32


def _median_seconds(
    fn: Callable[[], object], reference: Callable[[], object], repeats: int
) -> tuple[float, float]:
    """Median wall-clock seconds of ``fn`` and of ``reference``, timed alternately after one warm-up each."""
    fn(), reference()
    times: dict[str, list[float]] = {"fn": [], "reference": []}
    for _ in range(repeats):
        for key, call in (("fn", fn), ("reference", reference)):
            start = time.perf_counter()
            call()
            times[key].append(time.perf_counter() - start)
    return statistics.median(times["fn"]), statistics.median(times["reference"])


def kernel_speed(n_items: int = 1_000_000, repeats: int = 7, include_compiled: bool = True) -> dict:
    """Measure the kernels on ``n_items`` random rotations; return a flat dictionary of numbers.

    With ``include_compiled`` (the benchmark's default) the ``pipeline.*`` entries also compare eager with
    ``torch.compile`` (compiling takes about half a minute, so the unit test leaves it out).
    """
    threads = config.set_threads(1)
    gen = torch.Generator().manual_seed(0)
    q1 = torch.randn(n_items, 4, generator=gen)
    q2 = torch.randn(n_items, 4, generator=gen)
    q1, q2 = q1 / q1.norm(dim=-1, keepdim=True), q2 / q2.norm(dim=-1, keepdim=True)
    m1, m2 = quat_to_matrix(q1), quat_to_matrix(q2)
    # name: (kernel, floats read per item, floats written per item)
    kernels = {
        "quat_to_matrix": (lambda: quat_to_matrix(q1), 4, 9),
        "quat_geodesic": (lambda: quat_geodesic(q1, q2), 8, 1),
        "matrix_geodesic": (lambda: matrix_geodesic(m1, m2), 18, 1),
    }
    result: dict = {"n_items": n_items, "threads": threads, "dtype": "float32", "repeats": repeats}
    for name, (kernel, floats_in, floats_out) in kernels.items():
        traffic = n_items * (floats_in + floats_out) * FLOAT_BYTES
        buffer = torch.rand(traffic // (2 * FLOAT_BYTES), generator=gen)  # a clone reads and writes it once
        seconds, copy_seconds = _median_seconds(kernel, buffer.clone, repeats)
        result[f"{name}.seconds"] = seconds
        result[f"{name}.items_per_s"] = n_items / seconds
        result[f"{name}.bytes_per_s"] = traffic / seconds
        result[f"{name}.copy_bytes_per_s"] = traffic / copy_seconds
        result[f"{name}.fraction_of_copy_bandwidth"] = copy_seconds / seconds

    def pipeline(a: torch.Tensor, b: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return quat_to_matrix(a), quat_geodesic(a, b)

    variants = {"eager": pipeline}
    if include_compiled:
        start = time.perf_counter()
        variants["compiled"] = torch.compile(pipeline)
        variants["compiled"](q1, q2)
        result["pipeline.compile_seconds"] = time.perf_counter() - start
    traffic = n_items * (8 + 9 + 1) * FLOAT_BYTES
    buffer = torch.rand(traffic // (2 * FLOAT_BYTES), generator=gen)
    for name, fn in variants.items():
        seconds, copy_seconds = _median_seconds(lambda fn=fn: fn(q1, q2), buffer.clone, repeats)
        result[f"pipeline.{name}.items_per_s"] = n_items / seconds
        result[f"pipeline.{name}.bytes_per_s"] = traffic / seconds
        result[f"pipeline.{name}.fraction_of_copy_bandwidth"] = copy_seconds / seconds
    result["load_average_1min"] = os.getloadavg()[0]
    return result
