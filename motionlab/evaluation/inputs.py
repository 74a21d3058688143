"""What the evaluation classifiers see: joint positions in a body frame estimated from the hips.

Every model in the course can produce global joint positions, but not all of them produce joint rotations
(ODMO and TrajeVAE generate positions). So the classifiers read positions only: the heading is taken from
the hip line instead of the root's orientation, and the features are the MoGlow layout
(:func:`motionlab.data.representations.to_moglow`) in that heading frame: root height, the other joints'
xyz relative to the root's floor projection, and forward / sideways / yaw velocity per frame. They are
invariant to where the clip happens and which way it faces, which is what a style classifier should be.

The same frame measures how much a body moves: :func:`body_frame_poses` puts every frame's joints in it and
:func:`joint_speed` is their mean speed, travel over the floor and turning left out.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor

from motionlab.data.representations import to_moglow, yaw_to_quat
from motionlab.skeleton import JOINT
from motionlab.validation import check_scalar, check_tensor

#: Features per frame for the 22-joint skeleton: 1 root height + 21 × 3 joint coordinates + 3 velocities.
EVAL_FEATURES = 67


def hip_heading(positions: Tensor) -> Tensor:
    """Heading yaw ``(..., T)`` (radians) from the hip line of positions ``(..., T, 22, 3)``.

    The character's left is the direction from the right hip to the left hip; its forward direction is
    that vector turned by -90° about z (left × up), so a character at rest facing +x gets yaw 0.
    """
    check_tensor(positions, "positions", "hip_heading", trailing=(22, 3), min_leading=1)
    across = positions[..., JOINT["left_hip"], :2] - positions[..., JOINT["right_hip"], :2]
    if bool((across.norm(dim=-1) < 1e-6).any()):
        raise ValueError("hip_heading: the hips coincide in some frame, so the heading is undefined")
    return torch.atan2(-across[..., 0], across[..., 1])


def body_frame_features(positions: Tensor) -> Tensor:
    """Classifier input ``(..., T, 67)`` from global joint positions ``(..., T, 22, 3)`` (metres, z up)."""
    check_tensor(positions, "positions", "body_frame_features", trailing=(22, 3), min_leading=1)
    return to_moglow(positions, yaw_to_quat(hip_heading(positions)))


def body_frame_poses(positions: Tensor | np.ndarray) -> Tensor:
    """Joint positions ``(..., T, 22, 3)`` in each frame's body frame (root on the z axis, facing +x)."""
    features = body_frame_features(torch.as_tensor(np.asarray(positions), dtype=torch.float32))
    height = features[..., :1]
    root = torch.cat([torch.zeros_like(height), torch.zeros_like(height), height], dim=-1)
    return torch.cat([root[..., None, :], features[..., 1:64].unflatten(-1, (21, 3))], dim=-2)


def joint_speed(positions: Tensor | np.ndarray, fps: float = 30.0) -> Tensor:
    """Mean over joints of each frame's body-frame joint speed (m/s) ``(..., T)`` from global positions
    ``(..., T, 22, 3)`` at ``fps``; frame 0 repeats frame 1's.

    The body frame removes travel over the floor and turning, so a frozen pose scores 0 whether or not it
    glides: this is how much the body itself moves.
    """
    check_scalar(fps, "fps", "joint_speed", minimum=0.0, include_minimum=False)
    poses = body_frame_poses(positions)
    if poses.shape[-3] < 2:
        raise ValueError(f"joint_speed: need at least 2 frames, got {poses.shape[-3]}")
    speed = (poses[..., 1:, :, :] - poses[..., :-1, :, :]).norm(dim=-1).mean(-1) * fps
    return torch.cat([speed[..., :1], speed], dim=-1)
