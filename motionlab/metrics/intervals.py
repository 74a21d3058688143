r"""Mean ± 95% confidence intervals over repeated sample sets (the ODMO reporting protocol).

A metric computed on one set of generated motions is itself random. Every chapter therefore draws
``n_repeats`` sample sets of a fixed size, computes the metric on each, and reports the mean with the
half-width of a Student-t confidence interval:

.. math:: \bar v \pm t_{(1+c)/2,\;n-1}\, \frac{s}{\sqrt n}, \qquad s^2 = \frac{1}{n-1}\sum_r (v_r - \bar v)^2
.

(ODMO's code uses the normal quantile with :math:`s/\sqrt{n-1}`; with 20 repeats the two differ by a few
per cent. Student's t is the exact interval for normally distributed values.)
"""

from __future__ import annotations

import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from scipy.special import stdtrit

from motionlab.validation import ArrayLike, as_float_array, check_scalar

MetricValue = float | Mapping[str, float]
"""What a repeated metric returns per sample set: one number, or several by name."""


def mean_ci(values: ArrayLike, confidence: float = 0.95) -> tuple[float, float]:
    """``(mean, half_width)`` of the Student-t confidence interval of the mean of ``values`` ``(n,)``, ``n >=
    2``."""
    func = "mean_ci"
    v = as_float_array(values, "values", func, ndim=1, layout="(n,)")
    if v.shape[0] < 2:
        raise ValueError(f"{func}: values needs at least 2 entries for an interval, got {v.shape[0]}")
    level = float(
        check_scalar(
            confidence, "confidence", func, minimum=0, maximum=1, include_minimum=False, include_maximum=False
        )
    )
    n = v.shape[0]
    # Student's t quantile, as scipy.stats.t.ppf computes it (scipy.stats takes half a second to import)
    quantile = stdtrit(n - 1, 0.5 * (1.0 + level))
    return float(v.mean()), float(quantile * v.std(ddof=1) / np.sqrt(n))


@dataclass(frozen=True)
class Interval:
    """A metric over repeated sample sets: ``mean ± half_width`` at ``confidence``, and the raw values."""

    mean: float
    half_width: float
    values: tuple[float, ...]
    confidence: float

    def __str__(self) -> str:
        return f"{self.mean:.4g} ± {self.half_width:.2g}"


def _interval(values: list[float], confidence: float) -> Interval:
    mean, half_width = mean_ci(values, confidence)
    return Interval(mean, half_width, tuple(values), confidence)


def repeat_seed(seed: int, repeat: int) -> int:
    """The 64-bit seed of repeat ``repeat`` under master seed ``seed`` (``numpy.random.SeedSequence``)."""
    return int(np.random.SeedSequence([seed, repeat]).generate_state(1, dtype=np.uint64)[0])


def _number(value: Any, where: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"repeat_metric: {where} returned {type(value).__name__}, not a number") from exc
    if not np.isfinite(number):
        raise ValueError(f"repeat_metric: {where} returned a non-finite value ({number})")
    return number


def repeat_metric(
    fn: Callable[[Any], MetricValue],
    sample_fn: Callable[[torch.Generator], Any],
    n_repeats: int,
    seed: int,
    confidence: float = 0.95,
) -> Interval | dict[str, Interval]:
    """Evaluate ``fn`` on ``n_repeats`` independently drawn sample sets and summarise as mean ± CI.

    Args:
        fn: the metric, ``fn(sample_set) -> float`` or ``-> {name: float}`` (several metrics on the same
            sample set, computed once per repeat).
        sample_fn: draws one sample set of a fixed size, ``sample_fn(generator)``, using the given
            ``torch.Generator`` for all its randomness (seed NumPy from ``generator.initial_seed()``).
        n_repeats: number of sample sets, at least 2.
        seed: master seed; repeat ``r`` uses :func:`repeat_seed` ``(seed, r)``, so results are reproducible
            and repeats are independent.
        confidence: confidence level of the interval.

    Returns:
        An :class:`Interval` when ``fn`` returns a number, else ``{name: Interval}`` in ``fn``'s key order.
    """
    func = "repeat_metric"
    count = int(check_scalar(n_repeats, "n_repeats", func, kind=numbers.Integral, minimum=2))
    master = int(check_scalar(seed, "seed", func, kind=numbers.Integral, minimum=0))
    level = float(
        check_scalar(
            confidence, "confidence", func, minimum=0, maximum=1, include_minimum=False, include_maximum=False
        )
    )
    results = [fn(sample_fn(torch.Generator().manual_seed(repeat_seed(master, r)))) for r in range(count)]
    if not isinstance(results[0], Mapping):
        return _interval([_number(value, f"fn on repeat {r}") for r, value in enumerate(results)], level)
    names = list(results[0])
    for r, result in enumerate(results):
        if not isinstance(result, Mapping) or list(result) != names:
            raise ValueError(
                f"{func}: fn must return the same keys {names} on every repeat (repeat {r} differs)"
            )
    return {
        name: _interval(
            [_number(res[name], f"fn[{name!r}] on repeat {r}") for r, res in enumerate(results)], level
        )
        for name in names
    }
