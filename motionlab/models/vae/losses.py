"""The VAE's objective: the negative ELBO (reconstruction NLL plus KL) and the KL weight beta.

Both VAEs of :mod:`~motionlab.models.vae.model` train on :func:`elbo_loss` (the loss-function interface of
:func:`motionlab.train.train`); :func:`kl_weight` is the schedule of beta, the KL's weight.
:func:`negative_elbo` is the same objective written out for one batch of any encoder and decoder, as chapter
03's tiny CVAE uses it (and the reader writes it).
"""

from __future__ import annotations

import numbers
from collections.abc import Callable

import torch
from torch import Tensor

from motionlab.models.gaussian import gaussian_kl, gaussian_nll
from motionlab.models.vae.model import LatentVariableModel
from motionlab.train import Constant, KLAnneal
from motionlab.validation import check_same_shape, check_scalar, check_tensor


def elbo_terms(
    model: LatentVariableModel,
    x: Tensor,
    label: Tensor | None = None,
    generator: torch.Generator | None = None,
) -> dict[str, Tensor]:
    """The negative ELBO's two terms for a batch, in nats per sample (means over the batch).

    ``recon`` = E_q[-log p(x | z)], one draw of z, summed over all of x's numbers;
    ``kl`` = KL(q(z | x) || p(z)) summed over the latent dimensions (zero for an autoencoder).
    Also returns ``kl_per_dim`` ``(latent_dim,)`` (batch mean), for monitoring collapse.
    """
    out = model(x, label, generator)
    recon = gaussian_nll(x, out.mean, model.cfg.obs_logvar).flatten(1).sum(-1).mean()
    if out.logvar is None:
        kl_dims = torch.zeros(model.cfg.latent_dim, dtype=x.dtype, device=x.device)
    else:
        kl_dims = gaussian_kl(out.mu, out.logvar, prior_logvar=model.cfg.prior_logvar).mean(0)
    return {"recon": recon, "kl": kl_dims.sum(), "kl_per_dim": kl_dims}


def negative_elbo(
    x: Tensor, mu: Tensor, logvar: Tensor, eps: Tensor, decode: Callable[[Tensor], Tensor], obs_var: float
) -> tuple[Tensor, Tensor]:
    """The negative ELBO's two terms per sample, for a Gaussian encoder, decoder and N(0, I) prior.

    Args:
        x: ``(B, ...)`` the data.
        mu, logvar: ``(B, D)`` mean and log-variance of q(z | x).
        eps: ``(B, D)`` standard-normal noise: the code is ``z = mu + exp(logvar / 2) * eps``.
        decode: maps codes ``(B, D)`` to the decoder's means, ``x``'s shape.
        obs_var: sigma_x^2, the variance of p(x | z).

    Returns:
        ``(recon, kl)``, each ``(B,)`` in nats: the squared error over ``2 sigma_x^2`` summed over all of an
        example's numbers (the Gaussian NLL without its constant), and KL(q(z | x) || N(0, I)) summed over the
        latent dimensions.
    """
    for name, value in (("x", x), ("mu", mu), ("logvar", logvar), ("eps", eps)):
        check_tensor(value, name, "negative_elbo")
    check_same_shape(mu, logvar, ("mu", "logvar"), "negative_elbo")
    check_same_shape(mu, eps, ("mu", "eps"), "negative_elbo")
    check_scalar(obs_var, "obs_var", "negative_elbo", minimum=0.0, include_minimum=False)
    x_hat = decode(mu + torch.exp(0.5 * logvar) * eps)
    recon = 0.5 * ((x - x_hat) ** 2).flatten(1).sum(-1) / obs_var
    return recon, gaussian_kl(mu, logvar).sum(-1)


def elbo_loss(
    model: LatentVariableModel, batch: Tensor | tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    """Loss function for :func:`motionlab.train.train`: ``recon + beta * kl`` (``beta`` from the schedules,
    default 1), with its terms and ``objective``, the negative ELBO ``recon + kl``: the loss at the KL
    weight's final value, the measure whose levelling off says the run has converged (the loss itself rises
    while ``beta`` ramps up).

    ``batch`` is ``x`` for an unconditional model or ``(x, label)`` for a conditional one. For an autoencoder
    the loss is the reconstruction term alone.
    """
    x, label = batch if isinstance(batch, (tuple, list)) else (batch, None)
    terms = elbo_terms(model, x, label)
    if not model.variational:
        return {"loss": terms["recon"], "recon": terms["recon"]}
    beta = coeffs.get("beta", 1.0)
    return {
        "loss": terms["recon"] + beta * terms["kl"],
        "recon": terms["recon"],
        "kl": terms["kl"],
        "objective": (terms["recon"] + terms["kl"]).detach(),
    }


def kl_weight(steps: int, anneal: bool) -> KLAnneal | Constant:
    """The KL weight beta: a linear ramp from 0 to 1 over the first half of ``steps``, or 1 throughout."""
    check_scalar(steps, "steps", "kl_weight", kind=numbers.Integral, minimum=1)
    return KLAnneal(max_value=1.0, warmup=0, anneal=max(1, steps // 2)) if anneal else Constant(1.0)
