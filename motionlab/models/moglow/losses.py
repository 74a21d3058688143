"""The objective of the autoregressive models (MoGlow and the Gaussian baseline): NLL per frame.

Both models map ``(pose (B, T, P), control (B, T, C))`` windows to per-sequence log-likelihoods of frames
``H .. T-1``; the objective is their negative mean **per frame** (nats), the unit of the held-out
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
def held_out_nll_per_window(model: nn.Module, data: MoGlowFeatures, batch_size: int = 256) -> Tensor:
    """NLL per frame (nats) ``(M,)`` of each of the windows ``data``: the model's likelihood, in eval mode.

    The history dropout is a training device (the paper's Fig. 3): in eval mode the model conditions on
    the full history, so each number is ``-log p(x_t | x_{t-H..t-1}, u_{t-H..t}, h_t)`` averaged over
    the window's frames. In training mode the same forward pass would draw random masks instead
    (:func:`dropout_objective_nll`). The model's mode is restored afterwards.
    """
    check_scalar(batch_size, "batch_size", "held_out_nll_per_window", kind=numbers.Integral, minimum=1)
    was_training = model.training
    model.eval()
    try:
        frames = data.pose.shape[1] - model.cfg.history
        return torch.cat(
            [-model(pose, control) / frames for pose, control in zip(*(x.split(batch_size) for x in data))]
        )
    finally:
        model.train(was_training)


def held_out_nll_per_clip(
    model: nn.Module, data: MoGlowFeatures, n_clips: int, batch_size: int = 256
) -> Tensor:
    """Each clip's mean NLL per frame (nats) ``(n_clips,)`` over its windows, in eval mode: the unit of
    chapter 06's paired comparisons. ``data`` holds the windows of ``n_clips`` clips ordered start by start,
    clip by clip (:func:`~.data.prepare_data`), so window ``i`` belongs to clip ``i % n_clips``."""
    check_scalar(n_clips, "n_clips", "held_out_nll_per_clip", kind=numbers.Integral, minimum=1)
    per_window = held_out_nll_per_window(model, data, batch_size)
    if per_window.shape[0] % n_clips:
        raise ValueError(
            f"held_out_nll_per_clip: {per_window.shape[0]} windows are not a whole number per clip "
            f"of {n_clips} clips"
        )
    return per_window.view(-1, n_clips).mean(0)


def held_out_nll(model: nn.Module, data: MoGlowFeatures, batch_size: int = 256) -> float:
    """Mean NLL per frame (nats) of ``model`` on windows ``data``: its likelihood, in eval mode (see
    :func:`held_out_nll_per_window`)."""
    return float(held_out_nll_per_window(model, data, batch_size).mean())


@torch.no_grad()
def dropout_objective_nll(
    model: nn.Module, data: MoGlowFeatures, seed: int = 0, batch_size: int = 256
) -> float:
    """The training objective on windows ``data``: mean NLL per frame with the history dropout masks drawn
    (training mode, flags from ``seed``).

    For a model trained with dropout ``p > 0`` this is an average over masked inputs, a different quantity
    from the model's likelihood :func:`held_out_nll` (it equals it for ``p = 0``). The model's mode is
    restored afterwards; call it on a trained model (a fresh one would initialise its ActNorm layers).
    """
    check_scalar(seed, "seed", "dropout_objective_nll", kind=numbers.Integral, minimum=0)
    check_scalar(batch_size, "batch_size", "dropout_objective_nll", kind=numbers.Integral, minimum=1)
    generator = torch.Generator().manual_seed(seed)
    was_training = model.training
    model.train()
    try:
        total, frames = 0.0, 0
        for pose, control in zip(data.pose.split(batch_size), data.control.split(batch_size)):
            total -= float(model(pose, control, generator).sum())
            frames += pose.shape[0] * (pose.shape[1] - model.cfg.history)
    finally:
        model.train(was_training)
    return total / frames
