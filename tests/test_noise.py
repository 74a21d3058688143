"""The motion-capture noise model: jitter and spike statistics against their distributions."""

import numpy as np
import pytest
from scipy import stats
from scipy.spatial.transform import Rotation

from motionlab.data.noise import ROTATION_NOISE, NoiseConfig, add_position_noise, add_rotation_noise

SHAPE = (40, 120, 22)


@pytest.fixture(scope="module")
def clean_positions():
    return np.random.default_rng(0).normal(size=SHAPE + (3,)).astype(np.float32)


def test_position_jitter_is_gaussian_with_the_configured_spread(clean_positions):
    config = NoiseConfig(jitter=0.02, spike_rate=0.0)
    noisy, mask = add_position_noise(clean_positions, 1, config)
    assert noisy.dtype == np.float32 and noisy.shape == clean_positions.shape and not mask.any()
    error = (noisy.astype(np.float64) - clean_positions).ravel()
    assert error.std() == pytest.approx(0.02, rel=0.01)
    assert abs(error.mean()) < 1e-4
    assert stats.kstest(error / 0.02, "norm").pvalue > 1e-3


def test_position_spikes_follow_rate_length_and_size(clean_positions):
    config = NoiseConfig(jitter=0.0, spike_rate=0.01, spike_frames=(2, 5), spike_size=0.3)
    noisy, mask = add_position_noise(clean_positions, 2, config)
    error = np.linalg.norm(noisy.astype(np.float64) - clean_positions, axis=-1)
    np.testing.assert_array_equal(error > 1e-6, mask)  # exactly the masked entries move
    assert error[mask].min() >= 0.15 - 1e-5 and error[mask].max() <= 0.45 + 1e-5
    # mask runs: starts at the configured rate (binomial), each run 2..5 frames long unless merged or cut
    starts = mask & ~np.concatenate([np.zeros_like(mask[:, :1]), mask[:, :-1]], axis=1)
    expected = config.spike_rate * mask.size
    assert abs(starts.sum() - expected) < 5 * np.sqrt(expected)
    lengths = []
    for clip, joint in zip(*np.nonzero(starts.any(axis=1))):
        run = np.diff(np.concatenate([[0], mask[clip, :, joint].astype(int), [0]]))
        lengths += list(np.flatnonzero(run == -1) - np.flatnonzero(run == 1))
    assert min(lengths) >= 1 and np.median(lengths) in (3, 3.5, 4)
    # within one spike the displacement stays the same (the joint jumps away and stays there)
    clip, frame, joint = np.argwhere(starts)[0]
    first = noisy[clip, frame, joint] - clean_positions[clip, frame, joint]
    second = noisy[clip, frame + 1, joint] - clean_positions[clip, frame + 1, joint]
    np.testing.assert_allclose(second, first, atol=1e-6)


def test_noise_is_seeded_and_validated(clean_positions):
    a = add_position_noise(clean_positions, 7)
    b = add_position_noise(clean_positions, np.random.default_rng(7))
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.array_equal(add_position_noise(clean_positions, 8)[0], a[0])
    with pytest.raises(ValueError, match=r"add_position_noise: positions must have shape \(\.\.\., \*, 3\)"):
        add_position_noise(clean_positions[..., :2], 0)
    with pytest.raises(TypeError, match="add_position_noise: positions must have a floating-point dtype"):
        add_position_noise(clean_positions.astype(np.int64), 0)
    bad = clean_positions.copy()
    bad[0, 0, 0, 0] = np.nan
    with pytest.raises(
        ValueError, match=r"positions contains NaN or infinite values \(first at index \(0, 0, 0, 0\)\)"
    ):
        add_position_noise(bad, 0)
    with pytest.raises(ValueError, match="add_position_noise: rng must be a non-negative integer seed"):
        add_position_noise(clean_positions, -1)
    with pytest.raises(TypeError, match="add_rotation_noise: rng must be a numpy.random.Generator"):
        add_rotation_noise(np.ones((1, 2, 3, 4)) / 2, 0.5)
    with pytest.raises(ValueError, match=r"NoiseConfig: spike_frames\[1\] must be at least 3, got 2"):
        NoiseConfig(spike_frames=(3, 2))
    with pytest.raises(TypeError, match=r"NoiseConfig: spike_frames\[0\] must be an integer"):
        NoiseConfig(spike_frames=(1.5, 2))
    with pytest.raises(ValueError, match="NoiseConfig: jitter must be at least 0, got -0.1"):
        NoiseConfig(jitter=-0.1)
    with pytest.raises(
        ValueError, match="NoiseConfig: spike_rate .a probability per frame and joint. must be in"
    ):
        NoiseConfig(spike_rate=2.0)


def _angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation angles (flat) between quaternion arrays ``(..., 4)`` w first, by scipy."""
    rotation_a = Rotation.from_quat(a.reshape(-1, 4)[:, [1, 2, 3, 0]])
    rotation_b = Rotation.from_quat(b.reshape(-1, 4)[:, [1, 2, 3, 0]])
    return (rotation_a * rotation_b.inv()).magnitude()


def test_rotation_noise_angles_match_their_distributions():
    clean = Rotation.random(20 * 60 * 22, random_state=3).as_quat()[:, [3, 0, 1, 2]].reshape(20, 60, 22, 4)
    sigma = 0.05
    noisy, mask = add_rotation_noise(clean, 4, NoiseConfig(jitter=sigma, spike_rate=0.0))
    assert not mask.any()
    np.testing.assert_allclose(np.linalg.norm(noisy, axis=-1), 1.0, atol=1e-12)
    assert np.all(np.sum(noisy * clean, axis=-1) > 0)  # the sign of each clean quaternion is kept
    angle = _angle_between(noisy, clean)
    assert stats.kstest(angle / sigma, stats.maxwell.cdf).pvalue > 1e-3  # |Gaussian rotation vector|

    noisy, mask = add_rotation_noise(clean, 5, NoiseConfig(jitter=0.0, spike_rate=0.02, spike_size=0.5))
    angle = _angle_between(noisy, clean).reshape(mask.shape)
    assert mask.mean() > 0.02
    assert angle[~mask].max() < 1e-6 and angle[mask].min() >= 0.25 - 1e-6 and angle[mask].max() <= 0.75 + 1e-6
    assert (
        ROTATION_NOISE.spike_size == 0.5
        and add_rotation_noise(clean.astype(np.float32), 0)[0].dtype == np.float32
    )
