"""Coefficient schedules: a loss weight, a teacher-forcing ratio or a drop probability as a function of the
step.

Every schedule is a small frozen dataclass, validated when built, called with the 0-based optimiser step::

    beta = KLAnneal(max_value=1.0, warmup=1000, anneal=2000)
    beta(0), beta(1000), beta(2000), beta(3000)     # 0.0, 0.0, 0.5, 1.0

All of them are piecewise linear in the step, held constant before the first and after the last breakpoint:

* :class:`Constant` -- one value throughout.
* :class:`LinearRamp` -- ``begin`` until ``start``, linear to ``end`` over ``length`` steps, then ``end``.
  Loss weights switched on after a given step (``begin=0``), ODMO's decaying teacher forcing
  (``begin=1.0, end=0.3``), scheduled motion-word dropping (``begin=0.0, end=p``).
* :class:`KLAnneal` -- the KL weight of a VAE: warm-up, anneal, hold, and an optional cool-down.
* :class:`PiecewiseLinear` -- any list of breakpoints, for everything else.

The training loop stores a schedule's class name and fields in the hash of a training run, so two
schedules that differ in any argument never share a cached model.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from motionlab.validation import Checked, check_scalar, integer, real

#: The types a schedule's numbers may have: plain Python numbers, since a schedule's fields go into the cache
#: key of a training run (JSON).
_NUMBER = (int, float)


@runtime_checkable
class Schedule(Protocol):
    """Anything that maps a 0-based step to a float. The course's schedules are frozen dataclasses."""

    def __call__(self, step: int) -> float: ...


def _interpolate(points: tuple[tuple[int, float], ...], step: int, owner: str) -> float:
    """Piecewise-linear value at ``step`` through ``points`` (steps non-decreasing; equal steps mean a jump).

    Before the first point: the first value. At or after the last: the last value. At a jump (two points
    with the same step) the later point's value applies from that step on. ``owner`` names the schedule in
    the error for a bad ``step``.
    """
    check_scalar(step, "step", owner, kind=numbers.Integral, minimum=0)
    last_reached = -1
    for index, (at, _) in enumerate(points):
        if at <= step:
            last_reached = index
    if last_reached == -1:
        return float(points[0][1])
    if last_reached == len(points) - 1:
        return float(points[-1][1])
    (s0, v0), (s1, v1) = points[last_reached], points[last_reached + 1]
    return float(v0 + (v1 - v0) * (step - s0) / (s1 - s0))


@dataclass(frozen=True)
class PiecewiseLinear:
    """Linear between breakpoints ``((step, value), ...)``, constant outside them.

    Steps must be non-decreasing; two points at the same step make a jump (the second value applies
    from that step on). At most two points may share a step.
    """

    points: tuple[tuple[int, float], ...]

    def __post_init__(self) -> None:
        try:
            points = tuple((at, value) for at, value in self.points)
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"PiecewiseLinear.points must be (step, value) pairs, got {self.points!r}"
            ) from exc
        if not points:
            raise ValueError("PiecewiseLinear.points must not be empty")
        for index, (at, value) in enumerate(points):
            check_scalar(at, f"points[{index}] step", "PiecewiseLinear", kind=int, minimum=0)
            check_scalar(value, f"points[{index}] value", "PiecewiseLinear", kind=_NUMBER)
        for index in range(1, len(points)):
            if points[index][0] < points[index - 1][0]:
                raise ValueError(
                    f"PiecewiseLinear.points steps must be non-decreasing, point {index} goes back"
                )
            if index >= 2 and points[index][0] == points[index - 2][0]:
                raise ValueError(f"PiecewiseLinear.points: more than two points at step {points[index][0]}")
        object.__setattr__(self, "points", tuple((at, float(value)) for at, value in points))

    def __call__(self, step: int) -> float:
        return _interpolate(self.points, step, "PiecewiseLinear")


@dataclass(frozen=True)
class Constant(Checked):
    """The same value at every step."""

    value: float = real(kind=_NUMBER)

    def __call__(self, step: int) -> float:
        check_scalar(step, "step", "Constant", kind=numbers.Integral, minimum=0)
        return float(self.value)


@dataclass(frozen=True)
class LinearRamp(Checked):
    """``begin`` for ``step < start``; linear to ``end`` at ``start + length``; ``end`` afterwards.

    ``length=0`` is a switch: ``end`` from ``start`` on. Rising or falling both work, e.g. a loss weight
    that starts after step 500 (``LinearRamp(500, 1000, 0.0, 0.1)``) or ODMO's teacher forcing
    decaying from 1 to 0.3 (``LinearRamp(0, 5000, 1.0, 0.3)``).
    """

    start: int = integer(minimum=0, kind=int)
    length: int = integer(minimum=0, kind=int)
    begin: float = real(kind=_NUMBER)
    end: float = real(kind=_NUMBER)

    def __call__(self, step: int) -> float:
        return _interpolate(
            ((self.start, self.begin), (self.start + self.length, self.end)), step, "LinearRamp"
        )


@dataclass(frozen=True)
class KLAnneal(Checked):
    """KL weight: 0 during warm-up, linear ramp to ``max_value`` during anneal, hold; optional cool-down.

    With ``W = warmup``, ``A = anneal``, ``C = cooldown_start``, ``D = cooldown`` and ``m = max_value``::

        beta(s) = 0                                   s < W
                = m * (s - W) / A                     W <= s < W + A
                = m                                   W + A <= s < C      (hold)
                = m + (c - m) * (s - C) / D           C <= s < C + D      (cool-down)
                = c                                   s >= C + D

    where ``c = cooldown_value`` (``0 <= c <= m``). Without ``cooldown_start`` the hold lasts forever.
    ``A = 0`` or ``D = 0`` make the change a jump at ``W`` or ``C``. The cool-down lowers the weight at the
    end of training so the last steps favour reconstruction; it must start after the anneal ends.
    """

    max_value: float = real(minimum=0, kind=_NUMBER)
    warmup: int = integer(minimum=0, kind=int)
    anneal: int = integer(minimum=0, kind=int)
    cooldown_start: int | None = integer(None, minimum=0, kind=int, optional=True)
    cooldown: int = integer(0, minimum=0, kind=int)
    cooldown_value: float = real(0.0, minimum=0, kind=_NUMBER)

    def __post_init__(self) -> None:
        super().__post_init__()
        check_scalar(self.cooldown_value, "cooldown_value", "KLAnneal", minimum=0, maximum=self.max_value)
        if self.cooldown_start is not None and self.cooldown_start < self.warmup + self.anneal:
            raise ValueError(
                f"KLAnneal.cooldown_start ({self.cooldown_start}) must be >= warmup + anneal "
                f"({self.warmup + self.anneal})"
            )

    def __call__(self, step: int) -> float:
        points: tuple[tuple[int, float], ...] = (
            (self.warmup, 0.0),
            (self.warmup + self.anneal, self.max_value),
        )
        if self.cooldown_start is not None:
            points += (
                (self.cooldown_start, self.max_value),
                (self.cooldown_start + self.cooldown, self.cooldown_value),
            )
        return _interpolate(points, step, "KLAnneal")
