"""Training ODMO through the course's one training loop (cached in ``build/checkpoints``).

Every variant trains the same way: class-balanced batches, AdamW, gradient clipping, and the motion
decoder's teacher forcing decaying linearly from 1 to 0.3 over the run (``LinearRamp``), as in the
reference implementation (``tf_min = 0.3``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import torch

from motionlab.evaluation.evaluator import data_fingerprint
from motionlab.models.odmo.config import ODMOConfig
from motionlab.models.odmo.contrastive import BalancedBatches
from motionlab.models.odmo.data import ODMOData
from motionlab.models.odmo.model import ODMO, joint_objective
from motionlab.train import LinearRamp, TrainConfig, TrainResult, train_or_load


@dataclass(frozen=True)
class ODMOTraining:
    """How long and how fast to train: optimiser ``steps``, ``batch_size`` (a multiple of the class count),
    AdamW ``lr``, the final teacher-forcing probability, and the ``seed`` of initialisation and batches."""

    steps: int = 400
    batch_size: int = 60
    lr: float = 3e-3
    teacher_forcing_end: float = 0.3
    seed: int = 0

    def train_config(self) -> TrainConfig:
        """The :class:`~motionlab.train.TrainConfig` with the teacher-forcing schedule."""
        if not 0.0 <= self.teacher_forcing_end <= 1.0:
            raise ValueError(
                f"ODMOTraining.teacher_forcing_end must be a probability, got {self.teacher_forcing_end}"
            )
        ramp = LinearRamp(start=0, length=self.steps, begin=1.0, end=self.teacher_forcing_end)
        return TrainConfig(
            steps=self.steps,
            batch_size=self.batch_size,
            lr=self.lr,
            grad_clip=1.0,
            seed=self.seed,
            schedules={"teacher_forcing": ramp},
            checkpoint_every=None,
            log_every=20,
        )


def run_name(variant: str) -> str:
    """A file-name-safe cache name for a variant, e.g. ``"-L_cons"`` -> ``"odmo_l_cons"``."""
    slug = re.sub(r"[^a-z0-9]+", "_", variant.lower()).strip("_")
    return "odmo" if slug == "odmo" else f"odmo_{slug}"


def train_odmo(
    variant: str, cfg: ODMOConfig, data: ODMOData, training: ODMOTraining, progress: bool | None = None
) -> tuple[ODMO, TrainResult]:
    """Build the model of ``cfg`` (seeded), fit its standardiser on ``data`` and train it, or load it from the
    cache."""
    if cfg.n_frames != data.features.shape[1] or cfg.feature_dim != data.features.shape[2]:
        raise ValueError(
            f"train_odmo: the config expects clips of {cfg.n_frames} frames x {cfg.feature_dim} features, "
            f"the data has {tuple(data.features.shape[1:])}"
        )
    torch.manual_seed(training.seed)
    model = ODMO(cfg).fit_standardizer(data.features)
    batches = BalancedBatches(data.features, data.action, cfg.n_classes)
    result = train_or_load(
        run_name(variant),
        cfg,
        model,
        joint_objective,
        batches,
        training.train_config(),
        data_config=odmo_data_config(data),
        progress=progress,
    )
    return model, result


def odmo_data_config(data: ODMOData) -> dict:
    """What defines ODMO's training data (part of every variant's cache key)."""
    return {
        "features": data_fingerprint(data.features),
        "action": data_fingerprint(data.action.float()),
        "frame_stride": data.frame_stride,
    }
