"""Generation with a trained VAE: clips decoded from prior draws, and straight lines between two codes.

Single prior draws are the models' own :meth:`~motionlab.models.vae.model.LatentVariableModel.sample`;
here are the two ways the chapter walks the code space.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

from motionlab.models.vae.data import ClipCodec
from motionlab.models.vae.model import MLPVAE
from motionlab.validation import check_scalar, check_tensor


@torch.no_grad()
def sample_clips(
    model: MLPVAE,
    codec: ClipCodec,
    labels: Tensor,
    generator: torch.Generator,
    latent_std: float | None = None,
) -> Tensor:
    """Global positions ``(B, L, 22, 3)`` of clips a clip CVAE decodes from codes ``z ~ N(0, σ² I)``.

    Args:
        model: a conditional MLP VAE on standardised windows ``(L, 67)``.
        codec: the windows' :class:`~motionlab.models.vae.data.ClipCodec`.
        labels: the action of each clip ``(B,)`` (int64).
        generator: draws the codes ``(B, latent_dim)``, nothing else.
        latent_std: ``σ``; ``None`` is the model's prior standard deviation ``σ_p`` (another value shows
            what sampling from the wrong prior does).
    """
    std = math.exp(0.5 * model.cfg.prior_logvar) if latent_std is None else float(latent_std)
    check_scalar(std, "latent_std", "sample_clips", minimum=0.0)
    z = torch.randn(labels.shape[0], model.cfg.latent_dim, generator=generator) * std
    return codec.to_positions(model.decode(z, labels))


def interpolate_codes(z0: Tensor, z1: Tensor, w: Tensor | float) -> Tensor:
    """Straight-line interpolation ``(1 - w) z0 + w z1``: codes ``(D,)`` and the weight ``w`` scalar or
    ``(K,)`` -> ``(K, D)``."""
    check_tensor(z0, "z0", "interpolate_codes", ndim=1)
    check_tensor(z1, "z1", "interpolate_codes", ndim=1)
    if z0.shape != z1.shape:
        raise ValueError(
            f"interpolate_codes: z0 and z1 must be codes of one size, got {tuple(z0.shape)} and "
            f"{tuple(z1.shape)}"
        )
    w = torch.as_tensor(w, dtype=z0.dtype).reshape(-1, 1)
    return (1 - w) * z0 + w * z1
