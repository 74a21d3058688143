"""Every public metric: torch or NumPy in, float out; NaN, wrong ndim and empty input raise a named
ValueError, a non-numeric dtype a named TypeError."""

import numpy as np
import pytest
import torch

import motionlab.metrics as metrics

rng = np.random.default_rng(0)
FEATURES = rng.normal(size=(12, 4))
LABELS = np.array([0, 1] * 6)
SAMPLES = rng.normal(size=(5, 6, 3))
TARGET = rng.normal(size=(6, 3))
PROBS = np.full((6, 3), 1 / 3)
POSES = np.zeros((4, 22, 3))
PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19]

# (name, function of the tested array, the valid array, the argument name in messages)
CASES = [
    ("fid", lambda x: metrics.fid(x, FEATURES), FEATURES, "a"),
    ("feature_statistics", metrics.feature_statistics, FEATURES, "features"),
    ("inception_score", metrics.inception_score, PROBS, "probs"),
    ("recognition_accuracy", lambda x: metrics.recognition_accuracy(x, [0] * 6), PROBS, "logits_or_probs"),
    ("apd", metrics.apd, SAMPLES, "samples"),
    ("diversity", lambda x: metrics.diversity(x, 10, 0), FEATURES, "features"),
    ("multimodality", lambda x: metrics.multimodality(x, LABELS, 10, 0), FEATURES, "features"),
    ("class_apd", lambda x: metrics.class_apd(x, [0, 0, 1, 1, 1]), SAMPLES, "sequences"),
    ("n_apd", lambda x: metrics.n_apd(x, [0, 0, 1, 1, 1], SAMPLES, [0, 0, 1, 1, 1]), SAMPLES, "generated"),
    ("min_ade", lambda x: metrics.min_ade(x, TARGET), SAMPLES, "samples"),
    ("min_fde", lambda x: metrics.min_fde(SAMPLES, x), TARGET, "target"),
    ("mmade", lambda x: metrics.mmade(SAMPLES, x), SAMPLES, "gt_futures"),
    ("mmfde", lambda x: metrics.mmfde(x, SAMPLES), SAMPLES, "samples"),
    ("end_point_error", lambda x: metrics.end_point_error(x, SAMPLES[:, -1]), SAMPLES, "trajectories"),
    ("end_point_mse", lambda x: metrics.end_point_mse(x, SAMPLES[:, -1]), SAMPLES, "trajectories"),
    ("foot_skating", lambda x: metrics.foot_skating(x, np.ones((4, 4))), POSES, "positions"),
    ("bone_length_error", lambda x: metrics.bone_length_error(x, PARENTS, np.ones(22)), POSES, "positions"),
    ("mean_ci", metrics.mean_ci, FEATURES[:, 0], "values"),
]
IDS = [case[0] for case in CASES]


@pytest.mark.parametrize("name, call, valid, argument", CASES, ids=IDS)
def test_torch_and_numpy_agree(name, call, valid, argument):
    from_numpy = call(valid)
    from_torch = call(torch.tensor(valid, requires_grad=True))
    first = from_numpy[0] if isinstance(from_numpy, tuple) else from_numpy
    if isinstance(first, float):
        assert np.isfinite(first)
    assert str(from_numpy) == str(from_torch)


@pytest.mark.parametrize("name, call, valid, argument", CASES, ids=IDS)
def test_nan_and_inf_are_named(name, call, valid, argument):
    for bad_value in (np.nan, np.inf):
        bad = valid.copy()
        bad.flat[bad.size // 2] = bad_value
        with pytest.raises(
            ValueError, match=rf"{name}: {argument} contains NaN or infinite values \(first at index "
        ):
            call(bad)


@pytest.mark.parametrize("name, call, valid, argument", CASES, ids=IDS)
def test_scalar_is_rejected_by_ndim(name, call, valid, argument):
    with pytest.raises(ValueError, match=f"{name}: {argument} must (be|have)"):
        call(valid.ravel()[0])


@pytest.mark.parametrize("name, call, valid, argument", CASES, ids=IDS)
def test_empty_is_named(name, call, valid, argument):
    with pytest.raises(ValueError, match=f"{name}: {argument} (is empty|must)"):
        call(valid[:0])


def test_non_numeric_and_ragged_inputs():
    with pytest.raises(TypeError, match="apd: samples must hold real numbers, got dtype <U1"):
        metrics.apd(np.array([["a", "b"], ["c", "d"]]))
    with pytest.raises(ValueError, match="apd: samples is not a rectangular array"):
        metrics.apd([[1.0, 2.0], [3.0]])
