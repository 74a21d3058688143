"""Building and training the chapter's models through the course's one training loop.

Every model is built with its weights drawn from ``torch.manual_seed(seed)`` inside a forked RNG (the
caller's random state is untouched), then trained or loaded from the checkpoint cache by
:func:`motionlab.train.train_or_load`. The schedules of the Motion Cell objective are built by
:func:`motion_cell_schedules` from fractions of the run, so a short run and a long run share their shape.
"""

from __future__ import annotations

from typing import Any

from torch import nn

from motionlab.models.motion_cell.baselines import FrameBaseline
from motionlab.models.motion_cell.config import BaselineConfig, DenoiserConfig, MotionCellConfig
from motionlab.models.motion_cell.data import PoseCodec
from motionlab.models.motion_cell.denoise import DenoisingAutoencoder
from motionlab.models.motion_cell.losses import LossFn
from motionlab.models.motion_cell.model import MotionCellModel
from motionlab.train import KLAnneal, LinearRamp, TrainConfig, TrainResult, build_seeded, train_or_load
from motionlab.train import is_cached as cache_entry_exists
from motionlab.train.batches import BatchSource
from motionlab.train.schedules import Schedule

ModelConfig = MotionCellConfig | BaselineConfig | DenoiserConfig


def build_model(cfg: ModelConfig, codec: PoseCodec, seed: int = 0) -> nn.Module:
    """A fresh model for ``cfg`` (Motion Cell, baseline or denoiser), initialised from ``seed``.

    The model gets its own copy of ``codec``, so models never share (and overwrite) buffers.
    """
    builders = {
        MotionCellConfig: MotionCellModel,
        BaselineConfig: FrameBaseline,
        DenoiserConfig: DenoisingAutoencoder,
    }
    if type(cfg) not in builders:
        raise TypeError(f"build_model: unknown config type {type(cfg).__name__}")
    own_codec = PoseCodec(codec.offsets, codec.parents)
    own_codec.load_state_dict(codec.state_dict())
    return build_seeded(lambda: builders[type(cfg)](cfg, own_codec), seed)


def motion_cell_schedules(
    steps: int, beta: float = 1.0, classifier: float = 0.0, word_drop: float = 0.0
) -> dict[str, Schedule]:
    """The Motion Cell's coefficient schedules over a run of ``steps``.

    * ``beta``: KL annealing: 0 for the first 10% (warm-up), linear to ``beta`` by 40%, held, then a
      cool-down to half of it over the last 10%;
    * ``classifier``: lambda_CL, 0 for the first 30%, linear to ``classifier`` by 50% ("ramped in after
      the start": the classifier only makes sense once reconstructions look like motion);
    * ``word_drop``: scheduled motion-word dropping, from 0 at 10% to ``word_drop`` at 60%.
    """
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 10:
        raise ValueError(f"motion_cell_schedules: steps must be an integer >= 10, got {steps!r}")

    def at(fraction: float) -> int:
        return int(round(fraction * steps))

    return {
        "beta": KLAnneal(
            max_value=beta,
            warmup=at(0.1),
            anneal=at(0.3),
            cooldown_start=at(0.9),
            cooldown=at(0.1),
            cooldown_value=0.5 * beta,
        ),
        "classifier": LinearRamp(at(0.3), at(0.2), 0.0, classifier),
        "word_drop": LinearRamp(at(0.1), at(0.5), 0.0, word_drop),
    }


def is_cached(
    name: str,
    cfg: ModelConfig,
    train_config: TrainConfig,
    data_config: Any | None = None,
    loss_config: Any | None = None,
) -> bool:
    """Whether :func:`train_model` with these arguments would load from the checkpoint cache."""
    return cache_entry_exists(name, {"model": cfg, "loss": loss_config}, train_config, data_config)


def train_model(
    name: str,
    cfg: ModelConfig,
    codec: PoseCodec,
    loss_fn: LossFn,
    data: BatchSource,
    train_config: TrainConfig,
    data_config: Any | None = None,
    loss_config: Any | None = None,
    progress: bool | None = None,
) -> tuple[nn.Module, TrainResult]:
    """Build ``cfg``'s model (seeded by ``train_config.seed``) and train it, or load it from the cache.

    ``data_config`` (what defines the training data) and ``loss_config`` (the loss's fixed weights) go
    into the cache key with the model and training configs.
    """
    model = build_model(cfg, codec, train_config.seed)
    result = train_or_load(
        name,
        {"model": cfg, "loss": loss_config},
        model,
        loss_fn,
        data,
        train_config,
        data_config=data_config,
        progress=progress,
    )
    return model, result
