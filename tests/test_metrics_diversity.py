"""APD, Diversity, Multimodality and n-APD against explicit loops, hand values and expectations."""

import itertools

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import cdist

from motionlab.metrics import apd, class_apd, diversity, multimodality, n_apd


def loop_apd(samples: np.ndarray) -> float:
    flat = samples.reshape(samples.shape[0], -1)
    pairs = [
        np.sqrt(((flat[i] - flat[j]) ** 2).sum()) for i, j in itertools.permutations(range(len(flat)), 2)
    ]
    return float(np.mean(pairs))


def test_apd_hand_values():
    two = np.stack([np.zeros((2, 2)), np.ones((2, 2))])  # distance sqrt(4) = 2 over the whole sequence
    assert apd(two) == pytest.approx(2.0)
    line = np.array([0.0, 1.0, 3.0]).reshape(3, 1, 1)  # distances 1, 3, 2
    assert apd(line) == pytest.approx(2.0)


@pytest.mark.parametrize("seed", range(3))
def test_apd_matches_loop_over_ordered_pairs(seed):
    samples = np.random.default_rng(seed).normal(size=(7, 5, 6))
    assert apd(samples) == pytest.approx(loop_apd(samples), rel=1e-12)


def test_apd_norm_is_over_the_whole_sequence_not_per_frame():
    a = np.zeros((1, 2, 2))
    b = np.array([[[3.0, 0.0], [0.0, 4.0]]])  # per-frame distances 3 and 4 (mean 3.5); sequence distance 5
    assert apd(np.concatenate([a, b])) == pytest.approx(5.0)


def test_apd_flattens_joint_layouts_and_accepts_torch():
    samples = np.random.default_rng(3).normal(size=(5, 4, 22, 3))
    value = apd(torch.from_numpy(samples))
    assert isinstance(value, float)
    assert value == pytest.approx(apd(samples.reshape(5, 4, 66)), rel=1e-14)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31), k=st.integers(2, 8), scale=st.floats(-50.0, 50.0))
def test_property_apd_scales_linearly_and_ignores_translation(seed, k, scale):
    rng = np.random.default_rng(seed)
    samples = rng.normal(size=(k, 3, 4))
    base = apd(samples)
    assert apd(scale * samples) == pytest.approx(abs(scale) * base, rel=1e-10, abs=1e-12)
    assert apd(samples + rng.normal(size=(3, 4))) == pytest.approx(base, rel=1e-10)


def test_apd_needs_two_samples():
    with pytest.raises(ValueError, match="apd: samples needs at least 2 samples"):
        apd(np.zeros((1, 3, 2)))


def expected_pair_distance(features: np.ndarray) -> tuple[float, float]:
    """Mean and standard deviation of ||f_i - f_j|| for i, j drawn independently and uniformly."""
    distances = cdist(features, features).ravel()
    return float(distances.mean()), float(distances.std())


def test_diversity_matches_its_expectation():
    features = np.random.default_rng(4).normal(size=(30, 5))
    mean, std = expected_pair_distance(features)
    n_pairs = 20_000
    value = diversity(features, n_pairs, rng=0)
    assert abs(value - mean) < 5 * std / np.sqrt(n_pairs)


def test_diversity_is_reproducible_and_seeded():
    features = np.random.default_rng(5).normal(size=(40, 3))
    assert diversity(features, 200, 7) == diversity(torch.from_numpy(features), 200, np.random.default_rng(7))
    assert diversity(features, 200, 7) != diversity(features, 200, 8)


def test_diversity_of_identical_features_is_zero():
    assert diversity(np.ones((10, 4)), 50, 0) == 0.0


def test_multimodality_is_within_class():
    # Two classes far apart but each collapsed to a single point: diverse, yet no multimodality.
    features = np.concatenate([np.zeros((5, 2)), np.full((6, 2), 10.0)])
    labels = np.array([0] * 5 + [1] * 6)
    assert multimodality(features, labels, 20, 0) == 0.0
    assert diversity(features, 200, 0) > 5.0


def test_multimodality_matches_its_expectation():
    rng = np.random.default_rng(6)
    features = np.concatenate([rng.normal(size=(12, 3)), 3.0 * rng.normal(size=(20, 3))])
    labels = np.array(["jump"] * 12 + ["walk"] * 20)
    stats = [expected_pair_distance(features[labels == c]) for c in ("jump", "walk")]
    expected = np.mean([m for m, _ in stats])
    n_pairs = 20_000
    tolerance = 5 * np.sqrt(sum(s**2 for _, s in stats)) / 2 / np.sqrt(n_pairs)
    assert abs(multimodality(features, labels, n_pairs, 1) - expected) < tolerance


def test_multimodality_rejects_singleton_classes():
    with pytest.raises(ValueError, match=r"multimodality: every class needs at least 2 rows; classes \[2\]"):
        multimodality(np.zeros((5, 2)), [0, 0, 1, 1, 2], 20, 0)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: diversity(np.zeros((5, 2)), 0, 0), "diversity: n_pairs must be at least 1"),
        (lambda: diversity(np.zeros((5, 2)), 10, -1), "diversity: rng must be"),
        (lambda: diversity(np.zeros((1, 2)), 10, 0), "diversity: features needs at least 2 rows"),
        (
            lambda: multimodality(np.zeros((4, 2)), [0, 0, 1], 10, 0),
            r"multimodality: labels must have one entry per item \(4\), got 3",
        ),
    ],
)
def test_diversity_bad_inputs(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_class_apd_per_class():
    rng = np.random.default_rng(7)
    sequences = rng.normal(size=(9, 4, 3))
    labels = np.array([2, 0, 2, 0, 0, 2, 1, 1, 2])
    result = class_apd(sequences, labels)
    with pytest.raises(ValueError, match="class_apd: class 0 of sequences has only 1 sequence"):
        class_apd(sequences[:3], labels[:3])
    assert list(result) == [0, 1, 2]
    for label, value in result.items():
        assert value == pytest.approx(loop_apd(sequences[labels == label]), rel=1e-12)


def test_n_apd_is_one_for_the_real_data_and_follows_per_class_scaling():
    rng = np.random.default_rng(8)
    real = rng.normal(size=(10, 5, 3))
    labels = np.array([0] * 4 + [1] * 6)
    assert n_apd(real, labels, real, labels) == pytest.approx(1.0)
    generated = real.copy()
    generated[labels == 0] *= 2.0
    generated[labels == 1] *= 0.5
    assert n_apd(generated, labels, real, labels) == pytest.approx((2.0 + 0.5) / 2)


def test_n_apd_uses_each_sets_own_labels():
    rng = np.random.default_rng(9)
    real = rng.normal(size=(6, 2, 2))
    generated = rng.normal(size=(8, 2, 2))
    real_labels, gen_labels = [0, 0, 0, 1, 1, 1], [1, 1, 1, 1, 0, 0, 0, 0]
    gen_apd, real_apd = class_apd(generated, gen_labels), class_apd(real, real_labels)
    expected = (gen_apd[0] / real_apd[0] + gen_apd[1] / real_apd[1]) / 2
    assert n_apd(generated, gen_labels, real, real_labels) == pytest.approx(expected)


def test_n_apd_bad_inputs():
    real = np.random.default_rng(10).normal(size=(4, 2, 2))
    with pytest.raises(ValueError, match="n_apd: generated and real must contain the same classes"):
        n_apd(real, [0, 0, 1, 1], real, [0, 0, 2, 2])
    with pytest.raises(ValueError, match=r"n_apd: real sequences of classes \[1\] are all identical"):
        n_apd(real, [0, 0, 1, 1], np.concatenate([real[:2], np.zeros((2, 2, 2))]), [0, 0, 1, 1])
    with pytest.raises(ValueError, match="n_apd: generated and real must share the per-sequence shape"):
        n_apd(real, [0, 0, 1, 1], real[:, :1], [0, 0, 1, 1])
    with pytest.raises(ValueError, match="n_apd: class 1 of generated has only 1 sequence"):
        n_apd(real, [0, 0, 0, 1], real, [0, 0, 1, 1])
