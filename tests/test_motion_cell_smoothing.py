"""Smoothing generated motion words: steps between words removed, steady motion kept, rotations kept, bad
input refused."""

import math

import pytest
import torch

from motionlab.models.motion_cell.smoothing import (
    continuous_poses,
    moving_average,
    smooth_word_boundaries,
    spread_boundary_steps,
    triangle_weights,
)

ROOT = 6


def _poses(quaternions: torch.Tensor, root: torch.Tensor) -> torch.Tensor:
    """Pose vectors ``(B, T, K * 4 + 6)`` of quaternions ``(B, T, K, 4)`` and root channels ``(B, T, 6)``."""
    return torch.cat([quaternions.flatten(-2), root], dim=-1)


def _about_x(angles: torch.Tensor) -> torch.Tensor:
    """Unit quaternions (w first) of turns by ``angles`` about the x axis, ``angles.shape + (4,)``."""
    zero = torch.zeros_like(angles)
    return torch.stack([torch.cos(angles / 2), torch.sin(angles / 2), zero, zero], dim=-1)


def test_triangle_weights_are_two_boxes_convolved():
    torch.testing.assert_close(triangle_weights(3), torch.tensor([1.0, 2, 3, 2, 1]) / 9)
    torch.testing.assert_close(triangle_weights(1), torch.tensor([1.0]))
    assert triangle_weights(4).sum().item() == pytest.approx(1.0)


def test_moving_average_removes_a_period_of_its_width_and_keeps_a_ramp():
    t = torch.arange(30.0)
    wave = torch.cos(2 * math.pi * t / 3)[None, :, None]  # period 3: the word frequency
    torch.testing.assert_close(moving_average(wave, 3)[:, 1:-1], torch.zeros(1, 28, 1), atol=1e-5, rtol=0)
    ramp = (0.5 * t)[None, :, None]
    torch.testing.assert_close(moving_average(ramp, 3)[:, 1:-1], ramp[:, 1:-1])


def test_spreading_turns_a_staircase_into_a_ramp_and_keeps_the_distance_travelled():
    t = torch.arange(30)
    stairs = (t // 3).float()[None, :, None].repeat(2, 1, 4)  # one unit every third frame, flat in between
    spread = spread_boundary_steps(stairs, 3)
    steps = spread[:, 1:] - spread[:, :-1]
    assert steps[:, 6:-6].std() < 0.05 * stairs[:, 1:].sub(stairs[:, :-1]).std()  # the steps evened out
    torch.testing.assert_close(spread[:, -1], stairs[:, -1])  # the clip ends where it ended
    torch.testing.assert_close(spread[:, 0], stairs[:, 0])


def test_steady_motion_passes_unchanged_inside_the_clip():
    t = torch.arange(36.0)
    quaternions = _about_x(0.02 * t)[None, :, None].repeat(2, 1, 3, 1)  # a steady turn of 3 joints
    root = (0.1 * t)[None, :, None].repeat(2, 1, ROOT)
    poses = _poses(quaternions, root)
    smoothed = smooth_word_boundaries(poses, 3)
    assert smoothed.shape == poses.shape
    # the moving average of a slerp path is its chord mean, renormalised: equal to second order
    torch.testing.assert_close(smoothed[:, 1:-1], poses[:, 1:-1], atol=1e-4, rtol=0)


def test_signs_are_made_continuous_before_averaging():
    quaternions = _about_x(torch.full((1, 12, 1), 0.3))
    flipped = quaternions.clone()
    flipped[:, 5:] *= -1  # the same rotations, the other hemisphere from frame 5 on
    root = torch.zeros(1, 12, ROOT)
    torch.testing.assert_close(continuous_poses(_poses(flipped, root)), _poses(quaternions, root))
    smoothed = smooth_word_boundaries(_poses(flipped, torch.zeros(1, 12, ROOT)), 3)
    q = smoothed[..., :-ROOT].unflatten(-1, (-1, 4))
    torch.testing.assert_close(q.norm(dim=-1), torch.ones(1, 12, 1))
    torch.testing.assert_close(q, quaternions)  # no averaging of q with -q towards zero


def test_smoothing_is_deterministic_and_leaves_wordless_or_short_clips_alone():
    poses = _poses(
        _about_x(torch.rand(2, 30, 4, generator=torch.Generator().manual_seed(0))), torch.randn(2, 30, ROOT)
    )
    assert torch.equal(smooth_word_boundaries(poses, 3), smooth_word_boundaries(poses, 3))
    assert smooth_word_boundaries(poses, 1) is poses
    short = poses[:, :8]  # fewer than three words
    assert smooth_word_boundaries(short, 3) is short


@pytest.mark.parametrize(
    "poses, length, error, match",
    [
        (torch.zeros(30, 90), 3, ValueError, "poses"),
        (torch.zeros(2, 30, 7), 3, ValueError, r"\(J - 1\) \* 4 \+ 6"),
        (torch.full((2, 30, 90), float("nan")), 3, ValueError, "poses"),
        (torch.zeros(2, 30, 90), 0, ValueError, "word_length"),
        (torch.zeros(2, 30, 90), 1.5, TypeError, "word_length"),
    ],
)
def test_bad_input_is_refused_with_a_message(poses, length, error, match):
    with pytest.raises(error, match=match):
        smooth_word_boundaries(poses, length)
