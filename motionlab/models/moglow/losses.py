"""The objective of the autoregressive models (MoGlow and the Gaussian baseline): NLL per frame.

Both models map ``(pose (B, T, P), control (B, T, C))`` windows to per-sequence log-likelihoods of frames
``tau .. T-1``; the objective is their negative mean **per frame** (nats), the unit of the held-out
comparison of chapter 06.
"""

from __future__ import annotations

import numbers

import torch
from torch import Tensor, nn

from motionlab.models.moglow.data import MoGlowFeatures
from motionlab.validation import check_scalar


def nll_per_frame_loss(
    model: nn.Module, batch: tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    """Mean negative log-likelihood per generated frame (nats) of a batch ``(pose, control)``."""
    pose, control = batch
    frames = pose.shape[1] - model.cfg.history
    nll = -model(pose, control).sum() / (pose.shape[0] * frames)
    return {"loss": nll, "nll": nll.detach()}


@torch.no_grad()
def held_out_nll(model: nn.Module, data: MoGlowFeatures, batch_size: int = 256) -> float:
    """Mean NLL per frame (nats) of ``model`` on windows ``data``: the model's likelihood, in eval mode.

    The history dropout is a training device (the paper's Fig. 3): in eval mode the model conditions on
    the full history, so the number is ``-log p(x_t | x_{t-tau..t-1}, u_{t-tau..t}, h_t)`` averaged over
    frames. In training mode the same forward pass would average over random masks instead, which is the
    training objective, not the model's likelihood. The model's mode is restored afterwards.
    """
    check_scalar(batch_size, "batch_size", "held_out_nll", kind=numbers.Integral, minimum=1)
    was_training = model.training
    model.eval()
    try:
        total, frames = 0.0, 0
        for pose, control in zip(data.pose.split(batch_size), data.control.split(batch_size)):
            total -= float(model(pose, control).sum())
            frames += pose.shape[0] * (pose.shape[1] - model.cfg.history)
    finally:
        model.train(was_training)
    return total / frames
