"""Motion Cell sampling speed: a 4-second clip (120 frames at 30 fps) at batch 1 on one thread, and frames
per second at a large batch; the chapter's full-profile architecture (speed does not depend on the weights).

``rtf_b1_1thread`` times sampling pose vectors (joint rotations and root channels, what the model
outputs); ``rtf_b1_1thread_with_positions`` adds forward kinematics to joint positions.
"""

from __future__ import annotations

import numpy as np
import torch

from motionlab import config
from motionlab.bench._timing import generator_speed, median_seconds
from motionlab.models.motion_cell.data import PoseCodec
from motionlab.models.motion_cell.experiment import ExperimentConfig, build_model
from motionlab.skeleton import BODY_MEASUREMENTS, PARENTS

FPS = 30
FRAMES = 4 * FPS


def sampling_speed() -> dict:
    """Sampling speed of the Motion Cell (see the module notes)."""
    config.set_threads(1)
    settings = ExperimentConfig.current()
    codec = PoseCodec(np.stack([m.offsets() for m in BODY_MEASUREMENTS]), PARENTS)
    codec.root.fit(
        torch.randn(100, 6)
    )  # statistics only scale the root channels; they do not change the cost
    model = build_model(settings.motion_cell, codec).eval()
    generator = torch.Generator().manual_seed(0)

    def sample(batch_size: int) -> torch.Tensor:
        attributes = torch.zeros(batch_size, dtype=torch.int64)
        return model.generate(attributes, attributes, FRAMES, generator)

    def sample_positions() -> torch.Tensor:
        attributes = torch.zeros(1, dtype=torch.int64)
        return model.codec.positions(model.generate(attributes, attributes, FRAMES, generator), attributes)

    result = generator_speed(sample, FRAMES, FPS)
    result["rtf_b1_1thread_with_positions"] = (FRAMES / FPS) / median_seconds(sample_positions)
    result["frames"] = float(FRAMES)
    return result
