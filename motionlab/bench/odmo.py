"""ODMO's generation speed: code -> trajectory -> motion -> 30 fps joint positions, at batch 1 and batched.

The networks are the chapter's (:func:`~motionlab.models.odmo.experiment.chapter_model`, 40 model
frames at 10 fps, upsampled to a 4-second clip of 120 frames). Weights are untrained: the speed does not
depend on them.
"""

from __future__ import annotations

import torch

from motionlab import config
from motionlab.bench._timing import generator_speed
from motionlab.models.odmo.data import to_positions
from motionlab.models.odmo.experiment import chapter_model
from motionlab.models.odmo.model import ODMO

FPS = 30
FRAME_STRIDE = 3
SECONDS = 4


def generation_speed() -> dict:
    """``rtf_b1_1thread`` (target >= 100), ``seconds_b1`` and ``frames_per_second_batched``."""
    config.set_threads(1)
    torch.manual_seed(0)
    cfg = chapter_model(n_frames=SECONDS * FPS // FRAME_STRIDE)
    model = ODMO(cfg).fit_standardizer(torch.randn(8, cfg.n_frames, cfg.feature_dim)).eval()

    def generate(batch_size: int) -> torch.Tensor:
        code = torch.randn(batch_size, cfg.code_dim)
        action = torch.arange(batch_size) % cfg.n_classes
        end_point = torch.zeros(batch_size, 3)
        return to_positions(model.generate(code, action, end_point)[0], FRAME_STRIDE, 0.05)

    return generator_speed(generate, SECONDS * FPS, FPS)
