"""Student-t intervals against scipy.stats and a hand value; repeated-sample-set protocol."""

import numpy as np
import pytest
import torch
from scipy import stats

from motionlab.metrics import Interval, mean_ci, repeat_metric, repeat_seed


def test_hand_value():
    # mean 2, sample std 1. With 2 degrees of freedom the t CDF is 1/2 + t / (2 sqrt(2 + t^2)), so the
    # 97.5% quantile solves t / sqrt(2 + t^2) = 0.95: t = sqrt(2 * 0.95^2 / (1 - 0.95^2)) = 4.3027.
    t = np.sqrt(2 * 0.95**2 / (1 - 0.95**2))
    mean, half = mean_ci([1.0, 2.0, 3.0])
    assert mean == 2.0
    assert half == pytest.approx(t / np.sqrt(3), rel=1e-12)


@pytest.mark.parametrize("confidence", [0.8, 0.95, 0.99])
def test_matches_scipy_t_interval(confidence):
    values = np.random.default_rng(0).normal(size=12) * 3 + 1
    low, high = stats.t.interval(confidence, df=11, loc=values.mean(), scale=stats.sem(values))
    mean, half = mean_ci(torch.from_numpy(values), confidence)
    assert mean == pytest.approx((low + high) / 2, rel=1e-12)
    assert half == pytest.approx((high - low) / 2, rel=1e-10)


def test_constant_values_have_zero_width():
    assert mean_ci([4.0, 4.0, 4.0, 4.0]) == (4.0, 0.0)


def test_covers_the_true_mean_about_95_percent_of_the_time():
    rng = np.random.default_rng(1)
    hits = 0
    for _ in range(2000):
        mean, half = mean_ci(rng.normal(loc=5.0, size=8))
        hits += abs(mean - 5.0) <= half
    # binomial(2000, 0.95) has std 0.0049; allow 4 std
    assert abs(hits / 2000 - 0.95) < 0.02


@pytest.mark.parametrize(
    "values, confidence, match",
    [
        ([1.0], 0.95, "mean_ci: values needs at least 2 entries"),
        ([1.0, np.nan], 0.95, "mean_ci: values contains NaN"),
        ([[1.0, 2.0]], 0.95, "mean_ci: values must be 1-D"),
        ([1.0, 2.0], 1.0, r"mean_ci: confidence must be in \(0, 1\), got 1.0"),
    ],
)
def test_mean_ci_bad_inputs(values, confidence, match):
    with pytest.raises(ValueError, match=match):
        mean_ci(values, confidence)


def draw_normal(generator: torch.Generator) -> torch.Tensor:
    return torch.randn(50, generator=generator, dtype=torch.float64)


def test_repeat_metric_uses_one_seeded_generator_per_repeat():
    result = repeat_metric(lambda x: float(x.mean()), draw_normal, n_repeats=5, seed=3)
    assert isinstance(result, Interval)
    expected = [float(draw_normal(torch.Generator().manual_seed(repeat_seed(3, r))).mean()) for r in range(5)]
    assert list(result.values) == expected
    assert (result.mean, result.half_width) == mean_ci(expected)
    assert result.confidence == 0.95
    assert str(result) == f"{result.mean:.4g} ± {result.half_width:.2g}"


def test_repeat_metric_is_reproducible_and_repeats_differ():
    first = repeat_metric(lambda x: float(x.std()), draw_normal, 4, seed=0)
    assert first == repeat_metric(lambda x: float(x.std()), draw_normal, 4, seed=0)
    assert len(set(first.values)) == 4
    assert first.values != repeat_metric(lambda x: float(x.std()), draw_normal, 4, seed=1).values
    assert len({repeat_seed(s, r) for s in range(3) for r in range(3)}) == 9


def test_repeat_metric_with_several_metrics_per_sample_set():
    calls = []

    def sample(generator):
        calls.append(1)
        return draw_normal(generator)

    result = repeat_metric(lambda x: {"mean": float(x.mean()), "max": float(x.max())}, sample, 3, seed=2)
    assert list(result) == ["mean", "max"] and len(calls) == 3
    assert all(isinstance(v, Interval) and len(v.values) == 3 for v in result.values())
    assert all(m < x for m, x in zip(result["mean"].values, result["max"].values))


@pytest.mark.parametrize(
    "fn, kwargs, match",
    [
        (lambda x: 1.0, {"n_repeats": 1}, "repeat_metric: n_repeats must be at least 2"),
        (lambda x: 1.0, {"seed": -1}, "repeat_metric: seed must be at least 0"),
        (lambda x: float("nan"), {}, "repeat_metric: fn on repeat 0 returned a non-finite value"),
        (lambda x: {"a": 1.0} if x[0] > 0 else {"b": 1.0}, {"n_repeats": 40}, "fn must return the same keys"),
    ],
)
def test_repeat_metric_bad_inputs(fn, kwargs, match):
    arguments = {"n_repeats": 3, "seed": 0} | kwargs
    with pytest.raises(ValueError, match=match):
        repeat_metric(fn, draw_normal, **arguments)


def test_repeat_metric_wrong_types_raise_type_error():
    with pytest.raises(TypeError, match="repeat_metric: fn on repeat 0 returned str, not a number"):
        repeat_metric(lambda x: "high", draw_normal, 3, seed=0)
    with pytest.raises(TypeError, match=r"repeat_metric: n_repeats must be an integer, got 2.0 \(float\)"):
        repeat_metric(lambda x: 1.0, draw_normal, 2.0, seed=0)
    with pytest.raises(TypeError, match="repeat_metric: confidence must be a real number"):
        repeat_metric(lambda x: 1.0, draw_normal, 3, seed=0, confidence="0.9")
