"""What the evaluation classifiers see: joint positions in a body frame estimated from the hips.

Every model in the course can produce global joint positions, but not all of them produce joint rotations
(ODMO and TrajeVAE generate positions). So the classifiers read positions only: the heading is taken from
the hip line instead of the root's orientation, and the features are the MoGlow layout
(:func:`motionlab.data.representations.to_moglow`) in that heading frame: root height, the other joints'
xyz relative to the root's floor projection, and forward / sideways / yaw velocity per frame. They are
invariant to where the clip happens and which way it faces, which is what a style classifier should be.
"""

from __future__ import annotations

import torch
from torch import Tensor

from motionlab.data.representations import to_moglow, yaw_to_quat
from motionlab.skeleton import JOINT
from motionlab.validation import check_tensor

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
