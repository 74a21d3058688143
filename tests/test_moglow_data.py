"""MoGlow data: action selection, augmentation, features, standardisation, windows, control programmes."""

import math

import numpy as np
import pytest
import torch

from motionlab.data.augment import mirror_positions
from motionlab.data.synthetic import generate
from motionlab.models.moglow import (
    MoGlowDataConfig,
    Segment,
    augment_clips,
    clip_features,
    control_programme,
    fit_scalers,
    moglow_features,
    select_actions,
    sequence_windows,
    standardize,
)


@pytest.fixture(scope="module")
def clips():
    return select_actions(generate(seed=3, n_per_mode=1, seconds=1.5), ("walk", "jog"))


def test_select_actions(clips):
    assert clips.n_clips == 4
    assert set(clips.action.tolist()) == {0, 1}
    with pytest.raises(ValueError, match="unknown actions"):
        select_actions(clips, ("fly",))


def test_augmentation_order_and_control_symmetries(clips):
    positions, rotations = torch.from_numpy(clips.positions), torch.from_numpy(clips.rotations)
    aug_pos, aug_rot = augment_clips(positions, rotations, mirror=True, reverse_time=True)
    n = clips.n_clips
    assert aug_pos.shape[0] == 4 * n
    assert torch.equal(aug_pos[:n], positions)
    assert torch.allclose(aug_pos[n : 2 * n], mirror_positions(positions))
    assert torch.equal(aug_pos[2 * n :], aug_pos[: 2 * n].flip(1))
    features = moglow_features(aug_pos, aug_rot)
    original, mirrored, reversed_ = (
        features.control[:n],
        features.control[n : 2 * n],
        features.control[2 * n : 3 * n],
    )
    # mirroring keeps forward velocity and flips sideways velocity and yaw rate
    np.testing.assert_allclose(mirrored[..., 0], original[..., 0], atol=1e-5)
    np.testing.assert_allclose(mirrored[..., 1:], -original[..., 1:], atol=1e-5)
    # time reversal: frame t of the reversed clip is the step s -> s - 1 (s = T - t) seen from frame s's
    # heading
    frames = original.shape[1]
    s = torch.arange(frames - 1, 0, -1)
    turn = original[:, s, 2]
    expected_xy = -torch.stack(
        [
            torch.cos(turn) * original[:, s, 0] + torch.sin(turn) * original[:, s, 1],
            -torch.sin(turn) * original[:, s, 0] + torch.cos(turn) * original[:, s, 1],
        ],
        dim=-1,
    )
    np.testing.assert_allclose(reversed_[:, 1:, :2], expected_xy, atol=1e-5)
    np.testing.assert_allclose(reversed_[:, 1:, 2], -turn, atol=1e-5)
    assert (original[:, 1:, 0] > 0).all() and (reversed_[:, 1:, 0] < 0).all()


def test_features_standardisation_and_windows(clips):
    cfg = MoGlowDataConfig()
    features = clip_features(clips, cfg, augment=True)
    assert features.pose.shape == (16, 45, 64) and features.control.shape == (16, 45, 3)
    scalers = fit_scalers(features)
    standard = standardize(features, scalers)
    flat = standard.pose.reshape(-1, 64)
    np.testing.assert_allclose(flat.mean(0).numpy(), 0.0, atol=1e-4)
    np.testing.assert_allclose(flat.std(0, correction=0).numpy(), 1.0, atol=1e-3)
    windows = sequence_windows(standard, length=20, stride=10)
    assert windows.pose.shape == (16 * 3, 20, 64)  # starts 1, 11, 21
    assert torch.equal(windows.pose[16], standard.pose[0, 11:31])
    with pytest.raises(ValueError):
        sequence_windows(standard, length=50, stride=10)
    with pytest.raises(ValueError):
        MoGlowDataConfig(actions=())


def test_control_programme_values_and_ramp():
    control = control_programme([Segment(1.0, 1.5, turn=0.3), Segment(2.0, 0.0)], fps=30, ramp=0.0)
    assert control.shape == (90, 3)
    np.testing.assert_allclose(control[:30, 0].numpy(), 1.5 / 30, rtol=1e-6)
    np.testing.assert_allclose(control[:30, 2].numpy(), 0.3 / 30, rtol=1e-6)
    assert float(control[30:].abs().max()) == 0.0
    smooth = control_programme([Segment(1.0, 1.5), Segment(2.0, 0.0)], fps=30, ramp=0.5)
    assert smooth.shape == (90, 3)
    steps = smooth[1:, 0] - smooth[:-1, 0]
    assert (
        float(steps.max()) <= 1e-7 and float(-steps.min()) <= 1.5 / 30 / 15 + 1e-7
    )  # a 15-frame linear ramp
    assert math.isclose(float(smooth[0, 0]), 1.5 / 30, rel_tol=1e-6) and float(smooth[-1, 0]) == 0.0
    with pytest.raises(ValueError):
        Segment(0.0, 1.0)
    with pytest.raises(ValueError):
        control_programme([])
