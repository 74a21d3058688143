"""The VAE's objective: the negative ELBO (reconstruction NLL plus KL) and the KL weight beta.

Both VAEs of :mod:`~motionlab.models.vae.model` train on :func:`elbo_loss` (the loss-function interface of
:func:`motionlab.train.train`); :func:`kl_weight` is the schedule of beta, the KL's weight.
"""

from __future__ import annotations

import numbers

import torch
from torch import Tensor

from motionlab.models.gaussian import gaussian_kl, gaussian_nll
from motionlab.models.vae.model import LatentVariableModel
from motionlab.train import Constant, KLAnneal
from motionlab.validation import check_scalar


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


def elbo_loss(
    model: LatentVariableModel, batch: Tensor | tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    """Loss function for :func:`motionlab.train.train`: ``recon + beta * kl`` (``beta`` from the schedules,
    default 1).

    ``batch`` is ``x`` for an unconditional model or ``(x, label)`` for a conditional one. For an autoencoder
    the loss is the reconstruction term alone.
    """
    x, label = batch if isinstance(batch, (tuple, list)) else (batch, None)
    terms = elbo_terms(model, x, label)
    if not model.variational:
        return {"loss": terms["recon"], "recon": terms["recon"]}
    beta = coeffs.get("beta", 1.0)
    return {"loss": terms["recon"] + beta * terms["kl"], "recon": terms["recon"], "kl": terms["kl"]}


def kl_weight(steps: int, anneal: bool) -> KLAnneal | Constant:
    """The KL weight beta: a linear ramp from 0 to 1 over the first half of ``steps``, or 1 throughout."""
    check_scalar(steps, "steps", "kl_weight", kind=numbers.Integral, minimum=1)
    return KLAnneal(max_value=1.0, warmup=0, anneal=max(1, steps // 2)) if anneal else Constant(1.0)
