"""Worked solution to chapter 06's "your turn" exercise (checked by tests/test_exercises.py)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import torch


def my_sample_loop(
    invert_frame: Callable[[torch.Tensor, torch.Tensor, Any], tuple[torch.Tensor, Any]],
    control: torch.Tensor,
    seed_pose: torch.Tensor,
    noise: torch.Tensor,
    temperature: float,
) -> torch.Tensor:
    """Generate poses (B, N, P) frame by frame from control (B, tau + N, C), seed_pose (B, tau, P) and
    standard-normal noise (B, N, P); invert_frame(z_t, cond_t, state) -> (pose_t, state)."""
    tau = seed_pose.shape[1]
    past, state, poses = seed_pose, None, []
    for t in range(control.shape[1] - tau):
        # c_t: the last tau poses, oldest first, and the controls of frames t - tau .. t (no dropout)
        cond = torch.cat([past.flatten(1), control[:, t : t + tau + 1].flatten(1)], dim=1)
        pose, state = invert_frame(temperature * noise[:, t], cond, state)
        poses.append(pose)
        past = torch.cat([past[:, 1:], pose[:, None]], dim=1)
    return torch.stack(poses, dim=1)
