"""Chapter 02's second exercise: foot skating over given contacts, checked against
:func:`motionlab.metrics.physical.foot_skating`."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from motionlab.exercises.checking import CheckResult, Diagnosis, checker
from motionlab.metrics.physical import foot_skating

FootSkating = Callable[[np.ndarray, np.ndarray, float], float]


def _feet(batch: tuple[int, ...], seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Foot positions ``(*batch, T, F, 3)`` that drift a little, and contacts ``(*batch, T, F)``."""
    rng = np.random.default_rng(seed)
    steps = rng.normal(scale=0.01, size=(*batch, 12, 3, 3))
    contacts = rng.random((*batch, 12, 3)) < 0.6
    contacts[..., :2, 0] = True  # at least one planted pair
    return np.cumsum(steps, axis=-3), contacts


def _reference(feet: np.ndarray, contacts: np.ndarray, fps: float) -> float:
    return foot_skating(feet, contacts, fps=fps, feet=range(feet.shape[-2]))


def _variants(feet: np.ndarray, contacts: np.ndarray, fps: float) -> list[tuple[float, str]]:
    """Typical mistakes' values, with what to say about each."""
    step = feet[..., 1:, :, :] - feet[..., :-1, :, :]
    flat = np.linalg.norm(step[..., :2], axis=-1) * fps
    both = contacts[..., 1:, :] & contacts[..., :-1, :]
    first = contacts[..., :-1, :]
    return [
        (
            float((np.linalg.norm(step, axis=-1) * fps)[both].mean()),
            "the speed is horizontal: use the x and y displacement only (z is up; a foot may lift)",
        ),
        (float(flat[both].mean() / fps), "the speed is in m/s: multiply the per-frame displacement by fps"),
        (
            float(flat[first].mean()),
            "a frame pair counts when the foot is in contact at *both* ends: c_t and c_{t+1}",
        ),
        (
            float(flat.mean()),
            "average only over the planted frame pairs, not over all of them",
        ),
        (
            float((flat * both).mean()),
            "divide by the number of planted frame pairs, not by the number of all frame pairs",
        ),
    ]


def _skating_values(fn: FootSkating) -> None:
    fps = 30.0
    for batch, what in (((), "one clip (T, F, 3)"), ((4,), "clips (N, T, F, 3)")):
        feet, contacts = _feet(batch, len(batch))
        got = fn(feet, contacts, fps)
        if np.ndim(got) != 0:
            raise Diagnosis(f"for {what} return one number (m/s), got shape {np.shape(got)}")
        got = float(got)
        want = _reference(feet, contacts, fps)
        if np.isclose(got, want):
            continue
        for value, text in _variants(feet, contacts, fps):
            if np.isclose(got, value):
                raise Diagnosis(f"for {what}: {text}")
        if batch:
            per_clip = [_reference(f, c, fps) for f, c in zip(feet, contacts)]
            if np.isclose(got, np.mean(per_clip)):
                raise Diagnosis(
                    f"for {what} you averaged each clip's skating: pool the planted pairs of all clips, "
                    "then average (clips with more contact count more)"
                )
        raise Diagnosis(f"for {what} you gave {got:.4f} m/s, the skating is {want:.4f} m/s")


@checker(
    [_skating_values],
    "matches motionlab.metrics.physical.foot_skating with given contacts, for one clip and for a batch",
)
def check_foot_skating(fn: FootSkating) -> CheckResult:
    """Check ``fn(feet (..., T, F, 3), contacts (..., T, F) bool, fps) -> float``: the mean horizontal speed
    (m/s) of the foot joints over the frame pairs in which they are in contact at both ends."""
