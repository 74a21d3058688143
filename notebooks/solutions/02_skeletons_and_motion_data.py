"""Worked solutions to chapter 02's "your turn" exercises (checked by tests/test_exercises.py)."""

from __future__ import annotations

import numpy as np
import torch

from motionlab.geometry import quat_apply, quat_mul


def my_chain_positions(rotations: torch.Tensor, root: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
    """Forward kinematics of a chain: joint j's parent is j - 1.

    rotations (..., K, 4) local unit quaternions (joint 0's is its global orientation), root (..., 3) the
    position of joint 0, offsets (K, 3) rest offsets from each joint's parent. Returns positions (..., K, 3):
    x_0 = root, x_j = x_{j-1} + G_{j-1} o_j with G_0 = q_0 and G_j = G_{j-1} ⊗ q_j.
    """
    positions, frame = [root], rotations[..., 0, :]
    for j in range(1, rotations.shape[-2]):
        positions.append(positions[-1] + quat_apply(frame, offsets[j].expand_as(root)))
        frame = quat_mul(frame, rotations[..., j, :])
    return torch.stack(positions, dim=-2)


def my_foot_skating(feet: np.ndarray, contacts: np.ndarray, fps: float) -> float:
    """Mean horizontal speed (m/s) over the frame pairs planted at both ends; feet (..., T, F, 3), contacts
    (..., T, F) bool. The planted pairs of all clips are pooled, then averaged."""
    planted = contacts[..., 1:, :] & contacts[..., :-1, :]  # (..., T - 1, F)
    step = feet[..., 1:, :, :2] - feet[..., :-1, :, :2]  # horizontal: z is up
    return float((np.linalg.norm(step, axis=-1) * fps)[planted].mean())
