"""Worked solutions to chapter 04's "your turn" exercises (checked by tests/test_exercises.py)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def my_subtree_reach(parents: Sequence[int], bone_lengths: np.ndarray) -> np.ndarray:
    """L_k (J,): the longest path from joint k to an end effector, as a sum of bone lengths.

    Walk from the last joint back to the first (children come after parents), so every child's L is final
    when its parent takes the maximum of child L + bone over its children.
    """
    reach = np.zeros(len(parents))
    for joint in reversed(range(1, len(parents))):
        parent = parents[joint]
        reach[parent] = max(reach[parent], reach[joint] + bone_lengths[joint])
    return reach


def my_impact_weights(reach: np.ndarray, leaf_floor: float) -> np.ndarray:
    """alpha (J,), mean 1: each L_k raised to at least leaf_floor * max(L) (so that the end effectors'
    orientation still counts), then divided by the mean (so that a weighted loss keeps its scale)."""
    floored = np.maximum(reach, leaf_floor * reach.max())
    return floored / floored.mean()
