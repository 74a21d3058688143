"""Diagonal-Gaussian helpers shared by the latent-variable models (VAE, Motion Cell, TrajeVAE, ODMO).

A diagonal Gaussian is carried as two tensors of the same shape ``(..., D)``: its mean ``mu`` and its
log-variance ``logvar`` (natural log of sigma squared). Every function is batched over the leading dims,
works with autograd, and checks its arguments through :mod:`motionlab.validation` (``TypeError`` for a
non-tensor or an integer dtype, ``ValueError`` naming the function and the argument for a wrong shape, NaN
or infinity) instead of returning silent NaNs. The measurements of latent use (KL per dimension, active
units) are the VAE chapter's: :mod:`motionlab.models.vae.evaluate`.
"""

from __future__ import annotations

import math

import torch

from motionlab.validation import check_same_shape, check_tensor

_LOG_2PI = math.log(2.0 * math.pi)


def _prior_tensor(
    value: torch.Tensor | float | None, like: torch.Tensor, where: str, name: str
) -> torch.Tensor:
    """``value`` as a tensor broadcastable to ``like`` (``None`` means 0, the standard normal's value)."""
    if value is None:
        return torch.zeros((), dtype=like.dtype, device=like.device)
    if not isinstance(value, torch.Tensor):
        value = torch.tensor(float(value), dtype=like.dtype, device=like.device)
    check_tensor(value, name, where)
    # checked by hand: torch.broadcast_shapes imports sympy (a third of a second) the first time it runs
    if any(a != b and 1 not in (a, b) for a, b in zip(reversed(value.shape), reversed(like.shape))):
        raise ValueError(
            f"{where}: {name} of shape {tuple(value.shape)} does not broadcast to {tuple(like.shape)}"
        )
    return value


def reparameterize(
    mu: torch.Tensor, logvar: torch.Tensor, generator: torch.Generator | None = None
) -> torch.Tensor:
    """Draw ``z = mu + sigma * eps`` with ``eps ~ N(0, I)``: a sample that gradients flow through.

    Args:
        mu, logvar: ``(..., D)`` mean and log-variance of q(z | x).
        generator: optional ``torch.Generator`` for reproducible noise.

    Returns:
        ``(..., D)`` samples, differentiable with respect to ``mu`` and ``logvar``.
    """
    check_tensor(mu, "mu", "reparameterize")
    check_tensor(logvar, "logvar", "reparameterize")
    check_same_shape(mu, logvar, ("mu", "logvar"), "reparameterize")
    eps = torch.randn(mu.shape, generator=generator, dtype=mu.dtype, device=mu.device)
    return mu + torch.exp(0.5 * logvar) * eps


def gaussian_kl(
    mu: torch.Tensor,
    logvar: torch.Tensor,
    prior_mu: torch.Tensor | float | None = None,
    prior_logvar: torch.Tensor | float | None = None,
) -> torch.Tensor:
    r"""Closed-form KL(N(mu, sigma^2) || N(prior_mu, sigma_p^2)) per dimension.

    .. math::
        \mathrm{KL} = \tfrac12\Big(\log\sigma_p^2 - \log\sigma^2
                      + \frac{\sigma^2 + (\mu - \mu_p)^2}{\sigma_p^2} - 1\Big)

    With the defaults (``prior_mu = 0``, ``prior_logvar = 0``) the prior is the standard normal and this is
    the familiar ``-0.5 * (1 + logvar - mu**2 - exp(logvar))``.

    Args:
        mu, logvar: ``(..., D)`` posterior mean and log-variance.
        prior_mu, prior_logvar: prior mean and log-variance, tensors broadcastable to ``mu`` or floats;
            ``None`` means 0.

    Returns:
        ``(..., D)`` KL per dimension, in nats (sum over the last dim for the KL of the whole vector).
    """
    check_tensor(mu, "mu", "gaussian_kl")
    check_tensor(logvar, "logvar", "gaussian_kl")
    check_same_shape(mu, logvar, ("mu", "logvar"), "gaussian_kl")
    p_mu = _prior_tensor(prior_mu, mu, "gaussian_kl", "prior_mu")
    p_logvar = _prior_tensor(prior_logvar, mu, "gaussian_kl", "prior_logvar")
    return 0.5 * (p_logvar - logvar + (torch.exp(logvar) + (mu - p_mu) ** 2) * torch.exp(-p_logvar) - 1.0)


def gaussian_nll(x: torch.Tensor, mean: torch.Tensor, logvar: torch.Tensor | float = 0.0) -> torch.Tensor:
    r"""Negative log-density of ``x`` under N(mean, exp(logvar)), element-wise.

    .. math:: -\log p(x) = \tfrac12\big(\log 2\pi + \log\sigma^2 + (x - \mu)^2 / \sigma^2\big)

    With a fixed ``logvar`` this is a scaled squared error plus a constant: the usual VAE reconstruction term.

    Args:
        x, mean: tensors of the same shape.
        logvar: log-variance broadcastable to ``x`` (tensor or float; default 0, unit variance).

    Returns:
        Tensor of ``x``'s shape, in nats.
    """
    check_tensor(x, "x", "gaussian_nll")
    check_tensor(mean, "mean", "gaussian_nll")
    check_same_shape(x, mean, ("x", "mean"), "gaussian_nll")
    lv = _prior_tensor(logvar, x, "gaussian_nll", "logvar")
    return 0.5 * (_LOG_2PI + lv + (x - mean) ** 2 * torch.exp(-lv))
