"""Realism metrics against independent computations: scipy's periodogram, exact interpolation, rigid
bodies."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import periodogram

from motionlab.metrics import realism


@pytest.mark.parametrize("n_frames", [50, 51])
def test_velocity_spectrum_matches_scipy(n_frames: int) -> None:
    clip = np.random.default_rng(n_frames).normal(size=(n_frames, 4, 3))
    freqs, power = realism.velocity_spectrum(clip, 12.0)
    velocity = np.diff(clip, axis=0).reshape(n_frames - 1, -1) * 12.0
    want_freqs, want = periodogram(velocity, fs=12.0, window="hann", axis=0, detrend="constant")
    np.testing.assert_allclose(freqs, want_freqs)
    np.testing.assert_allclose(power, want.sum(axis=1), rtol=1e-10)


def test_velocity_spectrum_finds_a_sine() -> None:
    t = np.arange(120) / 12.0
    clip = np.zeros((120, 2, 3))
    clip[:, 1, 0] = np.sin(2 * np.pi * 2.0 * t)
    freqs, power = realism.velocity_spectrum(clip, 12.0)
    assert freqs[np.argmax(power)] == pytest.approx(2.0, abs=0.1)


def test_bone_length_variation_is_zero_for_a_rigid_body_and_matches_a_hand_count() -> None:
    parents = (-1, 0, 1)
    rigid = np.array([[[0, 0, 0], [1, 0, 0], [1, 2, 0]]], dtype=float) + np.arange(5)[:, None, None]
    np.testing.assert_allclose(realism.bone_length_variation(rigid, parents), 0.0, atol=1e-12)
    breathing = np.array([[[0, 0, 0], [length, 0, 0], [length, 1, 0]] for length in (1.0, 3.0)])
    np.testing.assert_allclose(realism.bone_length_variation(breathing, parents), [0.5, 0.0], atol=1e-12)


def test_resample_is_exact_for_linear_motion() -> None:
    times = np.arange(31) / 30.0
    clip = np.stack([np.stack([times, 2 * times, -times], -1)] * 2, axis=1)  # (31, 2, 3)
    out = realism.resample(clip, 30.0, 12.0)
    assert out.shape == (13, 2, 3)
    np.testing.assert_allclose(out[:, 0, 0], np.arange(13) / 12.0, atol=1e-12)


def test_facing_root_path_turns_the_start_to_face_x() -> None:
    # hips along x (left hip at +x): facing -y; walking along -y must become walking along +x
    clip = np.zeros((5, 3, 3))
    clip[:, 0, 1] = -np.arange(5.0)
    clip[:, 1, 0], clip[:, 2, 0] = 0.1, -0.1
    clip[:, 1:, 1] = clip[:, :1, 1]
    path = realism.facing_root_path(clip, 1, 2)
    np.testing.assert_allclose(path, np.stack([np.arange(5.0), np.zeros(5)], -1), atol=1e-12)


def test_contact_share_counts_planted_frames() -> None:
    clip = np.zeros((10, 2, 3))
    clip[5:, 1, 2] = 0.5  # the second joint lifts off after 5 frames
    np.testing.assert_allclose(realism.contact_share(clip, (0, 1), fps=12.0), [1.0, 0.5])


def test_refusals() -> None:
    with pytest.raises(ValueError, match="T >= 4"):
        realism.velocity_spectrum(np.zeros((3, 2, 3)), 12.0)
    with pytest.raises(ValueError, match="fps"):
        realism.resample(np.zeros((5, 2, 3)), 0.0, 12.0)
