"""Worked solutions to chapter 03's "your turn" exercises (the negative ELBO in the chapter; the
reparameterisation and the Gaussian KL in its appendix), checked by tests/test_exercises.py."""

from __future__ import annotations

from collections.abc import Callable

import torch


def my_reparameterize(mu: torch.Tensor, logvar: torch.Tensor, generator: torch.Generator) -> torch.Tensor:
    """A draw z ~ N(mu, exp(logvar)) that gradients flow through: z = mu + exp(logvar / 2) * eps."""
    eps = torch.randn(mu.shape, generator=generator, dtype=mu.dtype)
    return mu + torch.exp(0.5 * logvar) * eps


def my_gaussian_kl(mu: torch.Tensor, logvar: torch.Tensor) -> torch.Tensor:
    """KL(N(mu, exp(logvar)) || N(0, 1)) per dimension: 1/2 (mu^2 + sigma^2 - 1 - log sigma^2)."""
    return 0.5 * (mu**2 + logvar.exp() - 1.0 - logvar)


def my_negative_elbo(
    x: torch.Tensor,
    mu: torch.Tensor,
    logvar: torch.Tensor,
    eps: torch.Tensor,
    decode: Callable[[torch.Tensor], torch.Tensor],
    obs_var: float,
) -> tuple[torch.Tensor, torch.Tensor]:
    """The negative ELBO's two terms per example, (B,) each: reparameterise, decode, score, regularise."""
    z = mu + torch.exp(0.5 * logvar) * eps  # the draw, differentiable in mu and logvar
    x_hat = decode(z)
    recon = 0.5 * ((x - x_hat) ** 2).flatten(1).sum(-1) / obs_var  # -log N(x; x_hat, obs_var), no constant
    kl = 0.5 * (mu**2 + logvar.exp() - 1.0 - logvar).sum(-1)  # KL(N(mu, sigma^2) || N(0, 1)), summed over D
    return recon, kl
