"""MoGlow's generation speed: frame-by-frame sampling of a 4-second clip and decoding to joint positions.

The model has the chapter's size in the active profile (``make bench`` runs the default, full profile:
:meth:`motionlab.models.moglow.experiment.ExperimentConfig.moglow`; its history dropout acts in training
only, so generation reads the full history); weights are untrained, which does not change the speed. Each
clip starts from ``H`` seed frames (the history, the paper's ``τ``) and generates 120 frames (4 s at 30 fps).
"""

from __future__ import annotations

import torch

from motionlab import config
from motionlab.bench._timing import generator_speed
from motionlab.models.moglow.data import MoGlowFeatures, fit_scalers
from motionlab.models.moglow.experiment import ExperimentConfig
from motionlab.models.moglow.model import MoGlow
from motionlab.models.moglow.sampling import generate_motion

FPS = 30
SECONDS = 4


def generation_speed() -> dict:
    """``rtf_b1_1thread`` (target >= 100), ``seconds_b1`` and ``frames_per_second_batched``."""
    config.set_threads(1)
    torch.manual_seed(0)
    model = MoGlow(ExperimentConfig.current().moglow(0.5)).eval()
    history, frames = model.cfg.history, SECONDS * FPS
    scalers = fit_scalers(
        MoGlowFeatures(torch.randn(16, 30, model.cfg.pose_dim), 0.03 * torch.randn(16, 30, 3))
    )

    def generate(batch_size: int) -> torch.Tensor:
        seed = MoGlowFeatures(
            torch.randn(batch_size, history, model.cfg.pose_dim), torch.zeros(batch_size, history, 3)
        )
        control = torch.full((batch_size, frames, 3), 0.04)
        return generate_motion(model, scalers, control, seed, 1.0, torch.Generator().manual_seed(0)).positions

    return generator_speed(generate, frames, FPS)
