"""Worked solutions to chapter 03's "your turn" exercises (checked by tests/test_exercises.py)."""

from __future__ import annotations

import torch


def my_reparameterize(mu: torch.Tensor, logvar: torch.Tensor, generator: torch.Generator) -> torch.Tensor:
    """A draw z ~ N(mu, exp(logvar)) that gradients flow through: z = mu + exp(logvar / 2) * eps."""
    eps = torch.randn(mu.shape, generator=generator, dtype=mu.dtype)
    return mu + torch.exp(0.5 * logvar) * eps


def my_gaussian_kl(mu: torch.Tensor, logvar: torch.Tensor) -> torch.Tensor:
    """KL(N(mu, exp(logvar)) || N(0, 1)) per dimension: 1/2 (mu^2 + sigma^2 - 1 - log sigma^2)."""
    return 0.5 * (mu**2 + logvar.exp() - 1.0 - logvar)
