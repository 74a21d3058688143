"""Control-adherence and stability measures against hand computations; the fixed-length Glow helpers."""

import math

import numpy as np
import pytest
import torch

from motionlab.models.flows import Glow
from motionlab.models.moglow import (
    MoGlowFeatures,
    control_mismatch,
    experiment,
    fixed_length,
    gait_speed,
    joint_speed,
    speed_ratio,
    support_foot_slide,
)
from motionlab.models.moglow.evaluate import moving_average


def _walking_feet(frames: int, speed: float, fps: float = 30.0) -> torch.Tensor:
    """World positions (T, 22, 3): the left toe planted at x = 0, everything else 0.3 m up, pelvis moving."""
    positions = torch.zeros(frames, 22, 3)
    positions[..., 2] = 0.3
    positions[:, 10, 2] = 0.0
    positions[:, 0, 0] = torch.arange(frames) * speed / fps
    return positions


def test_support_foot_slide_by_hand():
    planted = _walking_feet(31, 1.0)
    assert float(support_foot_slide(planted)) == 0.0
    sliding = planted.clone()
    sliding[:, 10, 0] = torch.arange(31) * 0.02  # 0.6 m/s
    assert math.isclose(float(support_foot_slide(sliding)), 0.6, rel_tol=1e-5)
    with pytest.raises(ValueError):
        support_foot_slide(torch.zeros(1, 22, 3))


def _pose_with_foot_track(x_of_t: torch.Tensor) -> torch.Tensor:
    """MoGlow poses (T, 64): every joint 0.3 m up except the left toe (joint 10), on the floor at x(t)."""
    pose = torch.zeros(x_of_t.shape[0], 64)
    pose[:, 3::3] = 0.3  # z of joints 1..21
    pose[:, 1 + 3 * 9] = x_of_t  # x of joint 10
    pose[:, 1 + 3 * 9 + 2] = 0.0
    return pose


def test_gait_speed_and_control_mismatch_by_hand():
    frames = 61
    pose = _pose_with_foot_track(-torch.arange(frames) * 1.2 / 30)  # the support foot slides back at 1.2 m/s
    np.testing.assert_allclose(gait_speed(pose).numpy(), 1.2, rtol=1e-5)
    matching = torch.zeros(frames, 3)
    matching[:, 0] = 1.2 / 30
    assert float(control_mismatch(pose, matching)) < 1e-5
    standing = torch.zeros(frames, 3)  # told to stand still but still stepping: mismatch = the gait speed
    assert math.isclose(float(control_mismatch(pose, standing)), 1.2, rel_tol=1e-5)
    jitter = pose.clone()
    jitter[:, 1 + 3 * 9] += 0.01 * torch.tensor([1.0, -1.0]).repeat(31)[:frames]  # +-1 cm per frame
    assert float(control_mismatch(jitter, matching)) < 0.05  # averaged out within the windows
    with pytest.raises(ValueError):
        control_mismatch(pose[:10], matching[:10])


def test_joint_speed_and_ratio():
    pose = torch.zeros(2, 40, 64)
    pose[:, :, 1::3] = (torch.arange(40) / 30.0)[None, :, None]  # every joint moves 1 m/s along x
    np.testing.assert_allclose(joint_speed(pose).numpy(), 1.0, rtol=1e-5)
    slowing = pose.clone()
    slowing[:, 20:, 1::3] = slowing[:, 20:21, 1::3] + 0.5 * (slowing[:, 20:, 1::3] - slowing[:, 20:21, 1::3])
    assert math.isclose(speed_ratio(slowing, window=10), 0.5, rel_tol=1e-4)
    with pytest.raises(ValueError):
        speed_ratio(pose, window=30)


def test_moving_average_by_hand():
    series = torch.arange(5.0)
    assert torch.allclose(moving_average(series, 3), torch.tensor([1 / 3, 1.0, 2.0, 3.0, 11 / 3]))
    assert torch.equal(moving_average(series, 1), series)
    assert moving_average(series, 4).shape == (5,)
    with pytest.raises(ValueError):
        moving_average(series[None], 3)


def test_fixed_length_helpers():
    torch.manual_seed(0)
    features = MoGlowFeatures(torch.randn(3, 120, 64), torch.randn(3, 120, 3))
    x, cond = fixed_length.channels_first(features)
    assert x.shape == (3, 64, 120) and cond.shape == (3, 3, 120) and x.is_contiguous()
    cfg = fixed_length.glow_config(experiment.ExperimentConfig.quick())
    model = Glow(cfg)
    loss = fixed_length.glow_nll_loss(model, (x, cond), 0, {})
    with torch.no_grad():
        expected = float(-model.log_prob(x, cond).mean()) / (64 * 120)
    assert math.isclose(float(loss["loss"].detach()), expected, rel_tol=1e-5)
