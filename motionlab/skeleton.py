"""The kinematic tree: joint names, the two body types, forward kinematics and joint impact weights.

Conventions (the course's, see ``DESIGN.md``): z up, right-handed, metres; a character stands facing
+x, so its left is +y. Quaternions are ``(..., 4)`` with w first.

**Rest pose.** With every local rotation the identity the skeleton stands upright facing +x, legs
straight under the hips, arms hanging at its sides and feet flat (the rest offsets below describe
that pose). So "zero rotation" means "neutral standing", which keeps rotation data centred on the
identity.

**Offsets.** ``offsets[j]`` is joint ``j``'s rest position relative to its parent, in the parent's
frame. The root's offset is zero: the root (pelvis) is placed by ``root_positions`` in
:func:`forward_kinematics`.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np
import torch

from motionlab.geometry import quat_apply, quat_mul, quat_normalize
from motionlab.validation import check_choice, check_finite, check_finite_array, check_scalar, check_tensor

#: The 22 joints, named and ordered like the SMPL body.
JOINT_NAMES: tuple[str, ...] = (
    "pelvis",
    "left_hip",
    "right_hip",
    "spine1",
    "left_knee",
    "right_knee",
    "spine2",
    "left_ankle",
    "right_ankle",
    "spine3",
    "left_foot",
    "right_foot",
    "neck",
    "left_collar",
    "right_collar",
    "head",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
)

#: Parent of each joint (-1 for the root); every parent comes before its children.
PARENTS: tuple[int, ...] = (-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19)

#: Joint indices by name, e.g. ``JOINT["left_ankle"] == 7``.
JOINT: dict[str, int] = {name: index for index, name in enumerate(JOINT_NAMES)}

#: The body types, indexed by the ``body`` label of the data (the Motion Cell paper's "gender" control).
BODY_TYPES: tuple[str, ...] = ("broad", "slender")


@dataclass(frozen=True)
class BodyMeasurements:
    """Lengths (metres) that define one body type's rest skeleton; widths are half-widths from the midline.

    The foot joint (SMPL's ``*_foot``) sits at the ball of the foot. The heel is not a joint; ``heel_back``
    and the floor give the point a flat foot rests on behind the ankle, which the generator needs.
    """

    ball_height: float  # foot joint (ball of the foot) above the floor when the foot is flat
    foot_drop: float  # ankle above the foot joint
    foot_length: float  # foot joint ahead of the ankle
    heel_back: float  # heel contact point behind the ankle (not a joint)
    shank: float  # knee to ankle
    thigh: float  # hip to knee
    hip_drop: float  # hip joints below the pelvis joint
    hip_width: float  # hip joints beside the midline
    spine1: float  # pelvis to spine1
    spine2: float  # spine1 to spine2
    spine3: float  # spine2 to spine3
    neck: float  # spine3 to neck
    head: float  # neck to head (the head joint is the middle of the head)
    head_top: float  # crown above the head joint (not a joint; gives the stature)
    collar_out: float  # collar joints beside the midline
    collar_up: float  # collar joints above spine3
    shoulder_out: float  # shoulder joints beside the collar joints
    shoulder_drop: float  # shoulder joints below the collar joints
    upper_arm: float  # shoulder to elbow
    forearm: float  # elbow to wrist

    def __post_init__(self) -> None:
        for f in fields(self):
            check_scalar(getattr(self, f.name), f.name, "BodyMeasurements", minimum=0)

    @property
    def ankle_height(self) -> float:
        """Height of the ankle joints above the floor when standing with flat feet."""
        return self.ball_height + self.foot_drop

    @property
    def root_height(self) -> float:
        """Height of the pelvis joint above the floor in the rest pose."""
        return self.ankle_height + self.shank + self.thigh + self.hip_drop

    @property
    def stature(self) -> float:
        """Standing height (floor to crown) in the rest pose."""
        spine = self.spine1 + self.spine2 + self.spine3 + self.neck + self.head
        return self.root_height + spine + self.head_top

    def offsets(self) -> np.ndarray:
        """Rest offsets ``(22, 3)`` of the SMPL-order joints (see the module notes), float64."""
        m = self
        table = {
            "pelvis": (0.0, 0.0, 0.0),
            "left_hip": (0.0, m.hip_width, -m.hip_drop),
            "right_hip": (0.0, -m.hip_width, -m.hip_drop),
            "spine1": (0.0, 0.0, m.spine1),
            "left_knee": (0.0, 0.0, -m.thigh),
            "right_knee": (0.0, 0.0, -m.thigh),
            "spine2": (0.0, 0.0, m.spine2),
            "left_ankle": (0.0, 0.0, -m.shank),
            "right_ankle": (0.0, 0.0, -m.shank),
            "spine3": (0.0, 0.0, m.spine3),
            "left_foot": (m.foot_length, 0.0, -m.foot_drop),
            "right_foot": (m.foot_length, 0.0, -m.foot_drop),
            "neck": (0.0, 0.0, m.neck),
            "left_collar": (0.0, m.collar_out, m.collar_up),
            "right_collar": (0.0, -m.collar_out, m.collar_up),
            "head": (0.0, 0.0, m.head),
            "left_shoulder": (0.0, m.shoulder_out, -m.shoulder_drop),
            "right_shoulder": (0.0, -m.shoulder_out, -m.shoulder_drop),
            "left_elbow": (0.0, 0.0, -m.upper_arm),
            "right_elbow": (0.0, 0.0, -m.upper_arm),
            "left_wrist": (0.0, 0.0, -m.forearm),
            "right_wrist": (0.0, 0.0, -m.forearm),
        }
        return np.array([table[name] for name in JOINT_NAMES], dtype=np.float64)


#: Measurements of each body type, in :data:`BODY_TYPES` order. "broad": 1.76 m tall, shoulders 0.40 m
#: apart, relatively long torso; "slender": 1.62 m tall, shoulders 0.33 m apart on a relatively wider
#: pelvis, relatively long legs (leg / stature 0.546 against 0.533).
BODY_MEASUREMENTS: tuple[BodyMeasurements, ...] = (
    BodyMeasurements(
        ball_height=0.025,
        foot_drop=0.06,
        foot_length=0.14,
        heel_back=0.05,
        shank=0.42,
        thigh=0.43,
        hip_drop=0.075,
        hip_width=0.095,
        spine1=0.115,
        spine2=0.14,
        spine3=0.065,
        neck=0.20,
        head=0.10,
        head_top=0.125,
        collar_out=0.075,
        collar_up=0.12,
        shoulder_out=0.125,
        shoulder_drop=0.02,
        upper_arm=0.30,
        forearm=0.26,
    ),
    BodyMeasurements(
        ball_height=0.022,
        foot_drop=0.052,
        foot_length=0.125,
        heel_back=0.045,
        shank=0.40,
        thigh=0.41,
        hip_drop=0.065,
        hip_width=0.088,
        spine1=0.10,
        spine2=0.13,
        spine3=0.055,
        neck=0.175,
        head=0.09,
        head_top=0.12,
        collar_out=0.062,
        collar_up=0.11,
        shoulder_out=0.105,
        shoulder_drop=0.02,
        upper_arm=0.27,
        forearm=0.235,
    ),
)


def _check_parent_order(parents: Sequence[int], n_joints: int, where: str) -> tuple[int, ...]:
    values = tuple(int(p) for p in parents)
    if len(values) != n_joints:
        raise ValueError(f"{where}: parents has {len(values)} entries but there are {n_joints} joints")
    if n_joints == 0 or values[0] != -1:
        raise ValueError(f"{where}: joint 0 must be the root (parent -1), got parents {list(values)}")
    for j, p in enumerate(values[1:], start=1):
        if not 0 <= p < j:
            raise ValueError(
                f"{where}: parents[{j}] = {p}; every joint's parent must be an earlier joint (0..{j - 1})"
            )
    return values


@dataclass(frozen=True, eq=False)
class Skeleton:
    """A kinematic tree: joint ``names``, ``parents`` (-1 for the root, ``parents[j] < j``) and rest
    ``offsets``.

    ``offsets`` is ``(J, 3)`` float64 (a private copy): each joint's rest position relative to its parent,
    metres.
    """

    names: tuple[str, ...]
    parents: tuple[int, ...]
    offsets: np.ndarray

    def __post_init__(self) -> None:
        names = tuple(str(n) for n in self.names)
        if len(set(names)) != len(names):
            raise ValueError(f"Skeleton: joint names must be unique, got {list(names)}")
        parents = _check_parent_order(self.parents, len(names), "Skeleton")
        offsets = np.array(self.offsets, dtype=np.float64)
        if offsets.shape != (len(names), 3):
            raise ValueError(f"Skeleton: offsets must have shape ({len(names)}, 3), got {offsets.shape}")
        check_finite_array(offsets, "offsets", "Skeleton")
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "offsets", offsets)

    @property
    def n_joints(self) -> int:
        """Number of joints ``J``."""
        return len(self.names)

    def bone_lengths(self) -> np.ndarray:
        """Length of the bone from each joint's parent to the joint, ``(J,)`` (0 for the root)."""
        return np.linalg.norm(self.offsets, axis=-1) * (np.asarray(self.parents) >= 0)

    def children(self, joint: int) -> tuple[int, ...]:
        """Direct children of ``joint``."""
        return tuple(j for j, p in enumerate(self.parents) if p == joint)

    def rest_positions(self) -> np.ndarray:
        """Joint positions ``(J, 3)`` in the rest pose with the root at the origin."""
        positions = np.zeros((self.n_joints, 3))
        for j in range(1, self.n_joints):
            positions[j] = positions[self.parents[j]] + self.offsets[j]
        return positions


def body_skeleton(body: int | str) -> Skeleton:
    """The 22-joint skeleton of body type ``body`` (an index into, or a name from, :data:`BODY_TYPES`)."""
    if isinstance(body, str):
        body = BODY_TYPES.index(check_choice(body, "body (a body type name)", "body_skeleton", BODY_TYPES))
    check_scalar(
        body,
        "body (an index or a name)",
        "body_skeleton",
        kind=numbers.Integral,
        minimum=0,
        maximum=len(BODY_TYPES) - 1,
    )
    return Skeleton(JOINT_NAMES, PARENTS, BODY_MEASUREMENTS[int(body)].offsets())


def average_skeleton() -> Skeleton:
    """The skeleton whose offsets are the mean of the body types' offsets."""
    offsets = np.mean([m.offsets() for m in BODY_MEASUREMENTS], axis=0)
    return Skeleton(JOINT_NAMES, PARENTS, offsets)


def subtree_reach(parents: Sequence[int], bone_lengths: np.ndarray) -> np.ndarray:
    """``L_j`` ``(J,)``: the longest path (sum of bone lengths) from joint ``j`` down to an end effector.

    ``bone_lengths[j]`` is the length of the bone from joint ``j``'s parent to ``j``; ``parents[j] < j``.
    Children are visited before their parents (from the last joint back), so a child's reach is known when
    its parent takes the maximum over its children. End effectors have ``L_j = 0``.
    """
    reach = np.zeros(len(parents))
    for j in range(len(parents) - 1, 0, -1):
        parent = parents[j]
        reach[parent] = max(reach[parent], reach[j] + bone_lengths[j])
    return reach


def joint_impact_weights(skeleton: Skeleton | None = None, leaf_floor: float = 0.1) -> np.ndarray:
    """Joint weights ``λ_j`` ``(J,)`` of the Motion Cell paper (eq. 23, its ``α_k``): how far a joint's
    rotation reaches.

    ``L_j`` is the longest path (sum of bone lengths) from joint ``j`` down to an end effector of its
    subtree, so rotating joint ``j`` by a small angle moves some joint by up to ``L_j`` times that angle.
    Leaves have ``L_j = 0``: their rotation moves no joint, yet it still carries the orientation of the
    head, hands and feet, so a zero weight would leave it unconstrained in a rotation loss. We raise every
    ``L_j`` to at least ``leaf_floor * max(L)`` and then divide by the mean, so the weights average 1 and a
    weighted loss keeps the scale of the unweighted one.

    Args:
        skeleton: the tree to weigh; default :func:`average_skeleton` (the mean of the body types).
        leaf_floor: the floor as a fraction of the largest ``L_j``, in ``[0, 1]``.
    Returns:
        float64 ``(J,)``, positive, mean 1.
    """
    skeleton = average_skeleton() if skeleton is None else skeleton
    check_scalar(leaf_floor, "leaf_floor", "joint_impact_weights", minimum=0, maximum=1)
    reach = subtree_reach(skeleton.parents, skeleton.bone_lengths())
    if reach.max() <= 0:
        raise ValueError("joint_impact_weights: the skeleton has no bone of positive length")
    floored = np.maximum(reach, leaf_floor * reach.max())
    return floored / floored.mean()


def forward_kinematics(
    rotations: torch.Tensor,
    root_positions: torch.Tensor,
    offsets: torch.Tensor | np.ndarray,
    parents: Sequence[int] | torch.Tensor | np.ndarray,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Global joint positions and rotations from local rotations (differentiable, batched).

    Joint ``j`` with parent ``p``: ``G_j = G_p * q_j`` and ``x_j = x_p + G_p . offsets_j``; the root's
    ``G_0 = q_0`` (its global orientation) and ``x_0 = root_positions``.

    Args:
        rotations: ``(..., J, 4)`` local quaternions, w first (the root's is its global orientation); any
            non-zero quaternions, normalised first (as everywhere in :mod:`motionlab.geometry`).
        root_positions: ``(..., 3)`` root positions, metres.
        offsets: ``(J, 3)`` rest offsets, or ``(..., J, 3)`` broadcastable against the batch.
        parents: ``(J,)`` parent indices, ``-1`` for joint 0 and ``parents[j] < j`` otherwise.
    Returns:
        ``positions (..., J, 3)`` and ``global_rotations (..., J, 4)``.
    Raises:
        TypeError: ``rotations`` is not a floating-point tensor.
        ValueError: on mismatched shapes, a bad parent order, non-finite values or zero quaternions.
    """
    where = "forward_kinematics"
    check_tensor(rotations, "rotations", where, trailing=(None, 4), finite=False)
    n_joints = rotations.shape[-2]
    batch = rotations.shape[:-2]
    order = _check_parent_order(
        parents.tolist() if isinstance(parents, (torch.Tensor, np.ndarray)) else parents, n_joints, where
    )
    root_positions = torch.as_tensor(root_positions, dtype=rotations.dtype, device=rotations.device)
    if root_positions.shape != batch + (3,):
        raise ValueError(
            f"{where}: root_positions must have shape {tuple(batch) + (3,)}, "
            f"got {tuple(root_positions.shape)}"
        )
    offsets = torch.as_tensor(offsets, dtype=rotations.dtype, device=rotations.device)
    if offsets.dim() < 2 or offsets.shape[-2:] != (n_joints, 3):
        raise ValueError(
            f"{where}: offsets must have shape ({n_joints}, 3) or (..., {n_joints}, 3), "
            f"got {tuple(offsets.shape)}"
        )
    try:
        offsets = offsets.expand(batch + (n_joints, 3))
    except RuntimeError as exc:
        raise ValueError(
            f"{where}: offsets {tuple(offsets.shape)} do not broadcast to the batch {tuple(batch)}"
        ) from exc
    for name, value in (("rotations", rotations), ("root_positions", root_positions), ("offsets", offsets)):
        check_finite(value, name, where)
    rotations = quat_normalize(rotations)
    global_rotations = [rotations[..., 0, :]]
    positions = [root_positions]
    for j in range(1, n_joints):
        parent = order[j]
        global_rotations.append(quat_mul(global_rotations[parent], rotations[..., j, :]))
        positions.append(positions[parent] + quat_apply(global_rotations[parent], offsets[..., j, :]))
    return torch.stack(positions, dim=-2), torch.stack(global_rotations, dim=-2)
