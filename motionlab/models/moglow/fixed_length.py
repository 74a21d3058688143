"""The fixed-length, control-conditioned Glow of MoGlow §3.4 on whole 4-second clips.

One multi-scale Glow (:class:`motionlab.models.flows.Glow`) over a clip's standardised poses
``(64, T)``, conditioned on its standardised control ``(3, T)``: the exact log-likelihood of a whole
clip in one pass, and sampling of a whole clip at once. It cannot generate longer clips, react to a
control that changes while it plays, or start from a given pose -- the reasons §4 of the paper moves
to the autoregressive model. Chapter 05 trains it; chapter 06 compares it with MoGlow.
"""

from __future__ import annotations

from typing import NamedTuple

import torch
from torch import Tensor

from motionlab.data.representations import from_moglow
from motionlab.evaluation.benchmark import Benchmark
from motionlab.models.flows.glow import Glow, GlowConfig
from motionlab.models.moglow.data import (
    CONTROL_DIM,
    POSE_DIM,
    MoGlowDataConfig,
    MoGlowFeatures,
    Scalers,
    clip_features,
    data_identity,
    fit_scalers,
    standardize,
)
from motionlab.models.moglow.experiment import ExperimentConfig
from motionlab.train import (
    PiecewiseLinear,
    TensorBatches,
    TrainConfig,
    TrainResult,
    build_seeded,
    train_or_load,
)
from motionlab.validation import check_tensor

#: Frames per clip (the benchmark's 4 s at 30 fps); divisible by 2**levels.
CLIP_FRAMES = 120


def channels_first(features: MoGlowFeatures) -> tuple[Tensor, Tensor]:
    """Poses ``(N, 64, T)`` and controls ``(N, 3, T)`` (contiguous) from features ``(N, T, ·)``."""
    check_tensor(features.pose, "features.pose", "channels_first", ndim=3, finite=False)
    check_tensor(features.control, "features.control", "channels_first", ndim=3, finite=False)
    return features.pose.transpose(1, 2).contiguous(), features.control.transpose(1, 2).contiguous()


def glow_config(cfg: ExperimentConfig) -> GlowConfig:
    """The Glow of ``cfg`` (``glow_steps_per_level``, ``glow_hidden``): three levels over 120 frames."""
    return GlowConfig(
        channels=POSE_DIM,
        length=CLIP_FRAMES,
        cond_channels=CONTROL_DIM,
        levels=3,
        steps_per_level=cfg.glow_steps_per_level,
        hidden=cfg.glow_hidden,
    )


def glow_train_config(cfg: ExperimentConfig) -> TrainConfig:
    """``cfg.glow_train_steps`` of AdamW with a linear decay of the learning rate."""
    steps = cfg.glow_train_steps
    return TrainConfig(
        steps=steps,
        batch_size=16,
        lr=2e-3,
        grad_clip=5.0,
        lr_schedule=PiecewiseLinear(((0, 1.0), (steps, 0.05))),
    )


def glow_nll_loss(
    model: Glow, batch: tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    """Mean negative log-likelihood in nats per dimension (per pose channel and frame) of a batch ``(x,
    cond)``."""
    x, cond = batch
    nll = -model.log_prob(x, cond).mean() / (x.shape[1] * x.shape[2])
    return {"loss": nll, "nll": nll.detach()}


class FixedLengthGlow(NamedTuple):
    """The trained Glow, its scalers and training result, and the standardised train and test clips
    ``(x (N, 64, T), cond (N, 3, T))``."""

    model: Glow
    scalers: Scalers
    result: TrainResult
    train: tuple[Tensor, Tensor]
    test: tuple[Tensor, Tensor]


def train_fixed_length_glow(
    benchmark: Benchmark,
    data_cfg: MoGlowDataConfig | None = None,
    progress: bool | None = None,
    cfg: ExperimentConfig | None = None,
) -> FixedLengthGlow:
    """Train (or load from the cache) the fixed-length Glow on the benchmark's clips of ``data_cfg.actions``.

    Training clips are augmented (mirror, time reversal) as ``data_cfg`` says (default: walk and jog); the
    test clips are not. The sizes and schedule come from ``cfg`` (default: the active profile's).
    """
    data_cfg = data_cfg if data_cfg is not None else MoGlowDataConfig()
    cfg = cfg if cfg is not None else ExperimentConfig.current()
    train = clip_features(benchmark.train, data_cfg, augment=True)
    scalers = fit_scalers(train)
    train_x = channels_first(standardize(train, scalers))
    test_x = channels_first(standardize(clip_features(benchmark.test, data_cfg, augment=False), scalers))
    model_cfg, train_cfg = glow_config(cfg), glow_train_config(cfg)
    model = build_seeded(lambda: Glow(model_cfg), train_cfg.seed)
    result = train_or_load(
        "fixed_length_glow",
        model_cfg,
        model,
        glow_nll_loss,
        TensorBatches(train_x),
        train_cfg,
        data_config=data_identity(data_cfg, CLIP_FRAMES, CLIP_FRAMES),
        progress=progress,
    )
    return FixedLengthGlow(model, scalers, result, train_x, test_x)


def sample_clips(
    glow: FixedLengthGlow, control: Tensor, temperature: float = 1.0, generator: torch.Generator | None = None
) -> tuple[Tensor, Tensor]:
    """Whole clips for controls ``(B, T, 3)`` (m/frame, rad/frame): poses ``(B, T, 64)`` in metres and world
    joint positions ``(B, T, 22, 3)`` (root path integrated from the control, starting at the origin)."""
    check_tensor(control, "control", "sample_clips", trailing=(CONTROL_DIM,), ndim=3)
    cond = glow.scalers.control.transform(control).transpose(1, 2).contiguous()
    sample = glow.model.sample(cond, temperature=temperature, generator=generator)
    pose = glow.scalers.pose.inverse(sample.transpose(1, 2))
    return pose, from_moglow(torch.cat([pose, control], dim=-1))
