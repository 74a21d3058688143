"""Smooth curves of time for the synthetic generator, batched over clips (NumPy, float64).

Everything here maps per-clip parameters ``(B, ...)`` and a time axis to ``(B, T, ...)`` arrays:
random smooth noise (turning, speed changes, idle sway), eased transitions, cubic Hermite segments and
monotone keyframe interpolation (the non-periodic actions are keyframed in time).
"""

from __future__ import annotations

import numpy as np


def smooth_noise(t: np.ndarray, frequencies: np.ndarray, phases: np.ndarray) -> np.ndarray:
    """A sum of sinusoids with unit root-mean-square, ``(B, T)``.

    Args:
        t: ``(T,)`` seconds.
        frequencies, phases: ``(B, K)`` in Hz and radians.
    """
    k = frequencies.shape[-1]
    waves = np.sin(2 * np.pi * frequencies[:, None, :] * t[None, :, None] + phases[:, None, :])
    return waves.sum(axis=-1) * np.sqrt(2.0 / k)


def ease(s: np.ndarray) -> np.ndarray:
    """Minimum-jerk transition from 0 to 1 over ``s`` in ``[0, 1]`` (clamped outside), zero slope at both
    ends."""
    s = np.clip(s, 0.0, 1.0)
    return s**3 * (10 - 15 * s + 6 * s**2)


def bump(s: np.ndarray) -> np.ndarray:
    """``16 s^2 (1 - s)^2``: 0 with zero slope at ``s = 0`` and ``s = 1``, peak 1 at ``s = 1/2``."""
    s = np.clip(s, 0.0, 1.0)
    return 16 * s**2 * (1 - s) ** 2


def hermite(p0: np.ndarray, m0: np.ndarray, p1: np.ndarray, m1: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Cubic Hermite segment from ``p0`` (slope ``m0``) to ``p1`` (slope ``m1``) at ``s`` in ``[0, 1]``.

    Slopes are per unit of ``s``; all arguments broadcast.
    """
    s2, s3 = s * s, s * s * s
    return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * m1


def _segment(knots: np.ndarray, query: np.ndarray) -> np.ndarray:
    """Index ``(B, M)`` of the knot interval ``[knots[i], knots[i+1])`` holding each query, clamped to the
    ends."""
    index = np.sum(knots[:, None, :] <= query[:, :, None], axis=-1) - 1
    return np.clip(index, 0, knots.shape[1] - 2)


def gather_rows(values: np.ndarray, index: np.ndarray) -> np.ndarray:
    """``values[b, index[b, m], ...]`` ``(B, M, ...)`` for ``values (B, N, ...)`` and ``index (B, M)``."""
    expanded = index.reshape(index.shape + (1,) * (values.ndim - 2))
    return np.take_along_axis(values, expanded, axis=1)


def interp_rows(x: np.ndarray, y: np.ndarray, query: np.ndarray) -> np.ndarray:
    """Row-wise linear interpolation (linear extrapolation outside): ``(B, M, ...)``.

    Args:
        x: ``(B, N)`` increasing knots; y: ``(B, N, ...)`` values; query: ``(B, M)``.
    """
    index = _segment(x, query)
    x0, x1 = gather_rows(x, index), gather_rows(x, index + 1)
    weight = ((query - x0) / (x1 - x0)).reshape(query.shape + (1,) * (y.ndim - 2))
    return gather_rows(y, index) * (1 - weight) + gather_rows(y, index + 1) * weight


def hermite_keys(times: np.ndarray, values: np.ndarray, slopes: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Piecewise cubic Hermite curve through keys with given slopes, held constant outside the keys.

    Args:
        times: ``(B, K)`` strictly increasing key times per clip (seconds), ``K >= 2``.
        values, slopes: ``(B, K)`` or ``(B, K, D)``: values and time derivatives (per second) at the keys.
        t: ``(T,)`` frame times shared by all clips, or ``(B, T)`` per clip.
    Returns:
        ``(B, T)`` or ``(B, T, D)``.
    """
    scalar = values.ndim == 2
    v = values[..., None] if scalar else values
    m = slopes[..., None] if scalar else slopes
    query = np.broadcast_to(t, (times.shape[0], np.shape(t)[-1]))
    index = _segment(times, query)
    t0, t1 = gather_rows(times, index), gather_rows(times, index + 1)
    s = np.clip((query - t0) / (t1 - t0), 0.0, 1.0)[..., None]
    span = (t1 - t0)[..., None]
    out = hermite(
        gather_rows(v, index),
        gather_rows(m, index) * span,
        gather_rows(v, index + 1),
        gather_rows(m, index + 1) * span,
        s,
    )
    return out[..., 0] if scalar else out


def keyframes(times: np.ndarray, values: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Monotone cubic interpolation through keys, held constant before the first and after the last.

    Between keys the curve never overshoots (Fritsch-Carlson slopes), and it has zero slope at the first
    and last key and wherever the values turn back, so a keyframed motion starts and ends at rest.
    Arguments and result as in :func:`hermite_keys`, without the slopes.
    """
    v = values[..., None] if values.ndim == 2 else values
    h = np.diff(times, axis=1)[..., None]  # (B, K-1, 1)
    secant = np.diff(v, axis=1) / h
    slopes = np.zeros_like(v)
    w1 = 2 * h[:, 1:] + h[:, :-1]
    w2 = h[:, 1:] + 2 * h[:, :-1]
    same_sign = secant[:, :-1] * secant[:, 1:] > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        harmonic = (w1 + w2) / (w1 / secant[:, :-1] + w2 / secant[:, 1:])
    slopes[:, 1:-1] = np.where(same_sign, harmonic, 0.0)
    return hermite_keys(times, values, slopes.reshape(values.shape), t)


def place_event(
    durations: np.ndarray, n_frames: int, fps: int, where: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Start time ``(B,)`` and time scale ``(B,)`` of one event lasting ``durations`` ``(B,)`` seconds per
    clip.

    The clip keeps ``min(0.25 s, 15%)`` of rest at each end. An event longer than the time in between is
    played faster (scale < 1) so that it fits; otherwise it starts at fraction ``where`` ``(B,)`` in
    ``[0, 1)`` of the slack.
    """
    last = (n_frames - 1) / fps
    rest = min(0.25, 0.15 * last)
    room = last - 2 * rest
    scale = np.minimum(1.0, room / durations)
    return rest + (room - durations * scale) * where, scale


def smooth_time(x: np.ndarray, passes: int) -> np.ndarray:
    """Binomial ``[1, 2, 1] / 4`` smoothing along axis 1 (time), ``passes`` times, ends held."""
    for _ in range(passes):
        padded = np.concatenate([x[:, :1], x, x[:, -1:]], axis=1)
        x = 0.25 * padded[:, :-2] + 0.5 * padded[:, 1:-1] + 0.25 * padded[:, 2:]
    return x
