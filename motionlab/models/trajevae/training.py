"""Build the chapter's completion models from their configs and train them (or load them) through the one
loop."""

from __future__ import annotations

from typing import NamedTuple

from torch import Tensor, nn

from motionlab import config
from motionlab.evaluation.evaluator import data_fingerprint
from motionlab.models.trajevae.baselines import CVAERNN, GRUCompletion, RecurrentConfig
from motionlab.models.trajevae.config import TrajeVAEConfig
from motionlab.models.trajevae.data import FRAME_STEP, CompletionBatches
from motionlab.models.trajevae.losses import cvae_rnn_loss, gru_loss, trajevae_loss
from motionlab.models.trajevae.model import TrajeVAE
from motionlab.train import PiecewiseLinear, TrainConfig, TrainResult, train_or_load
from motionlab.train.loop import LossFn

ModelConfig = TrajeVAEConfig | RecurrentConfig


class ChapterSetup(NamedTuple):
    """The chapter's models and schedules for one profile.

    Attributes:
        trajevae: the full TrajeVAE (the last rung of the ablation ladder); gru, cvae_rnn: the baselines.
        train: the schedule every model trains with (the same for all, so the ladder and the baselines are
            compared at equal cost).
        n_eval_windows: test windows the metrics average over (each with ``N_SAMPLES`` samples).
    """

    trajevae: TrajeVAEConfig
    gru: RecurrentConfig
    cvae_rnn: RecurrentConfig
    train: TrainConfig
    n_eval_windows: int


def chapter_setup(profile: str | None = None) -> ChapterSetup:
    """The :class:`ChapterSetup` of ``profile`` (``"quick"`` or ``"full"``; default: the active profile).

    Quick: tiny widths and a few dozen steps so every code path runs in seconds. Full: the models whose
    numbers the chapter reports, sized for its 3-minute budget on two CPU cores (measured in the chapter).
    """
    if profile not in (None, "quick", "full"):
        raise ValueError(f"chapter_setup: profile must be 'quick' or 'full', got {profile!r}")
    quick = config.is_quick() if profile is None else profile == "quick"
    steps = 30 if quick else 400
    trajevae = TrajeVAEConfig(
        n_frames=60,
        width=8 if quick else 32,
        latent_dim=4 if quick else 8,
        dct_components=4 if quick else 8,
        heads=2,
    )
    gru = RecurrentConfig(n_frames=60, hidden=8 if quick else 64)
    cvae_rnn = RecurrentConfig(n_frames=60, hidden=8 if quick else 48, latent_dim=4 if quick else 16)
    schedule = PiecewiseLinear(((0, 0.05), (steps // 8, 1.0), (steps, 0.05)))
    train = TrainConfig(
        steps=steps,
        batch_size=16 if quick else 32,
        lr=2e-3,
        grad_clip=None,
        lr_schedule=schedule,
        checkpoint_every=None if quick else 100,
    )
    return ChapterSetup(trajevae, gru, cvae_rnn, train, 12 if quick else 48)


def build_model(cfg: ModelConfig) -> nn.Module:
    """TrajeVAE for a :class:`TrajeVAEConfig`; the GRU (``latent_dim == 0``) or CVAE-RNN for a
    :class:`RecurrentConfig`."""
    if isinstance(cfg, TrajeVAEConfig):
        return TrajeVAE(cfg)
    if isinstance(cfg, RecurrentConfig):
        return CVAERNN(cfg) if cfg.latent_dim > 0 else GRUCompletion(cfg)
    raise TypeError(f"build_model: expected a TrajeVAEConfig or RecurrentConfig, got {type(cfg).__name__}")


def loss_function(cfg: ModelConfig) -> LossFn:
    """The training loss of the model that ``cfg`` builds (see :mod:`motionlab.models.trajevae.losses`)."""
    if isinstance(cfg, TrajeVAEConfig):
        return trajevae_loss
    if isinstance(cfg, RecurrentConfig):
        return cvae_rnn_loss if cfg.latent_dim > 0 else gru_loss
    raise TypeError(f"loss_function: expected a TrajeVAEConfig or RecurrentConfig, got {type(cfg).__name__}")


def train_completion_model(
    name: str,
    cfg: ModelConfig,
    positions: Tensor,
    rotations: Tensor,
    train_config: TrainConfig,
    progress: bool | None = None,
) -> tuple[nn.Module, TrainResult]:
    """Train the model of ``cfg`` on clips (or load it from the checkpoint cache); returns it in eval mode.

    Args:
        name: the run's cache name, e.g. ``"trajevae"``.
        positions, rotations: the training clips ``(N, T, J, 3)`` and ``(N, T, J, 4)`` at the chapter's frame
            rate (:func:`motionlab.models.trajevae.data.decimate`); their fingerprint is part of the cache
            key.
        train_config: steps, batch size, learning rate, ... of the one training loop.
    """
    model = build_model(cfg)
    batches = CompletionBatches(positions, rotations, cfg.augment, cfg.keep_probability)
    result = train_or_load(
        name,
        cfg,
        model,
        loss_function(cfg),
        batches,
        train_config,
        data_config=completion_data_config(batches.positions),
        progress=progress,
    )
    return model, result


def completion_data_config(positions: Tensor) -> dict:
    """What defines a completion model's training data (part of its cache key): the clips and the frame
    step."""
    return {"clips": data_fingerprint(positions), "frame_step": FRAME_STEP}
