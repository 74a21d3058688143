"""TrajeVAE speed: completing one 4-second window (batch 1, one thread) and 50 samples of a window in one
batch.

The weights do not change the cost, so the model is built from the chapter's full-profile configuration
without training. A "window" is the chapter's 4 s at 15 fps (60 frames: the initial pose and 59 completed
frames), given the right foot's and left foot's trajectories.
"""

from __future__ import annotations

import torch

from motionlab import config
from motionlab.bench._timing import generator_speed, median_seconds
from motionlab.models.trajevae.data import FPS
from motionlab.models.trajevae.experiment import ExperimentConfig
from motionlab.models.trajevae.masks import first_joints, given_trajectories
from motionlab.models.trajevae.model import TrajeVAE


def completion_speed() -> dict[str, float]:
    config.set_threads(1)
    cfg = ExperimentConfig.full().trajevae
    model = TrajeVAE(cfg).eval()
    generator = torch.Generator().manual_seed(0)
    windows = torch.randn(256, cfg.n_frames, cfg.n_channels, generator=generator)
    mask = first_joints(2).expand(256, -1)
    trajectories = given_trajectories(windows[:, 1:], mask)

    def complete(batch_size: int) -> torch.Tensor:
        return model.sample(windows[:batch_size, 0], trajectories[:batch_size], 1)

    speed = generator_speed(complete, cfg.n_frames, FPS)
    speed["seconds_50_samples_one_window"] = median_seconds(
        lambda: model.sample(windows[:1, 0], trajectories[:1], 50, generator=generator)
    )
    return speed
