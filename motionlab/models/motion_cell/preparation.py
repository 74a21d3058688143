"""From clean clips to the training data of every model: capture noise, the denoiser, the denoised clips.

:func:`prepare_training_data` "captures" the training split through the noise model of
:func:`~motionlab.models.motion_cell.denoise.noisy_features`, trains the denoising autoencoder on noisy copies
of the validation split (whose clean version is known), and denoises the captured training split.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import torch
from torch import Tensor, nn

from motionlab import config
from motionlab.data.store import MotionSet
from motionlab.evaluation.evaluator import data_fingerprint
from motionlab.geometry import quat_geodesic
from motionlab.models.motion_cell.config import LossConfig
from motionlab.models.motion_cell.data import PoseCodec, WindowBatches, motion_cell_features
from motionlab.models.motion_cell.denoise import denoiser_loss, noisy_features
from motionlab.models.motion_cell.settings import ChapterSettings
from motionlab.models.motion_cell.training import train_model
from motionlab.train import TensorBatches, TrainConfig, TrainResult

#: Threads of the denoiser's training: it runs before the chapter's other training jobs (with the evaluators
#: cached by chapter 03, nothing else runs meanwhile), and its convolutions gain from both cores (24 s on one
#: thread, 17 s on two; the denoised clips had the same fingerprint on one and on two threads).
DENOISER_THREADS = 2

#: Seeds of the capture noise on the training split and of the denoiser's noisy copies of the validation
#: split.
CAPTURE_SEED, DENOISER_DATA_SEED = 1, 2


class PreparedData(NamedTuple):
    """The training data every model sees, and what the denoiser did to get it.

    Attributes:
        codec: pose-vector codec (root statistics of the captured training split, skeletons).
        captured: pose vectors of the captured (noisy) training split ``(N, T, 90)``.
        batches: windows of the denoised training split (:class:`WindowBatches`).
        fingerprint: identifies the denoised data in the models' cache keys.
        denoiser: the trained denoiser; denoiser_result: its training result.
        errors: mean joint-rotation error (degrees) against the clean clips, ``"captured"`` and
        ``"denoised"``.
    """

    codec: PoseCodec
    captured: Tensor
    batches: WindowBatches
    fingerprint: str
    denoiser: nn.Module
    denoiser_result: TrainResult
    errors: dict[str, float]


def cut_windows(poses: Tensor, length: int) -> Tensor:
    """Consecutive non-overlapping windows ``(N * (T // length), length, D)`` of clips ``(N, T, D)``."""
    n_windows = poses.shape[1] // length
    if n_windows < 1:
        raise ValueError(
            f"cut_windows: clips of {poses.shape[1]} frames are shorter than one window of {length}"
        )
    return poses[:, : n_windows * length].reshape(poses.shape[0] * n_windows, length, poses.shape[2])


def rotation_error_degrees(codec: PoseCodec, poses: Tensor, clean: Tensor) -> float:
    """Mean angle (degrees) between the joint rotations of two sets of pose vectors ``(..., 90)``."""
    return float(torch.rad2deg(quat_geodesic(codec.split(poses)[0], codec.split(clean)[0]).mean()))


def prepare_training_data(
    train: MotionSet, val: MotionSet, settings: ChapterSettings, progress: bool | None = None
) -> PreparedData:
    """Capture the training split with noise, train the denoiser on the validation split, denoise the
    capture."""
    captured = noisy_features(train.rotations, train.positions, CAPTURE_SEED)
    codec = PoseCodec(train.offsets, train.parents.tolist()).fit(captured)
    clean_val = codec.encode(motion_cell_features(val.rotations, val.positions))
    rng = np.random.default_rng(DENOISER_DATA_SEED)
    noisy_val = torch.cat(
        [
            codec.encode(noisy_features(val.rotations, val.positions, rng))
            for _ in range(settings.denoiser_copies)
        ]
    )
    pairs = TensorBatches(
        (
            cut_windows(noisy_val, settings.window),
            cut_windows(clean_val.repeat(settings.denoiser_copies, 1, 1), settings.window),
        )
    )
    denoiser_cfg = settings.denoiser
    loss_cfg = LossConfig()
    train_cfg = TrainConfig(
        steps=settings.denoiser_steps,
        batch_size=min(settings.denoiser_batch, len(pairs)),
        lr=settings.denoiser_lr,
        checkpoint_every=None,
    )
    with config.threads(DENOISER_THREADS):
        denoiser, result = train_model(
            "mcell_denoiser",
            denoiser_cfg,
            codec,
            denoiser_loss(loss_cfg),
            pairs,
            train_cfg,
            data_config={
                "val": data_fingerprint(noisy_val.numpy()),
                "codec": data_fingerprint(captured.numpy()),
                "window": settings.window,
            },
            loss_config=loss_cfg,
            progress=progress,
        )
    captured_poses = codec.encode(captured)
    denoised = denoiser.denoise(captured_poses)
    clean = codec.encode(motion_cell_features(train.rotations, train.positions))
    errors = {
        "captured": rotation_error_degrees(codec, captured_poses, clean),
        "denoised": rotation_error_degrees(codec, denoised, clean),
    }
    batches = WindowBatches(denoised, train.action, train.body, settings.window)
    return PreparedData(
        codec, captured_poses, batches, data_fingerprint(denoised.numpy()), denoiser, result, errors
    )
