"""On-demand customisation: walk between two modes, send a motion to a chosen end point, several styles to one
end point.

All three only choose codes and end points; the trained generators do the rest (through
:meth:`~motionlab.models.odmo.sampler.ODMOSampler.generate`). The code space is what makes them work:
the codes of a discovered mode share a style, the straight line between two mode centres stays inside
the class's region (the contrastive springs keep classes apart), and the end point is an input of the
trajectory generator, separate from the code.
"""

from __future__ import annotations

import numpy as np

from motionlab.models.odmo.sampler import ODMOSampler, Samples


def interpolate(a: np.ndarray, b: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``(1 - w) a + w b`` for each weight: vectors (codes, end points) ``(D,)``, ``(D,)``, weights ``(n,)``
    -> ``(n, D)``."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    if a.ndim != 1 or a.shape != b.shape or w.ndim != 1:
        raise ValueError(
            f"interpolate: need two vectors (D,) and weights (n,), got {a.shape}, {b.shape}, {w.shape}"
        )
    return (1.0 - w)[:, None] * a[None] + w[:, None] * b[None]


def _samples(
    sampler: ODMOSampler, action: int, codes: np.ndarray, ends: np.ndarray, modes: np.ndarray
) -> Samples:
    actions = np.full(len(codes), action, dtype=np.int64)
    return Samples(*sampler.generate(codes, actions, ends), codes, actions, modes, ends)


def _mode_mean(sampler: ODMOSampler, action: int, mode: int) -> np.ndarray:
    modes = sampler.modes.classes[sampler.modes.check_action(action)]
    if isinstance(mode, bool) or not isinstance(mode, (int, np.integer)) or not 0 <= mode < modes.n_modes:
        raise ValueError(f"action {action} has modes 0..{modes.n_modes - 1}, got {mode!r}")
    return modes.means[mode]


def mode_interpolation(
    sampler: ODMOSampler, action: int, mode_a: int, mode_b: int, weights: np.ndarray
) -> Samples:
    """Clips whose codes slide from the centre of ``mode_a`` to that of ``mode_b`` of ``action`` (``weights``
    ``(n,)`` in [0, 1]); each takes the end point of its nearest training code. ``mode`` holds the nearer end
    (a or b)."""
    codes = interpolate(_mode_mean(sampler, action, mode_a), _mode_mean(sampler, action, mode_b), weights)
    ends = sampler.modes.nearest_end_points(action, codes)
    return _samples(sampler, action, codes, ends, np.where(np.asarray(weights) < 0.5, mode_a, mode_b))


def to_end_point(sampler: ODMOSampler, action: int, codes: np.ndarray, end_points: np.ndarray) -> Samples:
    """Clips of ``action`` from given codes ``(n, D)``, each sent to its end point ``(n, 3)`` (metres,
    relative to the start; the character starts facing +x)."""
    codes = np.asarray(codes, dtype=np.float64)
    ends = np.asarray(end_points, dtype=np.float64)
    if ends.shape != (len(codes), 3):
        raise ValueError(f"to_end_point: end_points must be ({len(codes)}, 3), got {ends.shape}")
    modes = sampler.modes.classes[sampler.modes.check_action(action)].assign(codes)
    return _samples(sampler, action, codes, ends, modes)


def end_point_sweep(start: np.ndarray, stop: np.ndarray, n: int) -> np.ndarray:
    """``n`` end points evenly spaced on the segment from ``start`` ``(3,)`` to ``stop`` ``(3,)``, both
    included."""
    return interpolate(np.asarray(start, float), np.asarray(stop, float), np.linspace(0.0, 1.0, n))


def styles_to_end_point(
    sampler: ODMOSampler, action: int, end_point: np.ndarray, rng: np.random.Generator, per_mode: int = 1
) -> Samples:
    """``per_mode`` codes from every discovered mode of ``action``, all sent to one ``end_point`` ``(3,)``."""
    modes = sampler.modes.classes[sampler.modes.check_action(action)]
    codes, picked = sampler.modes.sample(
        action, per_mode * modes.n_modes, rng, probabilities=np.ones(modes.n_modes)
    )
    ends = np.repeat(np.asarray(end_point, dtype=np.float64)[None], len(codes), axis=0)
    return _samples(sampler, action, codes, ends, picked)
