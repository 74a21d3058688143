"""Physical plausibility of joint-position motion: foot skating, ground penetration, jerk, bone-length
error and drift.

Positions are world coordinates in metres, ``(..., T, J, 3)``, z up (so "horizontal" means x and y),
sampled at ``fps`` frames per second.

**Foot skating**: the mean horizontal speed (m/s) of the foot joints while they are in contact with the
ground. A foot frame interval ``t → t+1`` counts when the foot is in contact at both ends. Real planted
feet barely move, so lower is better. When contacts are not given they are inferred per frame: the foot
is low (less than ``height_threshold`` above the lowest height that joint reaches in the clip) and slow
(horizontal speed, by central differences, below ``speed_threshold``). Heights are relative to each
joint's own minimum so that ankles, which never touch the floor, are handled like toes.

**Ground penetration**: the mean depth (m) of the foot joints below the floor, ``max(0, floor - z)``, over
frames and feet; a body that stands on the floor gives 0.

**Jerk**: the mean norm (m/s³) of the third time derivative of every joint's position (third finite
differences times ``fps³``). Real motion is smooth; a generator that adds frame-to-frame noise has a large
jerk even when each pose looks right.

**Speed spectrum**: the power spectrum of the joint-speed signal (mean over joints of each joint's speed,
one value per frame interval) after removing each clip's mean speed: the squared modulus of each Fourier
coefficient divided by the number of samples, averaged over clips (m²/s²). **Periodic speed power** is its
value at one frequency, ``fps / period``: a generator that steps every ``period`` frames puts a line there,
where real motion has almost nothing. Compare it as a ratio to real clips'.

**Bone-length drift**: the standard deviation over frames of each bone's length, averaged over bones and
clips (m). It needs no reference skeleton: a model that outputs joint rotations and applies forward
kinematics gives exactly 0; a model that outputs joint positions lets bones stretch and shrink.

**Bone-length error**: the mean absolute difference, over frames and bones, between the distances of each
joint to its parent and the skeleton's reference bone lengths. Rigid bones give 0.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

import numpy as np

from motionlab.validation import ArrayLike, as_float_array, check_scalar

#: Foot joints of the default 22-joint skeleton: left/right ankle (7, 8) and left/right foot (10, 11).
FOOT_JOINTS = (7, 8, 10, 11)


def _positions(positions: ArrayLike, func: str, min_frames: int = 1) -> np.ndarray:
    x = as_float_array(positions, "positions", func, min_ndim=3, layout="(..., T, J, 3)")
    if x.shape[-1] != 3:
        raise ValueError(f"{func}: positions must end in 3 coordinates (x, y, z), got shape {x.shape}")
    if x.shape[-3] < min_frames:
        raise ValueError(f"{func}: positions needs at least {min_frames} frames, got {x.shape[-3]}")
    return x


def _foot_indices(feet: Sequence[int], n_joints: int, func: str) -> list[int]:
    indices = [int(j) for j in feet]
    if not indices or len(set(indices)) != len(indices) or min(indices) < 0 or max(indices) >= n_joints:
        raise ValueError(f"{func}: feet must be distinct joint indices in [0, {n_joints}), got {list(feet)}")
    return indices


def infer_foot_contacts(
    positions: ArrayLike,
    *,
    fps: float = 30.0,
    height_threshold: float = 0.05,
    speed_threshold: float = 1.0,
    feet: Sequence[int] = FOOT_JOINTS,
) -> np.ndarray:
    """Per-frame contact flags of the foot joints, ``(..., T, F)`` booleans (``F = len(feet)``).

    A foot is in contact on a frame when its height above its own lowest point in the clip is below
    ``height_threshold`` (m) and its horizontal speed (central differences) is below ``speed_threshold``
    (m/s).
    """
    func = "infer_foot_contacts"
    x = _positions(positions, func, min_frames=2)
    indices = _foot_indices(feet, x.shape[-2], func)
    rate = float(check_scalar(fps, "fps", func, minimum=0, include_minimum=False))
    return _contacts(x, indices, rate, height_threshold, speed_threshold, func)


def _contacts(
    x: np.ndarray, feet: list[int], fps: float, height_threshold: float, speed_threshold: float, func: str
) -> np.ndarray:
    """Contact flags ``(..., T, F)`` of the joints ``feet`` in positions ``x`` ``(..., T, J, 3)``."""
    max_height = float(
        check_scalar(height_threshold, "height_threshold", func, minimum=0, include_minimum=False)
    )
    max_speed = float(
        check_scalar(speed_threshold, "speed_threshold", func, minimum=0, include_minimum=False)
    )
    foot = x[..., feet, :]
    height = foot[..., 2] - foot[..., 2].min(axis=-2, keepdims=True)
    speed = np.linalg.norm(np.gradient(foot[..., :2], axis=-3), axis=-1) * fps
    return (height < max_height) & (speed < max_speed)


def foot_skating(
    positions: ArrayLike,
    contacts: ArrayLike | None = None,
    *,
    fps: float = 30.0,
    height_threshold: float = 0.05,
    speed_threshold: float = 1.0,
    feet: Sequence[int] = FOOT_JOINTS,
    never_planted: Literal["raise", "nan"] = "raise",
) -> float:
    """Mean horizontal speed (m/s) of the foot joints over frame intervals where the foot is planted.

    Args:
        positions: joint positions ``(..., T, J, 3)``, z up, metres.
        contacts: per-frame contact flags ``(..., T, F)`` for the joints in ``feet`` (booleans or 0/1);
            ``None`` infers them with :func:`infer_foot_contacts` and the thresholds below.
        fps: frame rate.
        height_threshold, speed_threshold: contact inference thresholds (m, m/s); unused with ``contacts``.
        feet: the foot joints (default :data:`FOOT_JOINTS`, the default skeleton's ankles and feet).
        never_planted: when no foot is in contact on two consecutive frames the metric is undefined:
            ``"raise"`` a ``ValueError`` (the default), or return ``nan``, for a caller that reports such
            motion as such (a generator whose feet never stand still, e.g. one that samples noise).

    Raises:
        ValueError: when no foot is in contact on two consecutive frames and ``never_planted`` is ``"raise"``.
    """
    func = "foot_skating"
    if never_planted not in ("raise", "nan"):
        raise ValueError(f"{func}: never_planted must be 'raise' or 'nan', got {never_planted!r}")
    x = _positions(positions, func, min_frames=2)
    indices = _foot_indices(feet, x.shape[-2], func)
    rate = float(check_scalar(fps, "fps", func, minimum=0, include_minimum=False))
    if contacts is None:
        planted = _contacts(x, indices, rate, height_threshold, speed_threshold, func)
    else:
        flags = as_float_array(contacts, "contacts", func, ndim=x.ndim - 1, layout="(..., T, F)")
        expected = x.shape[:-2] + (len(indices),)
        if flags.shape != expected:
            raise ValueError(
                f"{func}: contacts must have shape {expected} (frames x feet), got {flags.shape}"
            )
        if not np.isin(flags, (0.0, 1.0)).all():
            raise ValueError(f"{func}: contacts must be booleans or 0/1")
        planted = flags.astype(bool)
    both_ends = planted[..., 1:, :] & planted[..., :-1, :]
    if not both_ends.any():
        if never_planted == "nan":
            return math.nan
        raise ValueError(
            f"{func}: no foot is in contact on two consecutive frames, so there is nothing to measure"
        )
    horizontal = x[..., indices, :2]
    speed = np.linalg.norm(np.diff(horizontal, axis=-3), axis=-1) * rate
    return float(speed[both_ends].mean())


def _parents(parents: ArrayLike | Sequence[int], n_joints: int, func: str) -> np.ndarray:
    p = np.asarray(parents)
    if p.size and p.dtype.kind not in "iu":  # an empty list is a wrong length, not a wrong type
        raise TypeError(f"{func}: parents must be {n_joints} integers (one per joint), got dtype {p.dtype}")
    if p.ndim != 1 or p.shape[0] != n_joints:
        raise ValueError(f"{func}: parents must be {n_joints} integers (one per joint), got {p.tolist()}")
    joints = np.arange(n_joints)
    if (p < -1).any() or (p >= n_joints).any() or (p == joints).any() or not (p == -1).any():
        raise ValueError(
            f"{func}: parents must lie in [-1, {n_joints}), name no joint as its own parent, "
            f"and have a root (-1); got {p.tolist()}"
        )
    return p


def _bone_lengths(positions: ArrayLike, parents: ArrayLike | Sequence[int], func: str) -> np.ndarray:
    x = as_float_array(positions, "positions", func, min_ndim=2, layout="(..., J, 3)")
    if x.shape[-1] != 3:
        raise ValueError(f"{func}: positions must end in 3 coordinates, got shape {x.shape}")
    p = _parents(parents, x.shape[-2], func)
    children = np.flatnonzero(p >= 0)
    return np.linalg.norm(x[..., children, :] - x[..., p[children], :], axis=-1)


def bone_lengths(positions: ArrayLike, parents: ArrayLike | Sequence[int]) -> np.ndarray:
    """Distance of every non-root joint to its parent, ``(..., B)``, non-root joints in joint order.

    Args:
        positions: joint positions ``(..., J, 3)``.
        parents: parent index of each joint ``(J,)``, ``-1`` for roots.
    """
    return _bone_lengths(positions, parents, "bone_lengths")


def bone_length_error(
    positions: ArrayLike, parents: ArrayLike | Sequence[int], reference_offsets_or_lengths: ArrayLike
) -> float:
    """Mean absolute deviation (m) of the bone lengths in ``positions`` from the reference skeleton.

    Args:
        positions: joint positions ``(..., J, 3)``.
        parents: parent index of each joint ``(J,)``, ``-1`` for roots.
        reference_offsets_or_lengths: either rest offsets ``(J, 3)`` of each joint from its parent, or bone
            lengths ``(J,)`` indexed by child joint. Root entries are ignored.
    """
    func = "bone_length_error"
    measured = _bone_lengths(positions, parents, func)
    n_joints = len(parents)
    ref = as_float_array(reference_offsets_or_lengths, "reference_offsets_or_lengths", func, min_ndim=1)
    if ref.shape == (n_joints, 3):
        ref = np.linalg.norm(ref, axis=-1)
    elif ref.shape != (n_joints,):
        raise ValueError(
            f"{func}: reference_offsets_or_lengths must be offsets ({n_joints}, 3) or lengths "
            f"({n_joints},), got {ref.shape}"
        )
    reference = ref[np.asarray(parents) >= 0]
    return float(np.abs(measured - reference).mean())


def ground_penetration(
    positions: ArrayLike, *, floor: float = 0.0, feet: Sequence[int] = FOOT_JOINTS
) -> float:
    """Mean depth (m) of the foot joints below the floor, ``mean(max(0, floor - z))`` over frames and feet.

    Args:
        positions: joint positions ``(..., T, J, 3)``, z up, metres.
        floor: the floor's height (m).
        feet: the joints that touch the floor (default :data:`FOOT_JOINTS`).
    """
    func = "ground_penetration"
    x = _positions(positions, func)
    indices = _foot_indices(feet, x.shape[-2], func)
    level = float(check_scalar(floor, "floor", func))
    return float(np.maximum(level - x[..., indices, 2], 0.0).mean())


def jerk(positions: ArrayLike, *, fps: float = 30.0) -> float:
    """Mean norm (m/s³) of the third time derivative of the joint positions.

    Args:
        positions: joint positions ``(..., T, J, 3)`` with ``T >= 4``.
        fps: frame rate (the derivative is the third finite difference times ``fps ** 3``).
    """
    func = "jerk"
    x = _positions(positions, func, min_frames=4)
    rate = float(check_scalar(fps, "fps", func, minimum=0, include_minimum=False))
    return float(np.linalg.norm(np.diff(x, n=3, axis=-3), axis=-1).mean() * rate**3)


def speed_spectrum(
    positions: ArrayLike, *, fps: float = 30.0, n_samples: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Power spectrum of the joint-speed signal, mean over clips: frequencies (Hz) and power (m²/s²).

    The speed signal of a clip is the mean over joints of each joint's speed, one value per frame interval
    ``(T - 1,)``; its last ``n_samples`` values (default: all), minus their mean, are Fourier transformed,
    and the power is ``|coefficient|² / n_samples``. (The spectrum of the velocity *vectors* of one clip,
    windowed, is :func:`motionlab.metrics.realism.velocity_spectrum`; a step that repeats shows in the speed.)

    Args:
        positions: joint positions ``(..., T, J, 3)``.
        fps: frame rate.
        n_samples: how many of the last speed values to use (at least 2, at most ``T - 1``).

    Returns:
        ``(frequencies, power)``, both ``(n_samples // 2 + 1,)``.
    """
    func = "speed_spectrum"
    x = _positions(positions, func, min_frames=3)
    rate = float(check_scalar(fps, "fps", func, minimum=0, include_minimum=False))
    speed = np.linalg.norm(np.diff(x, axis=-3), axis=-1).mean(axis=-1) * rate  # (..., T - 1)
    n = speed.shape[-1] if n_samples is None else n_samples
    check_scalar(n, "n_samples", func, minimum=2, maximum=speed.shape[-1])
    signal = speed[..., -n:] - speed[..., -n:].mean(axis=-1, keepdims=True)
    power = np.abs(np.fft.rfft(signal, axis=-1)) ** 2 / n
    return np.fft.rfftfreq(n, 1.0 / rate), power.reshape(-1, power.shape[-1]).mean(axis=0)


def periodic_speed_power(positions: ArrayLike, period: int, *, fps: float = 30.0) -> float:
    """Power (m²/s²) of the joint-speed signal at the frequency ``fps / period`` (:func:`speed_spectrum`).

    Args:
        positions: joint positions ``(..., T, J, 3)`` with ``T > 2 * period``.
        period: the period in frames (an integer ``>= 2``); the speed signal is cut to its last
            ``period * floor((T - 1) / period)`` samples, so the frequency falls on a Fourier bin.
        fps: frame rate.
    """
    func = "periodic_speed_power"
    n_period = int(check_scalar(period, "period", func, minimum=2))
    if n_period != period:
        raise ValueError(f"{func}: period must be a whole number of frames, got {period!r}")
    x = _positions(positions, func, min_frames=2 * n_period + 1)
    n_words = (x.shape[-3] - 1) // n_period
    _, power = speed_spectrum(x, fps=fps, n_samples=n_period * n_words)
    return float(power[n_words])


def bone_length_drift(positions: ArrayLike, parents: ArrayLike | Sequence[int]) -> float:
    """Mean over clips and bones of the standard deviation over frames of the bone length (m).

    Args:
        positions: joint positions ``(..., T, J, 3)`` with ``T >= 2``.
        parents: parent index of each joint ``(J,)``, ``-1`` for roots.
    """
    func = "bone_length_drift"
    x = _positions(positions, func, min_frames=2)
    lengths = _bone_lengths(x, parents, func)  # (..., T, B)
    return float(lengths.std(axis=-2).mean())
