"""The chapter 03 CVAE's generation speed: prior code -> standardised 2-second window -> 30 fps joint
positions.

The network has the full profile's sizes
(:meth:`~motionlab.models.vae.experiment.ExperimentConfig.clip_model`); weights are untrained and the
standardiser is fitted on noise: the speed depends on neither.
"""

from __future__ import annotations

import torch

from motionlab import config
from motionlab.bench._timing import generator_speed
from motionlab.data.datasets import Standardizer
from motionlab.models.vae.data import CLIP_FEATURES, ClipCodec
from motionlab.models.vae.experiment import ExperimentConfig
from motionlab.models.vae.model import MLPVAE

FPS = 30
N_ACTIONS = 6


def generation_speed() -> dict:
    """``rtf_b1_1thread``, ``seconds_b1`` and ``frames_per_second_batched`` of sampling one 2-second clip."""
    config.set_threads(1)
    torch.manual_seed(0)
    cfg = ExperimentConfig.current()
    model = MLPVAE(cfg.clip_model(N_ACTIONS)).eval()
    codec = ClipCodec(Standardizer(CLIP_FEATURES).fit(torch.randn(256, CLIP_FEATURES)), cfg.clip_length)
    generator = torch.Generator().manual_seed(0)

    def generate(batch_size: int) -> torch.Tensor:
        action = torch.arange(batch_size) % N_ACTIONS
        return codec.to_positions(model.sample(action, generator))

    return generator_speed(generate, cfg.clip_length, FPS)
