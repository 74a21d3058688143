"""Worked solutions to chapter 08's "your turn" exercises (checked by tests/test_exercises.py)."""

from __future__ import annotations

import torch


def my_contrastive_loss(
    mu_a: torch.Tensor, mu_b: torch.Tensor, same: torch.Tensor, margin: float
) -> torch.Tensor:
    """ODMO's eq. 1 per pair: 1/2 d^2 for codes of the same class, 1/2 max(0, alpha - d)^2 otherwise, with
    d = |mu_a - mu_b| and the margin alpha; codes (P, D), same (P,) bool, losses (P,)."""
    squared = (mu_a - mu_b).pow(2).sum(dim=-1)
    distance = squared.clamp_min(1e-12).sqrt()  # sqrt's slope is infinite at 0
    return 0.5 * torch.where(same, squared, torch.relu(margin - distance).pow(2))


def my_covariance_prior(mu: torch.Tensor, logvar: torch.Tensor, prior_variance: float) -> torch.Tensor:
    """ODMO's eq. 1 prior term -ln det Σ + Tr Σ / σ_0² (B,) for Σ = diag(exp(logvar)), codes (B, D); the means
    mu get no prior (the springs place them)."""
    return (logvar.exp() / prior_variance - logvar).sum(dim=-1)
