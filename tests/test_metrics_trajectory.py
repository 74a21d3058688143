"""Best-of-K ADE/FDE, multimodal ground truth, MMADE/MMFDE and end-point error against loops and hand
values."""

import math

import numpy as np
import pytest
import torch

from motionlab.metrics import (
    end_point_error,
    end_point_mse,
    min_ade,
    min_fde,
    mmade,
    mmfde,
    multimodal_ground_truth,
)


def loop_ade(samples: np.ndarray, target: np.ndarray) -> float:
    best = math.inf
    for sample in samples:
        frames = [math.sqrt(sum((a - b) ** 2 for a, b in zip(s, t))) for s, t in zip(sample, target)]
        best = min(best, sum(frames) / len(frames))
    return best


def loop_fde(samples: np.ndarray, target: np.ndarray) -> float:
    return min(math.sqrt(sum((a - b) ** 2 for a, b in zip(sample[-1], target[-1]))) for sample in samples)


def test_hand_values():
    target = np.zeros((4, 3))
    near = np.tile([1.0, 0.0, 0.0], (4, 1))  # distance 1 on every frame
    far_then_exact = np.zeros((4, 3))
    far_then_exact[:3] = [0.0, 4.0, 0.0]  # distances 4, 4, 4, 0: ADE 3, FDE 0
    samples = np.stack([near, far_then_exact])
    assert min_ade(samples, target) == pytest.approx(1.0)
    assert min_fde(samples, target) == pytest.approx(0.0)


@pytest.mark.parametrize("seed", range(3))
def test_match_loops(seed):
    rng = np.random.default_rng(seed)
    samples, target = rng.normal(size=(6, 5, 4)), rng.normal(size=(5, 4))
    assert min_ade(samples, target) == pytest.approx(loop_ade(samples, target), rel=1e-12)
    assert min_fde(samples, target) == pytest.approx(loop_fde(samples, target), rel=1e-12)


def test_frame_distance_is_over_the_whole_pose_vector():
    # Two joints off by (3, 0, 0) and (0, 4, 0): the frame distance is 5, not the per-joint mean 3.5.
    target = np.zeros((2, 2, 3))
    sample = np.zeros((1, 2, 2, 3))
    sample[0, :, 0, 0] = 3.0
    sample[0, :, 1, 1] = 4.0
    assert min_ade(sample, target) == pytest.approx(5.0)
    assert min_ade(sample.reshape(1, 2, 6), target.reshape(2, 6)) == pytest.approx(5.0)


def test_accepts_torch_and_returns_float():
    rng = np.random.default_rng(3)
    samples, target = rng.normal(size=(4, 3, 2)), rng.normal(size=(3, 2))
    value = min_ade(torch.from_numpy(samples), torch.from_numpy(target))
    assert isinstance(value, float) and value == min_ade(samples, target)
    assert isinstance(min_fde(torch.from_numpy(samples), target), float)


def test_multimodal_ground_truth_groups_similar_starts():
    starts = np.array([[0.0], [0.05], [1.0], [1.02], [1.2]])
    futures = np.arange(5, dtype=float).reshape(5, 1, 1) * np.ones((5, 2, 3))
    groups = multimodal_ground_truth(starts, futures, threshold=0.1)
    members = [g[:, 0, 0].astype(int).tolist() for g in groups]
    assert members == [[0, 1], [0, 1], [2, 3], [2, 3], [4]]
    assert all(g.shape[1:] == (2, 3) for g in groups)


def test_multimodal_ground_truth_threshold_is_strict():
    groups = multimodal_ground_truth([[0.0], [0.5]], np.zeros((2, 1, 1)), threshold=0.5)
    assert [len(g) for g in groups] == [1, 1]


@pytest.mark.parametrize("seed", range(2))
def test_multimodal_ground_truth_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    starts, futures = rng.normal(size=(20, 4, 3)), rng.normal(size=(20, 6, 2))
    groups = multimodal_ground_truth(starts, futures, threshold=4.0)
    for i, group in enumerate(groups):
        expected = [j for j in range(20) if np.sqrt(((starts[i] - starts[j]) ** 2).sum()) < 4.0]
        assert i in expected
        np.testing.assert_array_equal(group, futures[expected])


def test_mmade_and_mmfde_average_best_of_k_over_ground_truths():
    rng = np.random.default_rng(4)
    samples, gts = rng.normal(size=(8, 5, 6)), rng.normal(size=(3, 5, 6))
    assert mmade(samples, gts) == pytest.approx(np.mean([loop_ade(samples, g) for g in gts]), rel=1e-12)
    assert mmfde(samples, gts) == pytest.approx(np.mean([loop_fde(samples, g) for g in gts]), rel=1e-12)
    assert mmade(samples, gts[:1]) == pytest.approx(min_ade(samples, gts[0]), rel=1e-14)


def test_end_point_error_hand_value():
    trajectories = np.zeros((2, 10, 2))
    trajectories[0, -1] = [3.0, 4.0]  # 5 from the origin
    trajectories[1, -1] = [1.0, 1.0]  # exactly at its target
    targets = np.array([[0.0, 0.0], [1.0, 1.0]])
    assert end_point_error(trajectories, targets) == pytest.approx(2.5)
    assert end_point_mse(trajectories, targets) == pytest.approx((25.0 + 0.0) / 2)  # ODMO's dist_e


@pytest.mark.parametrize(
    "call, match",
    [
        (
            lambda: min_ade(np.zeros((2, 3, 4)), np.zeros((3, 5))),
            r"min_ade: each sample and target must have the same",
        ),
        (
            lambda: min_ade(np.zeros((3, 4)), np.zeros((3, 4))),
            "min_ade: samples must have at least 3 dimensions",
        ),
        (
            lambda: min_fde(np.zeros((2, 3, 4)), np.full((3, 4), np.inf)),
            "min_fde: target contains NaN or infinite values",
        ),
        (
            lambda: mmade(np.zeros((2, 3, 4)), np.zeros((3, 4))),
            "mmade: gt_futures must have at least 3 dimensions",
        ),
        (
            lambda: multimodal_ground_truth(np.zeros((3, 2)), np.zeros((4, 2, 2)), 0.1),
            "multimodal_ground_truth: start_poses and futures must have the same N",
        ),
        (
            lambda: multimodal_ground_truth(np.zeros((3, 2)), np.zeros((3, 2, 2)), 0.0),
            "multimodal_ground_truth: threshold must be greater than 0, got 0.0",
        ),
        (
            lambda: end_point_error(np.zeros((2, 5, 2)), np.zeros((2, 3))),
            r"end_point_error: targets must be \(2, 2\)",
        ),
    ],
)
def test_bad_inputs(call, match):
    with pytest.raises(ValueError, match=match):
        call()
