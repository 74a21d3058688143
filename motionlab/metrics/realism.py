"""What tells recorded motion from clean synthetic motion: bone-length variation, speed and acceleration
spectra, foot contacts.

Positions are ``(T, J, 3)`` world coordinates in metres, z up, at ``fps`` frames per second.

* :func:`bone_length_variation`: for each bone, the coefficient of variation of its length over the
  frames of a clip (standard deviation over mean). Forward kinematics of a rigid skeleton gives 0;
  optical capture gives joint centres estimated from skin markers, whose distances breathe.
* :func:`velocity_spectrum`: the power spectral density of the joint velocities (root included), summed
  over joints and axes, from a Hann-windowed periodogram (one-sided, ``(m/s)^2 / Hz``). Where the power sits
  in frequency says how smooth the motion is; a recording at 12 fps holds nothing above 6 Hz.
* :func:`contact_share`: the share of frames on which each foot joint is planted (low and slow, as
  :func:`motionlab.metrics.physical.infer_foot_contacts`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motionlab.metrics.physical import bone_lengths, infer_foot_contacts
from motionlab.validation import ArrayLike, as_float_array, check_scalar


def _clip(positions: ArrayLike, func: str, min_frames: int = 2) -> np.ndarray:
    x = as_float_array(positions, "positions", func, min_ndim=3, layout="(T, J, 3)")
    if x.ndim != 3 or x.shape[-1] != 3 or x.shape[0] < min_frames:
        raise ValueError(f"{func}: positions must be (T >= {min_frames}, J, 3), got shape {x.shape}")
    return x


def bone_length_variation(positions: ArrayLike, parents: ArrayLike | Sequence[int]) -> np.ndarray:
    """Coefficient of variation of every bone's length over the frames of a clip ``(T, J, 3)``: ``(B,)``,
    bones in the order of :func:`~motionlab.metrics.physical.bone_lengths` (non-root joints)."""
    lengths = bone_lengths(_clip(positions, "bone_length_variation"), parents)
    return lengths.std(axis=0) / lengths.mean(axis=0)


def velocity_spectrum(positions: ArrayLike, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies ``(F,)`` (Hz, 0 to ``fps / 2``) and the power spectral density ``(F,)`` of the joint
    velocities of a clip ``(T, J, 3)`` (velocities by frame differences, ``T - 1`` of them), summed over
    joints and axes: a Hann-windowed, one-sided periodogram with the mean velocity removed."""
    func = "velocity_spectrum"
    x = _clip(positions, func, min_frames=4)
    rate = float(check_scalar(fps, "fps", func, minimum=0, include_minimum=False))
    velocity = np.diff(x, axis=0).reshape(x.shape[0] - 1, -1) * rate
    velocity = velocity - velocity.mean(axis=0)
    n = velocity.shape[0]
    window = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n) / n)  # periodic Hann
    spectrum = np.abs(np.fft.rfft(velocity * window[:, None], axis=0)) ** 2 / (rate * (window**2).sum())
    spectrum[1 : (n + 1) // 2] *= 2  # one-sided: every frequency but 0 and (for even n) Nyquist twice
    return np.fft.rfftfreq(n, d=1.0 / rate), spectrum.sum(axis=1)


def contact_share(
    positions: ArrayLike,
    feet: Sequence[int],
    fps: float,
    height_threshold: float = 0.05,
    speed_threshold: float = 1.0,
) -> np.ndarray:
    """Share of the frames of a clip ``(T, J, 3)`` on which each joint of ``feet`` is planted ``(F,)``."""
    x = _clip(positions, "contact_share")
    contacts = infer_foot_contacts(
        x, fps=fps, height_threshold=height_threshold, speed_threshold=speed_threshold, feet=feet
    )
    return contacts.mean(axis=0)


def resample(positions: ArrayLike, fps: float, new_fps: float) -> np.ndarray:
    """A clip ``(T, J, 3)`` at ``fps`` linearly interpolated to ``new_fps`` over the same duration:
    ``(floor((T - 1) new_fps / fps) + 1, J, 3)``, frame ``t`` at time ``t / new_fps``."""
    func = "resample"
    x = _clip(positions, func)
    rate = float(check_scalar(fps, "fps", func, minimum=0, include_minimum=False))
    new_rate = float(check_scalar(new_fps, "new_fps", func, minimum=0, include_minimum=False))
    times = np.arange(int(np.floor((x.shape[0] - 1) * new_rate / rate + 1e-9)) + 1) * rate / new_rate
    flat = x.reshape(x.shape[0], -1)
    columns = [np.interp(times, np.arange(x.shape[0]), flat[:, channel]) for channel in range(flat.shape[1])]
    return np.stack(columns, axis=-1).reshape((len(times),) + x.shape[1:])


def facing_root_path(positions: ArrayLike, left_hip: int, right_hip: int) -> np.ndarray:
    """The root's path on the floor ``(T, 2)`` of a clip ``(T, J, 3)``, from the origin, turned so that the
    first frame faces +x (forward = the right-to-left hip vector turned by -90 degrees about z)."""
    x = _clip(positions, "facing_root_path")
    across = x[0, left_hip, :2] - x[0, right_hip, :2]
    yaw = np.arctan2(-across[0], across[1])
    path = x[:, 0, :2] - x[0, 0, :2]
    cos, sin = np.cos(-yaw), np.sin(-yaw)
    return path @ np.array([[cos, sin], [-sin, cos]])
