"""Structured joint masks: which joints' trajectories are given, and the trajectories themselves.

TrajeVAE casts control as completion. A mask ``m`` ``(J,)`` marks the joints whose whole trajectory is known
(1) and the joints to complete (0); it is the same for every frame (a *structured* mask, not random
entries). With poses ``X`` ``(T, J, 3)`` the trajectories are ``Y = X ⊙ M`` (``M`` is ``m`` broadcast over
frames and coordinates): the given joints' coordinates, zeros elsewhere. The posterior sees the complement
``X ⊙ (1 - M)``.

In training each sequence draws its own mask, every joint kept independently with probability
:data:`KEEP_PROBABILITY` (0.15, so 3.3 of 22 joints on average). The paper draws coordinates from
Bernoulli(p_m) with p_m = 0.85 (§4) without saying which outcome has that probability; we read it as the
probability of being hidden, the reading closer to its aim of 3-4 trajectories on average.

For evaluation the joints are given in the paper's order, :data:`PAPER_ORDER`: right foot, left foot, right
hand, left hand (our skeleton's hands are the wrists), then :data:`FULL_ORDER` continues to all joints.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import torch
from torch import Tensor

from motionlab.skeleton import JOINT, JOINT_NAMES
from motionlab.validation import check_scalar, check_tensor

#: Probability that a joint's trajectory is given in a training sequence.
KEEP_PROBABILITY = 0.15

#: The paper's order of adding trajectories (Table 1, Figure 4): right foot, left foot, right hand, left hand.
PAPER_ORDER: tuple[str, ...] = ("right_foot", "left_foot", "right_wrist", "left_wrist")

#: All 22 joints: the paper's four first, then the head and pelvis, then the rest from the extremities
#: inwards.
FULL_ORDER: tuple[str, ...] = PAPER_ORDER + (
    "head",
    "pelvis",
    "right_elbow",
    "left_elbow",
    "right_knee",
    "left_knee",
    "right_ankle",
    "left_ankle",
    "right_shoulder",
    "left_shoulder",
    "neck",
    "spine3",
    "spine2",
    "spine1",
    "right_hip",
    "left_hip",
    "right_collar",
    "left_collar",
)


def sample_joint_masks(
    n_sequences: int,
    generator: torch.Generator,
    n_joints: int = len(JOINT_NAMES),
    keep_probability: float = KEEP_PROBABILITY,
) -> Tensor:
    """Random structured masks ``(n_sequences, n_joints)`` bool: each joint given with ``keep_probability``.

    One ``torch.rand`` draw of ``(n_sequences, n_joints)`` from ``generator``.
    """
    where = "sample_joint_masks"
    check_scalar(n_sequences, "n_sequences", where, kind=numbers.Integral, minimum=1)
    check_scalar(n_joints, "n_joints", where, kind=numbers.Integral, minimum=1)
    check_scalar(keep_probability, "keep_probability", where, minimum=0, maximum=1)
    return torch.rand((n_sequences, n_joints), generator=generator) < keep_probability


def joint_mask(joints: Sequence[str | int], n_joints: int = len(JOINT_NAMES)) -> Tensor:
    """The mask ``(n_joints,)`` bool with the given joints (names or indices) set."""
    mask = torch.zeros(n_joints, dtype=torch.bool)
    for joint in joints:
        if isinstance(joint, str):
            if joint not in JOINT:
                raise ValueError(f"joint_mask: unknown joint {joint!r}; joints are {JOINT_NAMES}")
            index = JOINT[joint]
        else:
            index = int(joint)
        if not 0 <= index < n_joints:
            raise ValueError(f"joint_mask: joint index {index} is outside [0, {n_joints})")
        mask[index] = True
    return mask


def first_joints(k: int, order: Sequence[str] = FULL_ORDER) -> Tensor:
    """The mask ``(22,)`` of the first ``k`` joints of ``order`` (``k = 0`` gives no trajectory at all)."""
    check_scalar(k, "k", "first_joints", kind=numbers.Integral, minimum=0, maximum=len(order))
    return joint_mask(order[:k])


def check_mask(mask: Tensor, name: str, where: str, shape: tuple[int, ...] | None = None) -> Tensor:
    """Check a joint mask ``(..., J)`` of dtype bool (of exactly ``shape`` if given) and return it.

    Raises ``TypeError`` for a non-tensor or a dtype other than bool, ``ValueError`` for a wrong shape.
    """
    if not isinstance(mask, Tensor) or mask.dtype != torch.bool:
        got = mask.dtype if isinstance(mask, Tensor) else type(mask).__name__
        raise TypeError(f"{where}: {name} must be a bool tensor (..., J), got {got}")
    if mask.dim() < 1 or (shape is not None and tuple(mask.shape) != shape):
        raise ValueError(f"{where}: {name} must have shape {shape or '(..., J)'}, got {tuple(mask.shape)}")
    return mask


def _check_poses_and_mask(poses: Tensor, mask: Tensor, where: str) -> None:
    check_tensor(poses, "poses", where, min_leading=2, finite=False)
    check_mask(mask, "mask", where)
    n_joints = mask.shape[-1]
    if poses.shape[-1] != 3 * n_joints:
        raise ValueError(
            f"{where}: poses have {poses.shape[-1]} channels but the mask has {n_joints} joints "
            f"(expected {3 * n_joints} = J * 3 channels)"
        )
    if mask.shape[:-1] != poses.shape[:-2]:
        raise ValueError(
            f"{where}: mask {tuple(mask.shape)} must have the leading shape of poses "
            f"{tuple(poses.shape[:-2])} plus the joint axis"
        )


def channel_mask(mask: Tensor) -> Tensor:
    """A joint mask ``(..., J)`` bool repeated for the x, y, z channels: ``(..., J * 3)`` bool."""
    check_mask(mask, "mask", "channel_mask")
    return mask.repeat_interleave(3, dim=-1)


def given_trajectories(poses: Tensor, mask: Tensor) -> Tensor:
    """``Y = X ⊙ M``: poses ``(..., T, J * 3)`` with the joints outside ``mask`` ``(..., J)`` set to zero."""
    _check_poses_and_mask(poses, mask, "given_trajectories")
    return poses * channel_mask(mask)[..., None, :].to(poses.dtype)


def hidden_poses(poses: Tensor, mask: Tensor) -> Tensor:
    """``X ⊙ (1 - M)``: poses ``(..., T, J * 3)`` with the given joints set to zero (what the posterior
    sees)."""
    _check_poses_and_mask(poses, mask, "hidden_poses")
    return poses * (~channel_mask(mask))[..., None, :].to(poses.dtype)
