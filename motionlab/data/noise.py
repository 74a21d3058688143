"""A motion-capture noise model, for denoising experiments (the Motion Cell paper's first step).

Real optical capture has two kinds of error: small **jitter** on every frame (marker noise) and sparse
**spikes**: when markers are occluded or swapped, a joint jumps away for a few frames and comes back.
Both functions below add the two to clean data and return the spike mask, the ground truth a
denoiser can be scored against.

- :func:`add_position_noise`: joint positions ``(..., T, J, 3)``; jitter is Gaussian with standard
  deviation ``jitter`` metres per coordinate; a spike displaces the joint by a fixed vector in a random
  direction with length uniform in ``[spike_size / 2, 3 spike_size / 2]``.
- :func:`add_rotation_noise`: local quaternions ``(..., T, J, 4)``; jitter is a rotation whose
  rotation vector is Gaussian with standard deviation ``jitter`` radians per axis; a spike is a fixed
  extra rotation by an angle uniform in ``[spike_size / 2, 3 spike_size / 2]`` about a random axis.

A spike starts at a (frame, joint) with probability ``spike_rate`` and lasts a uniform number of frames
in ``spike_frames`` (inclusive), cut at the end of the clip; where spikes overlap the later one wins.
Everything is drawn from one ``numpy.random.Generator`` (or a seed for one), in a fixed order.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np
import torch

from motionlab.geometry import axis_angle_to_quat, quat_mul
from motionlab.validation import Checked, as_rng, check_array, check_scalar, real, tuple_of


@dataclass(frozen=True)
class NoiseConfig(Checked):
    """Noise levels; lengths in metres for positions and angles in radians for rotations."""

    jitter: float = real(0.01, minimum=0)
    spike_rate: float = real(0.002, minimum=0, maximum=1, note="a probability per frame and joint")
    spike_frames: tuple[int, int] = tuple_of((2, 5), kind=numbers.Integral, minimum=1, length=2)
    spike_size: float = real(0.15, minimum=0)

    def __post_init__(self) -> None:
        super().__post_init__()
        check_scalar(self.spike_frames[1], "spike_frames[1]", "NoiseConfig", minimum=self.spike_frames[0])


#: Defaults for rotations: 0.02 rad jitter, spikes of about 0.5 rad (29 degrees).
ROTATION_NOISE = NoiseConfig(jitter=0.02, spike_size=0.5)


def _spikes(
    shape: tuple[int, ...], rng: np.random.Generator, config: NoiseConfig, displacement: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Spike mask ``shape = (..., T, J)`` and the per-frame spike vectors ``(..., T, J, D)``.

    ``displacement`` ``(..., T, J, D)`` holds a candidate vector for a spike starting at each frame.
    """
    lo, hi = config.spike_frames
    starts = rng.random(shape) < config.spike_rate
    lengths = rng.integers(lo, hi + 1, size=shape)
    mask = np.zeros(shape, bool)
    vectors = np.zeros(displacement.shape)
    n_frames = shape[-2]
    for offset in range(min(hi, n_frames)):
        covered = (starts & (lengths > offset))[
            ..., : n_frames - offset, :
        ]  # spikes still on `offset` frames later
        mask[..., offset:, :] |= covered
        vectors[..., offset:, :, :] = np.where(
            covered[..., None], displacement[..., : n_frames - offset, :, :], vectors[..., offset:, :, :]
        )
    return mask, vectors


def _random_directions(shape: tuple[int, ...], rng: np.random.Generator) -> np.ndarray:
    """Unit vectors ``shape + (3,)`` uniform on the sphere."""
    v = rng.standard_normal(shape + (3,))
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _spike_lengths(shape: tuple[int, ...], rng: np.random.Generator, size: float) -> np.ndarray:
    return size * rng.uniform(0.5, 1.5, size=shape + (1,))


def add_position_noise(
    positions: np.ndarray, rng: np.random.Generator | int, config: NoiseConfig = NoiseConfig()
) -> tuple[np.ndarray, np.ndarray]:
    """Noisy joint positions (same shape and dtype) and the spike mask ``(..., T, J)`` bool."""
    clean = check_array(positions, "positions", "add_position_noise", trailing=(None, 3), min_leading=1)
    rng = as_rng(rng, "add_position_noise")
    shape = clean.shape[:-1]
    jitter = config.jitter * rng.standard_normal(clean.shape)
    displacement = _random_directions(shape, rng) * _spike_lengths(shape, rng, config.spike_size)
    mask, spikes = _spikes(shape, rng, config, displacement)
    return (clean + jitter + spikes).astype(clean.dtype), mask


def add_rotation_noise(
    rotations: np.ndarray, rng: np.random.Generator | int, config: NoiseConfig = ROTATION_NOISE
) -> tuple[np.ndarray, np.ndarray]:
    """Noisy local quaternions (same shape and dtype, w first) and the spike mask ``(..., T, J)``.

    The noise rotation is applied on the left (in the parent's frame) and is less than a half turn, so
    each noisy quaternion keeps the sign of its clean one (sign-continuous data stays continuous).
    """
    clean = check_array(rotations, "rotations", "add_rotation_noise", trailing=(None, 4), min_leading=1)
    rng = as_rng(rng, "add_rotation_noise")
    shape = clean.shape[:-1]
    jitter = config.jitter * rng.standard_normal(shape + (3,))
    displacement = _random_directions(shape, rng) * _spike_lengths(shape, rng, config.spike_size)
    mask, spikes = _spikes(shape, rng, config, displacement)
    perturbation = quat_mul(
        axis_angle_to_quat(torch.from_numpy(spikes)), axis_angle_to_quat(torch.from_numpy(jitter))
    )
    noisy = quat_mul(perturbation, torch.from_numpy(clean.astype(np.float64)))
    return noisy.numpy().astype(clean.dtype), mask
