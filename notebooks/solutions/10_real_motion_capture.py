"""Worked solutions to chapter 10's "your turn" exercises (checked by tests/test_exercises_real.py)."""

from __future__ import annotations

import numpy as np


def my_bone_length_variation(positions: np.ndarray, parents) -> np.ndarray:
    """Coefficient of variation of every bone's length over the frames: positions (T, J, 3) -> (J - 1,)."""
    parents = np.asarray(parents)
    children = np.flatnonzero(parents >= 0)
    lengths = np.linalg.norm(positions[:, children] - positions[:, parents[children]], axis=-1)  # (T, J - 1)
    return lengths.std(axis=0) / lengths.mean(axis=0)


def my_mirror(positions: np.ndarray, mirror) -> np.ndarray:
    """Left/right mirror image of positions (T, J, 3): reflect y -> -y, then joint j is joint mirror[j]."""
    reflected = positions * np.array([1.0, -1.0, 1.0])
    return reflected[:, list(mirror)]
