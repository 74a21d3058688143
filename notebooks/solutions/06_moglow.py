"""Worked solutions to chapter 06's "your turn" exercises (checked by tests/test_exercises.py)."""

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
    """Generate poses (B, N, P) frame by frame from control (B, H + N, C), seed_pose (B, H, P) and
    standard-normal noise (B, N, P); invert_frame(z_t, cond_t, state) -> (pose_t, state)."""
    history = seed_pose.shape[1]
    past, state, poses = seed_pose, None, []
    for t in range(control.shape[1] - history):
        # c_t: the last H poses, oldest first, and the controls of frames t - H .. t (no dropout)
        cond = torch.cat([past.flatten(1), control[:, t : t + history + 1].flatten(1)], dim=1)
        pose, state = invert_frame(temperature * noise[:, t], cond, state)
        poses.append(pose)
        past = torch.cat([past[:, 1:], pose[:, None]], dim=1)
    return torch.stack(poses, dim=1)


def my_keep_mask(
    batch: int, frames: int, history: int, dropout: float, generator: torch.Generator, training: bool
) -> torch.Tensor:
    """Keep flags (batch, frames, history): in training each previous pose is dropped (0) with probability
    dropout and a kept one scaled by 1 / (1 - dropout) (inverted dropout); outside training all are 1."""
    if not training:
        return torch.ones(batch, frames, history)
    keep = (torch.rand(batch, frames, history, generator=generator) >= dropout).float()
    return keep / (1.0 - dropout) if dropout < 1.0 else keep
