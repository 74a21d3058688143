"""Shared helpers of the Motion Cell tests: a few short synthetic clips and tiny models (no tests here)."""

from __future__ import annotations

import functools

import torch

from motionlab.data.store import MotionSet
from motionlab.data.synthetic import generate
from motionlab.models.motion_cell.baselines import BaselineConfig
from motionlab.models.motion_cell.data import PoseCodec, WindowBatch, motion_cell_features
from motionlab.models.motion_cell.experiment import build_model
from motionlab.models.motion_cell.model import MotionCellConfig

TINY = MotionCellConfig(word_dim=8, feature_dim=8, latent_dim=4, hidden_dim=8, control_dim=4)


@functools.cache
def clips() -> MotionSet:
    """One 1-second clip per style mode (12 clips of 30 frames)."""
    return generate(seed=0, n_per_mode=1, seconds=1.0)


@functools.cache
def features() -> torch.Tensor:
    data = clips()
    return motion_cell_features(data.rotations, data.positions)


def codec() -> PoseCodec:
    data = clips()
    return PoseCodec(data.offsets, data.parents.tolist()).fit(features())


def batch(frames: int = 12) -> WindowBatch:
    data = clips()
    poses = codec().encode(features())[:, :frames]
    return WindowBatch(poses, torch.as_tensor(data.action), torch.as_tensor(data.body))


def perturb(weight: torch.Tensor, std: float, seed: int = 0) -> None:
    """Fill ``weight`` with seeded Gaussian noise (a zero-initialised output layer that moves)."""
    with torch.no_grad():
        weight.copy_(std * torch.randn(weight.shape, generator=torch.Generator().manual_seed(seed)))


def motion_cell(**changes) -> torch.nn.Module:
    from dataclasses import replace

    return build_model(replace(TINY, **changes), codec(), seed=0)


def baseline(kind: str) -> torch.nn.Module:
    return build_model(BaselineConfig(kind=kind, hidden_dim=8, encoder_dim=8, control_dim=4), codec(), seed=0)
