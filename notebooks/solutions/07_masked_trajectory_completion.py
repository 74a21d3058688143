"""Worked solutions to chapter 07's "your turn" exercises (checked by tests/test_exercises.py)."""

from __future__ import annotations

import math

import torch


def my_dct_matrix(n_frames: int) -> torch.Tensor:
    """The orthonormal DCT-II matrix (n_frames, n_frames): U[u, t] = s_u cos(pi (2t + 1) u / (2T)),
    s_0 = sqrt(1/T), s_u = sqrt(2/T) for u > 0, with T = n_frames."""
    u = torch.arange(n_frames, dtype=torch.float64)[:, None]
    t = torch.arange(n_frames, dtype=torch.float64)[None, :]
    scale = torch.full((n_frames, 1), math.sqrt(2.0 / n_frames), dtype=torch.float64)
    scale[0] = math.sqrt(1.0 / n_frames)
    return scale * torch.cos(math.pi * (2 * t + 1) * u / (2 * n_frames))


def my_given_trajectories(poses: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Y = X ⊙ M (..., T, J * 3): poses (..., T, J * 3) with the joints outside mask (..., J) set to 0."""
    channels = mask.repeat_interleave(3, dim=-1)  # (..., J * 3): x, y, z of each joint in turn
    return poses * channels[..., None, :].to(poses.dtype)  # the same mask in every frame


def my_prior_kl(
    mu_q: torch.Tensor, logvar_q: torch.Tensor, mu_p: torch.Tensor, logvar_p: torch.Tensor
) -> torch.Tensor:
    """KL(q_pose || p_traj) per sequence (B,) for latents (B, C, L): the closed form per number, summed."""
    kl = 0.5 * (logvar_p - logvar_q + (logvar_q.exp() + (mu_q - mu_p) ** 2) / logvar_p.exp() - 1)
    return kl.sum(dim=(1, 2))
