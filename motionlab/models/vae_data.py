"""What the VAE chapter trains on, and the way back to joint positions.

* Single poses: the pose channels of the MoGlow representation (root height, then the 21 other joints' xyz
  in the heading frame: 64 numbers), taken every few frames of every clip. :func:`pose_to_positions`
  puts a pose back on the floor at the origin, facing +x.
* Short clips: windows of the MoGlow representation (pose plus root control, 67 numbers a frame),
  standardised per channel. A :class:`ClipCodec` turns a model's standardised output back into global
  positions ``(..., L, 22, 3)``, which is what the evaluation classifiers and the stick figures read.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from motionlab.data.datasets import MotionClips, Standardizer, WindowDataset, motion_windows
from motionlab.data.representations import CONTROL_FEATURES, from_moglow, representation

#: Numbers in a MoGlow pose vector for the 22-joint skeleton (root height + 21 x 3).
POSE_FEATURES = 64


def pose_features(clips: MotionClips, every: int = 10) -> Tensor:
    """Pose vectors ``(N * ceil(T / every), 64)`` from every ``every``-th frame of every clip, in metres.

    Uses the root's orientation for the heading (``rotations[..., 0, :]``), so each pose is seen from the
    character's own frame: facing +x, left +y, root above the origin.
    """
    if isinstance(every, bool) or not isinstance(every, int) or every < 1:
        raise ValueError(f"pose_features: every must be a positive integer, got {every!r}")
    rep = representation("moglow")
    positions = torch.as_tensor(clips.positions)[:, ::every]
    rotations = torch.as_tensor(clips.rotations)[:, ::every]
    features = rep.encode(positions, rotations)
    return rep.select(features, "pose").reshape(-1, POSE_FEATURES)


def pose_to_positions(poses: Tensor) -> Tensor:
    """Joint positions ``(..., 22, 3)`` of pose vectors ``(..., 64)``: root above the origin, facing +x."""
    if not isinstance(poses, Tensor) or poses.dim() < 1 or poses.shape[-1] != POSE_FEATURES:
        shape = tuple(poses.shape) if isinstance(poses, Tensor) else type(poses).__name__
        raise ValueError(f"pose_to_positions: poses must be a tensor (..., {POSE_FEATURES}), got {shape}")
    still = poses.new_zeros(poses.shape[:-1] + (len(CONTROL_FEATURES),))
    return from_moglow(torch.cat([poses, still], dim=-1)[..., None, :])[..., 0, :, :]


@dataclass(frozen=True, eq=False)
class ClipCodec:
    """Standardised MoGlow windows <-> global joint positions.

    Attributes:
        standardizer: per-channel statistics of the training windows (67 channels).
        length: frames per window.
    """

    standardizer: Standardizer
    length: int

    def to_positions(self, features: Tensor) -> Tensor:
        """Positions ``(..., L, 22, 3)`` of standardised windows ``(..., L, 67)``; each starts at the origin
        facing +x."""
        if not isinstance(features, Tensor) or features.dim() < 2 or features.shape[-2] != self.length:
            shape = tuple(features.shape) if isinstance(features, Tensor) else type(features).__name__
            raise ValueError(
                f"ClipCodec.to_positions: features must be (..., {self.length}, 67), got {shape}"
            )
        return from_moglow(self.standardizer.inverse(features.detach()))


def clip_windows(
    train: MotionClips, others: tuple[MotionClips, ...], length: int, stride: int
) -> tuple[ClipCodec, WindowDataset, tuple[WindowDataset, ...]]:
    """Standardised MoGlow windows of the training clips and of other splits (train statistics).

    Returns the codec, the training windows and the other splits' windows, each a
    :class:`~motionlab.data.datasets.WindowDataset` whose ``features`` are ``(W, length, 67)``.
    """
    rep = representation("moglow")
    raw = motion_windows(train, rep, length, stride)
    standardizer = Standardizer(rep.dim).fit(raw.features)
    train_windows = raw.with_features(standardizer.transform(raw.features))
    other_windows = tuple(
        motion_windows(clips, rep, length, stride, standardizer=standardizer) for clips in others
    )
    return ClipCodec(standardizer, length), train_windows, other_windows
