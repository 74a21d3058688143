"""Mode discovery and sampling: the silhouette rule, GMM fits against known clusters, counts, nearest end
points."""

import numpy as np
import pytest
from sklearn.metrics import adjusted_rand_score

from motionlab.models.odmo.modes import (
    choose_component_count,
    discover_modes,
    fit_class_modes,
    mode_counts,
    prior_modes,
    single_gaussian_modes,
)


def blobs(centres: list[list[float]], n: int, spread: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    points = np.concatenate([rng.normal(c, spread, size=(n, len(c))) for c in centres])
    return points, np.repeat(np.arange(len(centres)), n)


def test_selection_rule_takes_the_first_k_not_beaten_by_five_percent():
    ks = [3, 4, 5, 6]
    assert choose_component_count(ks, [0.50, 0.51, 0.9, 0.2]) == 3  # 0.50 > 0.95 * 0.51
    assert choose_component_count(ks, [0.40, 0.50, 0.51, 0.2]) == 4  # 0.40 <= 0.475, then 0.50 > 0.4845
    assert choose_component_count(ks, [0.1, 0.2, 0.3, 0.4]) == 6  # always beaten: the last k
    with pytest.raises(ValueError, match="one silhouette per k"):
        choose_component_count(ks, [0.1])


def test_fit_finds_well_separated_clusters_and_drops_tiny_ones():
    centres = [[0, 0, 0], [6, 0, 0], [0, 6, 0], [0, 0, 6]]
    codes, truth = blobs(centres, 40, 0.3, seed=0)
    modes = fit_class_modes(codes, k_values=range(3, 8), seed=0)
    assert modes.n_modes == 4
    assert adjusted_rand_score(truth, modes.assign(codes)) == pytest.approx(1.0)
    assert modes.weights.sum() == pytest.approx(1.0)
    assert set(modes.silhouettes) == set(range(3, 8))
    # a 3-point outlier cluster is a component of its own, then dropped as tiny
    outliers = np.random.default_rng(1).normal([20, 20, 20], 0.1, size=(3, 3))
    with_outliers = fit_class_modes(np.concatenate([codes[:120], outliers]), k_values=[4, 5], min_share=0.05)
    assert with_outliers.n_modes == 3


def test_discover_modes_labels_every_training_code_within_its_class():
    codes_a, truth_a = blobs([[0, 0], [5, 5], [10, 0]], 20, 0.2, seed=2)
    codes_b, truth_b = blobs([[0, 20], [5, 25], [10, 20]], 20, 0.2, seed=3)
    codes = np.concatenate([codes_a, codes_b])
    action = np.repeat([0, 1], 60)
    ends = np.random.default_rng(0).normal(size=(120, 3))
    modes = discover_modes(codes, action, ends, 2, k_values=[3, 4])
    assert adjusted_rand_score(truth_a, modes.labels[:60]) == pytest.approx(1.0)
    assert adjusted_rand_score(truth_b, modes.labels[60:]) == pytest.approx(1.0)
    assert sorted(set(modes.global_labels())) == list(range(6))
    with pytest.raises(ValueError, match="no codes"):
        discover_modes(codes, action, ends, 3)


def test_mode_counts_split_by_largest_remainder():
    assert mode_counts(np.array([0.5, 0.3, 0.2]), 10).tolist() == [5, 3, 2]
    assert mode_counts(np.array([1.0, 1.0, 1.0]), 10).tolist() == [4, 3, 3]
    assert mode_counts(np.array([0.0, 2.0]), 3).tolist() == [0, 3]
    with pytest.raises(ValueError, match="probabilities"):
        mode_counts(np.array([-1.0, 2.0]), 3)


def test_mode_preserving_sampling_follows_each_mode():
    codes, truth = blobs([[0, 0], [10, 0], [0, 10]], 30, 0.1, seed=4)
    modes = discover_modes(codes, np.zeros(90, dtype=int), np.zeros((90, 3)), 1, k_values=[3, 4])
    rng = np.random.default_rng(0)
    drawn, picked = modes.sample(0, 9, rng)
    assert np.bincount(picked).tolist() == [3, 3, 3]
    assert np.array_equal(modes.classes[0].assign(drawn), picked)
    only, picked = modes.sample(0, 5, rng, mode=2)
    assert (picked == 2).all() and np.allclose(only.mean(0), modes.classes[0].means[2], atol=0.3)
    custom, picked = modes.sample(0, 10, rng, probabilities=[0.8, 0.2, 0.0])
    assert np.bincount(picked, minlength=3).tolist() == [8, 2, 0]
    with pytest.raises(ValueError, match="modes 0..2"):
        modes.sample(0, 2, rng, mode=3)


def test_nearest_end_points_come_from_the_same_class():
    codes = np.array([[0.0, 0.0], [1.0, 0.0], [0.1, 0.0]])
    action = np.array([0, 0, 1])
    ends = np.array([[1.0, 0, 0], [2.0, 0, 0], [3.0, 0, 0]])
    modes = single_gaussian_modes(np.repeat(codes, 2, 0), np.repeat(action, 2), np.repeat(ends, 2, 0), 2)
    assert np.array_equal(
        modes.nearest_end_points(0, np.array([[0.2, 0.0], [0.9, 0.0]])), [[1.0, 0, 0], [2.0, 0, 0]]
    )
    assert np.array_equal(modes.nearest_end_points(1, np.array([[0.9, 0.0]])), [[3.0, 0, 0]])


def test_single_gaussian_and_prior_samplers():
    codes, _ = blobs([[0, 0], [4, 0]], 50, 0.5, seed=5)
    action = np.repeat([0, 1], 50)
    conv = single_gaussian_modes(codes, action, np.zeros((100, 3)), 2)
    assert conv.classes[1].n_modes == 1
    assert np.allclose(conv.classes[1].means[0], codes[50:].mean(0))
    assert np.allclose(conv.classes[1].covariances[0], np.cov(codes[50:], rowvar=False) + 1e-4 * np.eye(2))
    prior = prior_modes(codes, action, np.zeros((100, 3)), 2)
    drawn, _ = prior.sample(0, 4000, np.random.default_rng(0))
    assert np.allclose(drawn.mean(0), 0, atol=0.06) and np.allclose(
        np.cov(drawn, rowvar=False), np.eye(2), atol=0.08
    )
