"""Ground penetration, jerk and bone-length drift against hand computations on motions with known answers."""

import numpy as np
import pytest
import torch

from motionlab.metrics import (
    FOOT_JOINTS,
    bone_length_drift,
    ground_penetration,
    jerk,
    periodic_speed_power,
    speed_spectrum,
)
from motionlab.skeleton import PARENTS

FPS = 30.0


def test_penetration_is_the_mean_depth_of_the_feet_below_the_floor():
    motion = np.ones((4, 22, 3))
    motion[:, list(FOOT_JOINTS), 2] = 0.05
    motion[1, 7, 2] = -0.02  # one ankle 2 cm under the floor on one frame
    motion[2, 10, 2] = -0.04
    expected = (0.02 + 0.04) / (4 * len(FOOT_JOINTS))
    assert ground_penetration(motion) == pytest.approx(expected)
    assert ground_penetration(motion, floor=-0.03) == pytest.approx(0.01 / 16)
    assert ground_penetration(torch.as_tensor(motion)) == pytest.approx(expected)


def test_jerk_of_a_cubic_is_its_constant_third_derivative():
    t = np.arange(20) / FPS
    motion = np.zeros((2, 20, 22, 3))
    motion[..., 0] = (2.0 * t**3)[None, :, None]  # x''' = 12 m/s^3 for every joint
    assert jerk(motion, fps=FPS) == pytest.approx(12.0, rel=1e-6)
    still_then_jump = np.zeros((5, 22, 3))
    still_then_jump[4:, :, 1] = 0.001  # one step of 1 mm: the last third difference is 1 mm
    assert jerk(still_then_jump, fps=FPS) == pytest.approx(0.001 * FPS**3 / 2)


def test_jerk_grows_with_frame_noise_and_rejects_short_clips():
    rng = np.random.default_rng(0)
    smooth = np.cumsum(np.full((30, 22, 3), 0.01), axis=0)
    assert jerk(smooth) == pytest.approx(0.0, abs=1e-6)
    assert jerk(smooth + rng.normal(0, 0.005, smooth.shape)) > 10.0
    with pytest.raises(ValueError, match="at least 4 frames"):
        jerk(smooth[:3])


def test_bone_length_drift_is_zero_for_rigid_bones_and_the_std_otherwise():
    rng = np.random.default_rng(1)
    offsets = rng.normal(0, 0.2, (22, 3))
    rigid = np.zeros((10, 22, 3))
    for j, p in enumerate(PARENTS):  # rigidly translated skeleton
        rigid[:, j] = (0 if p < 0 else rigid[:, p]) + offsets[j] + np.arange(10)[:, None] * 0.1 * (p < 0)
    assert bone_length_drift(rigid, PARENTS) == pytest.approx(0.0, abs=1e-12)
    stretched = rigid.copy()
    stretched[:, 21] += (np.arange(10) % 2 * 0.1)[:, None] * (offsets[21] / np.linalg.norm(offsets[21]))
    lengths = [np.linalg.norm(stretched[t, 21] - stretched[t, PARENTS[21]]) for t in range(10)]
    assert bone_length_drift(stretched, PARENTS) == pytest.approx(np.std(lengths) / 21)


def test_bad_inputs_are_named():
    with pytest.raises(ValueError, match="ground_penetration: feet"):
        ground_penetration(np.zeros((3, 22, 3)), feet=(30,))
    with pytest.raises(ValueError, match="jerk: fps"):
        jerk(np.zeros((5, 22, 3)), fps=0)
    with pytest.raises(ValueError, match="bone_length_drift"):
        bone_length_drift(np.zeros((1, 22, 3)), PARENTS)


def test_periodic_speed_power_of_a_staircase_and_of_steady_motion():
    steps = np.zeros((2, 31, 1, 3))
    steps[:, :, 0, 0] = 0.03 * (np.arange(31) // 3)  # 3 cm every 3 frames: speed 0.9 m/s once per word
    # centred speed per 3 samples: (-0.3, -0.3, 0.6) m/s; its period-3 coefficient has modulus 0.9 per word,
    # 9 over the 10 words of the 30 samples: power 81 / 30
    assert periodic_speed_power(steps, 3) == pytest.approx(81 / 30, rel=1e-9)
    steady = np.zeros((31, 2, 3))
    steady[:, :, 1] = 0.01 * np.arange(31)[:, None]
    assert periodic_speed_power(steady, 3) == pytest.approx(0.0, abs=1e-12)
    slow = np.zeros((31, 1, 3))
    slow[:, 0, 0] = 0.1 * np.sin(2 * np.pi * np.arange(31) / 30)  # one cycle per clip: no 10 Hz content
    assert periodic_speed_power(slow, 3) < 1e-3 * periodic_speed_power(steps, 3)


def test_periodic_speed_power_rejects_bad_periods_and_short_clips():
    motion = np.zeros((31, 2, 3))
    with pytest.raises(ValueError, match="period"):
        periodic_speed_power(motion, 1)
    with pytest.raises(ValueError, match="whole number of frames"):
        periodic_speed_power(motion, 2.5)
    with pytest.raises(ValueError, match="at least 7 frames"):
        periodic_speed_power(motion[:6], 3)


def test_speed_spectrum_puts_a_speed_oscillation_at_its_frequency_and_keeps_its_variance():
    frames = np.arange(61)
    motion = np.zeros((3, 61, 2, 3))
    motion[..., 0] = (0.02 * frames + 0.002 * np.sin(2 * np.pi * 6 * frames / 30) / (2 * np.pi * 6 / 30))[
        None, :, None
    ]  # speed ~ 0.6 m/s plus a 6 Hz oscillation
    frequencies, power = speed_spectrum(motion, fps=30.0)
    assert frequencies.shape == power.shape == (31,)
    assert frequencies[np.argmax(power)] == pytest.approx(6.0)
    speed = np.abs(np.diff(motion[0, :, 0, 0])) * 30.0
    # Parseval: the full spectrum (the one-sided one with its inner bins twice) sums to n times the variance
    total = power[0] + 2 * power[1:-1].sum() + power[-1]
    assert total == pytest.approx(60 * speed.var(), rel=1e-9)
    with pytest.raises(ValueError, match="n_samples"):
        speed_spectrum(motion, n_samples=61)
