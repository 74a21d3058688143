"""Worked solutions to chapter 04's "your turn" exercises and its appendix's (checked by
tests/test_exercises.py)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch


def my_subtree_reach(parents: Sequence[int], bone_lengths: np.ndarray) -> np.ndarray:
    """L_j (J,): the longest path from joint j to an end effector, as a sum of bone lengths.

    Walk from the last joint back to the first (children come after parents), so every child's L is final
    when its parent takes the maximum of child L + bone over its children.
    """
    reach = np.zeros(len(parents))
    for joint in reversed(range(1, len(parents))):
        parent = parents[joint]
        reach[parent] = max(reach[parent], reach[joint] + bone_lengths[joint])
    return reach


def my_impact_weights(reach: np.ndarray, leaf_floor: float) -> np.ndarray:
    """The joint weights lambda_j (J,), mean 1: each L_j raised to at least leaf_floor * max(L) (so that the
    end effectors' orientation still counts), then divided by the mean (so that a weighted loss keeps its
    scale)."""
    floored = np.maximum(reach, leaf_floor * reach.max())
    return floored / floored.mean()


def my_motion_cell_step(word, state, eps, prior, posterior, decode, transition):
    """One teacher-forced step over a motion word: (word_hat (B, D_w), kl (B,), next_state (B, D_h)).

    Draw z_t from the posterior, which reads the real word, decode it with the state before the word, score
    the posterior against the learned prior with the closed-form Gaussian KL, and update the state from the
    real word (teacher forcing) and the drawn z_t.
    """
    mu_p, logvar_p = prior(state)
    mu_q, logvar_q = posterior(word, state)
    z = mu_q + torch.exp(0.5 * logvar_q) * eps
    kl = 0.5 * (logvar_p - logvar_q + (logvar_q.exp() + (mu_q - mu_p) ** 2) / logvar_p.exp() - 1)
    return decode(z, state), kl.sum(-1), transition(word, z, state)
