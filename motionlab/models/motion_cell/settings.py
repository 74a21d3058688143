"""The chapter's settings per profile: model sizes, training lengths, schedule values, evaluation sizes.

Fairness: every Table 2 model trains on the same denoised clips, with the same batch size, learning rate and
number of steps (the output-representation comparison has its own, shorter, equal budget), and is
evaluated by the same protocol (:mod:`motionlab.models.motion_cell.evaluate`).
"""

from __future__ import annotations

from dataclasses import dataclass

from motionlab import config
from motionlab.models.motion_cell.config import DenoiserConfig, MotionCellConfig


@dataclass(frozen=True)
class ChapterSettings:
    """Everything the chapter's runs depend on (one instance per profile, see :func:`chapter_settings`).

    Attributes:
        motion_cell: the full model's architecture (ablations and baselines are derived from it).
        denoiser: the denoising autoencoder's architecture.
        window: training window in frames (a multiple of the word length); batch_size, lr: for every run.
        steps: optimiser steps of every Table 2 model; representation_steps: of each output-head run;
        denoiser_steps, denoiser_batch, denoiser_lr: the denoiser's training (windows of ``window`` frames);
        denoiser_copies: noisy copies of the validation split it sees.
        beta: KL weight after annealing; classifier: lambda_CL after its ramp; word_drop: final word-drop
        rate. input_noise: ERD's final input noise (std, in pose-vector units); sampling: QuaterNet's final
            scheduled-sampling probability.
        n_per_combination, n_repeats: evaluation sample sets (per action x body) and their number.
    """

    motion_cell: MotionCellConfig
    denoiser: DenoiserConfig
    window: int
    batch_size: int
    lr: float
    steps: int
    representation_steps: int
    denoiser_steps: int
    denoiser_batch: int
    denoiser_lr: float
    denoiser_copies: int
    beta: float
    classifier: float
    word_drop: float
    input_noise: float
    sampling: float
    n_per_combination: int
    n_repeats: int


def chapter_settings() -> ChapterSettings:
    """The settings of the active profile: tiny and fast in ``quick``, the reported models in ``full``."""
    return config.choose(
        quick=ChapterSettings(
            MotionCellConfig(word_dim=16, feature_dim=16, latent_dim=8, hidden_dim=16, control_dim=8),
            DenoiserConfig(channels=16, bottleneck=8),
            window=24,
            batch_size=16,
            lr=3e-3,
            steps=12,
            representation_steps=10,
            denoiser_steps=10,
            denoiser_batch=8,
            denoiser_lr=1e-3,
            denoiser_copies=1,
            beta=0.2,
            classifier=1.0,
            word_drop=0.5,
            input_noise=0.05,
            sampling=1.0,
            n_per_combination=2,
            n_repeats=2,
        ),
        full=ChapterSettings(
            MotionCellConfig(word_dim=48, feature_dim=48, latent_dim=16, hidden_dim=64, control_dim=16),
            DenoiserConfig(channels=96, bottleneck=64),
            window=96,
            batch_size=32,
            lr=3e-3,
            steps=300,
            representation_steps=80,
            denoiser_steps=400,
            denoiser_batch=16,
            denoiser_lr=1e-3,
            denoiser_copies=3,
            beta=0.2,
            classifier=1.0,
            word_drop=0.5,
            input_noise=0.05,
            sampling=1.0,
            n_per_combination=20,
            n_repeats=5,
        ),
    )
