"""ODMO's data: benchmark clips as local movement profile + root trajectory, and generated features back to
positions.

Preparation (:func:`prepare`) does three things to each clip of a :class:`~motionlab.data.store.MotionSet`:

1. turns it about the vertical axis so that it starts facing +x (the course convention; the reference
   implementation rotates its clips to one heading too, ``rotate2xz``), so the model does not have to learn
   the random heading each clip happens to start with;
2. encodes it with :func:`motionlab.data.representations.to_odmo` (joints minus the root, and the root
   trajectory with the first frame's root at the origin: ``66`` channels for 22 joints);
3. keeps every ``frame_stride``-th frame (the chapter's stride 3: 10 fps, 40 frames for a 4-second clip),
   which cuts the cost of the autoregressive decoder threefold. :func:`to_positions` interpolates back to
   the data's 30 fps.

The ODMO features do not say how high the pelvis starts. :func:`to_positions` puts the lowest joint of
the first frame at the average height it has in the training data (``floor_clearance``), which puts
real clips back at their true height to 3 mm on average.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from motionlab.data.augment import rotate_yaw
from motionlab.data.representations import RootStart, check_tensor, from_odmo, heading_yaw, to_odmo
from motionlab.data.store import MotionSet


@dataclass(frozen=True, eq=False)
class ODMOData:
    """Clips prepared for ODMO.

    Attributes:
        features: ``(N, T, 3 (J - 1) + 3)`` float32; local movement profile then root trajectory (metres).
        action: ``(N,)`` int64 action class; mode: ``(N,)`` int64 true style mode; body: ``(N,)`` int64 body
            type (mode and body are for evaluation only: the model never sees them).
        frame_stride: frames of the 30 fps data per model frame.
        floor_clearance: mean height (metres) of the lowest joint in the first frame of the training clips.
    """

    features: Tensor
    action: Tensor
    mode: Tensor
    body: Tensor
    frame_stride: int
    floor_clearance: float

    @property
    def end_point(self) -> Tensor:
        """The end points ``r_e`` ``(N, 3)``: the last frame's root trajectory."""
        return self.features[:, -1, -3:]

    @property
    def lmp(self) -> Tensor:
        """The local movement profile ``(N, T, 3 (J - 1))``."""
        return self.features[..., :-3]

    def __len__(self) -> int:
        return int(self.features.shape[0])


def face_forward(positions: Tensor, rotations: Tensor) -> Tensor:
    """Clips ``(N, T, J, 3)`` turned about z so that each root starts with heading yaw 0 (facing +x)."""
    check_tensor(positions, "positions", "face_forward", (None, 3), min_leading=2)
    yaw = heading_yaw(rotations[:, 0, 0, :])
    return rotate_yaw(positions, rotations, -yaw)[0]


def lowest_first_joint(features: Tensor) -> Tensor:
    """Height of each clip's lowest non-root joint relative to the root in its first frame ``(N,)``."""
    return features[:, 0, :-3].unflatten(-1, (-1, 3))[..., 2].min(dim=-1).values


def prepare(data: MotionSet, frame_stride: int = 3, floor_clearance: float | None = None) -> ODMOData:
    """ODMO features of a motion set (see the module notes); ``floor_clearance`` defaults to this set's
    own."""
    if isinstance(frame_stride, bool) or not isinstance(frame_stride, int) or frame_stride < 1:
        raise ValueError(f"prepare: frame_stride must be a positive integer, got {frame_stride!r}")
    if data.n_frames < 2 * frame_stride:
        raise ValueError(
            f"prepare: clips of {data.n_frames} frames are too short for frame_stride {frame_stride}"
        )
    positions = face_forward(torch.as_tensor(data.positions), torch.as_tensor(data.rotations))
    features = to_odmo(positions)[:, ::frame_stride].contiguous()
    if floor_clearance is None:
        root_height = torch.as_tensor(data.positions[:, 0, 0, 2])
        floor_clearance = float((root_height + lowest_first_joint(features)).mean())
    return ODMOData(
        features.float(),
        torch.as_tensor(data.action, dtype=torch.int64),
        torch.as_tensor(data.mode, dtype=torch.int64),
        torch.as_tensor(data.body, dtype=torch.int64),
        frame_stride,
        float(floor_clearance),
    )


def upsample_frames(x: Tensor, factor: int) -> Tensor:
    """Linear interpolation along the frame axis ``(N, T, ...) -> (N, T · factor, ...)``.

    Model frame ``t`` becomes data frame ``t · factor``; the frames between are interpolated, and the
    ``factor - 1`` frames after the last one continue its last velocity.
    """
    if factor == 1:
        return x
    steps = torch.arange(factor, dtype=x.dtype) / factor
    shape = (1, 1, factor) + (1,) * (x.dim() - 2)
    following = torch.cat([x[:, 1:], 2 * x[:, -1:] - x[:, -2:-1]], dim=1)
    blended = x.unsqueeze(2) + steps.view(shape) * (following - x).unsqueeze(2)
    return blended.flatten(1, 2)


def to_positions(features: Tensor, frame_stride: int, floor_clearance: float) -> Tensor:
    """Global joint positions at the data's frame rate ``(N, T · frame_stride, J, 3)`` from ODMO features.

    The first frame's root is placed above the origin, at the height that puts the first frame's lowest
    joint ``floor_clearance`` metres above the floor.
    """
    check_tensor(features, "features", "to_positions", (None,), min_leading=2)
    if features.dim() != 3 or features.shape[-1] % 3 or features.shape[-1] < 6:
        raise ValueError(
            f"to_positions: features must be (N, T, 3 (J - 1) + 3) with J >= 2 joints, got "
            f"{tuple(features.shape)}"
        )
    height = floor_clearance - lowest_first_joint(features)
    start = torch.zeros(features.shape[0], 3, dtype=features.dtype)
    start[:, 2] = height
    positions = from_odmo(features, RootStart(start, torch.zeros(features.shape[0], dtype=features.dtype)))
    return upsample_frames(positions, frame_stride)
