"""Worked solution to chapter 11's "your turn" exercise (checked by tests/test_exercises.py)."""

from __future__ import annotations

import torch


def my_ancestral_step(
    x0_hat: torch.Tensor, x_t: torch.Tensor, t: int, betas: torch.Tensor, noise: torch.Tensor
) -> torch.Tensor:
    """x_{n-1} (B, D): a draw of q(x_{n-1} | x_n, x0_hat) from x_t = x_n (B, D) at the 0-based step
    t = n - 1, with the standard normal noise (B, D); betas (S,) are the one-step variances
    sigma_{n|n-1}^2."""
    alpha_bar = torch.cumprod(1 - betas, dim=0)  # 1 - sigma_n^2 at every step
    if t == 0:  # 1 - sigma^2 before the first step is 1: the posterior is a point at x0_hat
        return x0_hat
    beta, now, before = betas[t], alpha_bar[t], alpha_bar[t - 1]
    mean = beta * before.sqrt() / (1 - now) * x0_hat + (1 - before) * (1 - beta).sqrt() / (1 - now) * x_t
    variance = beta * (1 - before) / (1 - now)
    return mean + variance.sqrt() * noise
