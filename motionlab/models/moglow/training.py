"""Training data and objective for the autoregressive models (MoGlow and the Gaussian baseline).

Both models map ``(pose (B, T, P), control (B, T, C))`` windows to per-sequence log-likelihoods of frames
``tau .. T-1``; the objective is their negative mean **per frame** (nats), the unit of the held-out
comparison of chapter 06.
"""

from __future__ import annotations

from dataclasses import asdict
from typing import Any, NamedTuple

import torch
from torch import Tensor, nn

from motionlab.data.synthetic import generator_fingerprint
from motionlab.evaluation.benchmark import Benchmark, benchmark_sizes
from motionlab.models.moglow.data import (
    MoGlowDataConfig,
    MoGlowFeatures,
    Scalers,
    clip_features,
    fit_scalers,
    sequence_windows,
    standardize,
)


class PreparedData(NamedTuple):
    """Standardised training windows (augmented), held-out test windows, and the scalers.

    ``train``/``test``: windows ``(M, length, ·)`` (the test windows are not augmented).
    """

    train: MoGlowFeatures
    test: MoGlowFeatures
    scalers: Scalers


def prepare_data(benchmark: Benchmark, cfg: MoGlowDataConfig, length: int, stride: int) -> PreparedData:
    """Windows of ``length`` frames (every ``stride``) from the benchmark's clips of ``cfg.actions``.

    The scalers are fitted on the augmented training clips; frame 0 of every clip (no control) is skipped.
    The benchmark's validation split is not used: nothing here is tuned on held-out data during training.
    """
    train = clip_features(benchmark.train, cfg, augment=True)
    scalers = fit_scalers(train)
    test = standardize(clip_features(benchmark.test, cfg, augment=False), scalers)
    return PreparedData(
        sequence_windows(standardize(train, scalers), length, stride),
        sequence_windows(test, length, stride),
        scalers,
    )


def data_identity(cfg: MoGlowDataConfig, length: int, stride: int) -> dict[str, Any]:
    """What defines the training data, for the checkpoint cache key (with the benchmark sizes and
    generator)."""
    return {
        "data": asdict(cfg),
        "length": length,
        "stride": stride,
        "sizes": list(benchmark_sizes()),
        "generator": generator_fingerprint(),
    }


def nll_per_frame_loss(
    model: nn.Module, batch: tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    """Mean negative log-likelihood per generated frame (nats) of a batch ``(pose, control)``."""
    pose, control = batch
    frames = pose.shape[1] - model.cfg.history
    nll = -model(pose, control).sum() / (pose.shape[0] * frames)
    return {"loss": nll, "nll": nll.detach()}


@torch.no_grad()
def held_out_nll(model: nn.Module, data: MoGlowFeatures, seed: int = 0, batch_size: int = 256) -> float:
    """Mean NLL per frame (nats) of ``model`` on windows ``data`` (history dropout flags drawn from
    ``seed``)."""
    generator = torch.Generator().manual_seed(seed)
    total, frames = 0.0, 0
    for pose, control in zip(data.pose.split(batch_size), data.control.split(batch_size)):
        total -= float(model(pose, control, generator).sum())
        frames += pose.shape[0] * (pose.shape[1] - model.cfg.history)
    return total / frames
