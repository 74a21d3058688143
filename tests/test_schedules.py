"""Coefficient schedules: values at their breakpoints, argument validation, and np.interp as an oracle."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motionlab.train.schedules import Constant, KLAnneal, LinearRamp, PiecewiseLinear


def test_kl_anneal_breakpoints() -> None:
    beta = KLAnneal(max_value=2.0, warmup=10, anneal=20)
    assert [beta(s) for s in (0, 9, 10, 11, 20, 29, 30, 31, 10**6)] == pytest.approx(
        [0.0, 0.0, 0.0, 0.1, 1.0, 1.9, 2.0, 2.0, 2.0]
    )


def test_kl_anneal_cooldown_breakpoints() -> None:
    beta = KLAnneal(max_value=2.0, warmup=10, anneal=20, cooldown_start=50, cooldown=10, cooldown_value=0.5)
    assert [beta(s) for s in (30, 49, 50, 55, 59, 60, 1000)] == pytest.approx(
        [2.0, 2.0, 2.0, 1.25, 0.65, 0.5, 0.5]
    )


def test_kl_anneal_zero_lengths_are_jumps() -> None:
    beta = KLAnneal(max_value=1.0, warmup=5, anneal=0, cooldown_start=8, cooldown=0, cooldown_value=0.25)
    assert [beta(s) for s in (0, 4, 5, 7, 8, 9)] == [0.0, 0.0, 1.0, 1.0, 0.25, 0.25]
    no_warmup = KLAnneal(max_value=3.0, warmup=0, anneal=0)
    assert no_warmup(0) == 3.0


def test_linear_ramp_teacher_forcing_and_delayed_weight() -> None:
    teacher_forcing = LinearRamp(start=0, length=100, begin=1.0, end=0.3)
    assert [teacher_forcing(s) for s in (0, 50, 100, 500)] == pytest.approx([1.0, 0.65, 0.3, 0.3])
    weight = LinearRamp(start=20, length=10, begin=0.0, end=0.5)
    assert [weight(s) for s in (0, 19, 20, 25, 30, 31)] == pytest.approx([0.0, 0.0, 0.0, 0.25, 0.5, 0.5])
    switch = LinearRamp(start=7, length=0, begin=0.0, end=1.0)
    assert [switch(6), switch(7)] == [0.0, 1.0]


def test_constant_and_piecewise_linear() -> None:
    assert Constant(0.7)(0) == Constant(0.7)(12345) == 0.7
    curve = PiecewiseLinear(((10, 1.0), (20, 3.0), (20, 0.0), (30, 1.0)))
    assert [curve(s) for s in (0, 10, 15, 19, 20, 25, 30, 99)] == pytest.approx(
        [1.0, 1.0, 2.0, 2.8, 0.0, 0.5, 1.0, 1.0]
    )
    assert PiecewiseLinear([[0, 1], [4, 3]]).points == ((0, 1.0), (4, 3.0))


@pytest.mark.parametrize(
    "build, message",
    [
        (
            lambda: KLAnneal(max_value=-1.0, warmup=0, anneal=10),
            "KLAnneal: max_value must be at least 0, got -1.0",
        ),
        (
            lambda: KLAnneal(max_value=float("nan"), warmup=0, anneal=10),
            "KLAnneal: max_value must be a finite",
        ),
        (
            lambda: KLAnneal(max_value=1.0, warmup=-1, anneal=10),
            "KLAnneal: warmup must be at least 0, got -1",
        ),
        (lambda: KLAnneal(max_value=1.0, warmup=10, anneal=10, cooldown_start=15), "cooldown_start"),
        (
            lambda: KLAnneal(max_value=1.0, warmup=0, anneal=10, cooldown_start=20, cooldown_value=2.0),
            r"KLAnneal: cooldown_value must be in \[0, 1\], got 2.0",
        ),
        (
            lambda: LinearRamp(start=0, length=1, begin=0.0, end=math.inf),
            "LinearRamp: end must be a finite number",
        ),
        (lambda: PiecewiseLinear(()), "empty"),
        (lambda: PiecewiseLinear(((5, 0.0), (4, 1.0))), "non-decreasing"),
        (lambda: PiecewiseLinear(((5, 0.0), (5, 1.0), (5, 2.0))), "more than two"),
        (lambda: PiecewiseLinear((1, 2, 3)), "pairs"),
    ],
)
def test_invalid_arguments_name_the_field(build, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        build()


@pytest.mark.parametrize(
    "build, message",
    [
        (
            lambda: KLAnneal(max_value=1.0, warmup=0, anneal=2.5),
            r"KLAnneal: anneal must be int, got 2.5 \(float\)",
        ),
        (
            lambda: LinearRamp(start=True, length=1, begin=0.0, end=1.0),
            "LinearRamp: start must be int, got True",
        ),
        (lambda: Constant("1"), "Constant: value must be int or float, got '1' \\(str\\)"),
        (lambda: PiecewiseLinear(((0, 0.0), (1.5, 1.0))), r"PiecewiseLinear: points\[1\] step must be int"),
    ],
)
def test_arguments_of_the_wrong_type_raise_type_error(build, message: str) -> None:
    with pytest.raises(TypeError, match=message):
        build()


@pytest.mark.parametrize(
    "step, error", [(-1, ValueError), (1.5, TypeError), (True, TypeError), ("3", TypeError)]
)
def test_invalid_steps_are_rejected(step, error) -> None:
    for schedule in (
        Constant(1.0),
        LinearRamp(0, 5, 0.0, 1.0),
        KLAnneal(1.0, 0, 5),
        PiecewiseLinear(((0, 1.0),)),
    ):
        with pytest.raises(error, match=f"{type(schedule).__name__}: step must be"):
            schedule(step)


def test_schedules_are_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        KLAnneal(1.0, 0, 5).warmup = 3  # type: ignore[misc]


@settings(max_examples=60, deadline=None)
@given(
    start=st.integers(0, 1000),
    length=st.integers(1, 1000),
    begin=st.floats(-5, 5),
    end=st.floats(-5, 5),
    step=st.integers(0, 3000),
)
def test_linear_ramp_matches_numpy_interp(
    start: int, length: int, begin: float, end: float, step: int
) -> None:
    expected = np.interp(step, [start, start + length], [begin, end])
    assert LinearRamp(start, length, begin, end)(step) == pytest.approx(expected, abs=1e-9)


@settings(max_examples=60, deadline=None)
@given(
    gaps=st.lists(st.integers(1, 50), min_size=1, max_size=6),
    values=st.lists(st.floats(-10, 10), min_size=7, max_size=7),
    step=st.integers(0, 400),
)
def test_piecewise_linear_matches_numpy_interp(gaps: list[int], values: list[float], step: int) -> None:
    steps = np.cumsum([0, *gaps])
    points = tuple(zip(steps.tolist(), values[: len(steps)]))
    expected = np.interp(step, steps, values[: len(steps)])
    assert PiecewiseLinear(points)(step) == pytest.approx(expected, abs=1e-9)


@settings(max_examples=60, deadline=None)
@given(
    max_value=st.floats(0, 10),
    warmup=st.integers(0, 100),
    anneal=st.integers(0, 100),
    step=st.integers(0, 300),
)
def test_kl_anneal_rises_monotonically_to_its_max(
    max_value: float, warmup: int, anneal: int, step: int
) -> None:
    beta = KLAnneal(max_value, warmup, anneal)
    assert 0.0 <= beta(step) <= max_value
    assert beta(step) <= beta(step + 1) + 1e-12
    if step < warmup:
        assert beta(step) == 0.0
    if step >= warmup + anneal:
        assert beta(step) == max_value
