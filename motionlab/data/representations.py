"""Motion representations: four ways to turn a clip into per-frame feature vectors, and back.

Each representation is a pair of functions ``to_X`` / ``from_X`` on torch tensors, batched over leading
dimensions ``(..., T, ...)`` where ``T`` is the frame axis (30 fps). Conventions: z up, metres, quaternions
``(w, x, y, z)``; at rest a character faces +x and its left is +y. Joint 0 is the root (pelvis).

**Heading.** The root's global orientation ``q`` is split as ``q = yaw ⊗ tilt``: ``yaw`` turns about the
world z axis, ``tilt`` turns about a horizontal axis (the swing-twist decomposition about z). Then
``yaw = 2 atan2(q_z, q_w)``, and ``tilt`` is the shortest rotation that takes the world's up axis to the
pelvis's up axis, seen from the heading frame. The split is defined for every orientation except a pelvis
turned exactly upside down (``q_w = q_z = 0``), where :func:`split_heading` raises. Unlike the yaw of
Euler angles it has no gimbal lock at a 90° lean. The *heading frame* of a frame has its origin on the
floor below the root, x along the heading, y to the character's left and z up.

**Root control** (shared by Motion Cell and MoGlow). The features of frame ``t`` describe the step from
``t - 1`` to ``t``: the displacement of the root's floor projection expressed in the heading frame of frame
``t - 1`` (forward, sideways; metres per frame, multiply by the fps for m/s) and the yaw rate
``wrap(yaw_t - yaw_{t-1})`` in radians per frame. Frame 0 has no previous frame: its control is zero,
and the inverses take the first frame's root position and yaw as a :class:`RootStart`.

The four representations (``J`` joints; ``J = 22`` gives the dimension in brackets):

* :func:`to_motion_cell` (Motion Cell) [90]: the ``J - 1`` non-root local quaternions, then forward and
  sideways velocity, root height, yaw rate, pitch and roll of the root in the heading frame.
* :func:`to_odmo` (ODMO) [66]: local movement profile (non-root joints minus the root position, world
  axes, not rotated), then the root trajectory with the first frame's root at the origin.
* :func:`to_moglow` (MoGlow) [67]: pose in the heading frame (root height, then the non-root joints'
  xyz), then the three control channels.
* :func:`to_trajevae` (TrajeVAE) [66]: global joint positions shifted horizontally so that the first
  frame's pelvis is above the origin; heights are kept, so the floor stays at z = 0.

:func:`representation` describes each one (dimension, named channel groups, encode and decode) for the
data sets and the models.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import NamedTuple

import torch
from torch import Tensor

from motionlab import validation
from motionlab.geometry import axis_angle_to_quat, quat_mul, quat_normalize, quat_to_axis_angle
from motionlab.skeleton import forward_kinematics

#: Below this value of ``q_w**2 + q_z**2`` the root is considered upside down and its heading undefined.
UPSIDE_DOWN_TOLERANCE = 1e-8

ROOT_FEATURES = ("forward_velocity", "sideways_velocity", "root_height", "yaw_rate", "pitch", "roll")
"""The six Motion Cell root channels, in order."""

CONTROL_FEATURES = ("forward_velocity", "sideways_velocity", "yaw_rate")
"""The three root control channels (Motion Cell velocities, MoGlow control), in order."""


class RootStart(NamedTuple):
    """Where a clip starts: the root position ``(..., 3)`` and heading yaw ``(...,)`` (radians) at frame 0.

    Each inverse uses what its representation leaves out: Motion Cell, MoGlow and TrajeVAE use the
    horizontal position and (the first two) the yaw; ODMO adds back the full xyz.
    """

    position: Tensor
    yaw: Tensor


# ----------------------------------------------------------------------------------------------------
# input checks


def _check_start(start: RootStart | None, leading: torch.Size, like: Tensor, func: str) -> RootStart:
    """``start`` checked against the clip's leading shape; ``None`` becomes the origin with yaw 0."""
    if start is None:
        return RootStart(like.new_zeros(leading + (3,)), like.new_zeros(leading))
    position = validation.check_tensor(start.position, "start.position", func, trailing=(3,))
    yaw = validation.check_tensor(start.yaw, "start.yaw", func)
    if position.shape[:-1] != leading or yaw.shape != leading:
        raise ValueError(
            f"{func}: start must have position {tuple(leading) + (3,)} and yaw {tuple(leading)} for "
            f"clips with leading shape {tuple(leading)}, got {tuple(position.shape)} and "
            f"{tuple(yaw.shape)}"
        )
    return RootStart(position.to(like.dtype), yaw.to(like.dtype))


def _n_joints(n_features: int, per_joint: int, extra: int, name: str, func: str) -> int:
    """Joint count ``J`` from a feature size ``(J - 1) * per_joint + extra``."""
    body, rest = divmod(n_features - extra, per_joint)
    if n_features <= extra or rest:
        raise ValueError(
            f"{func}: {name} has {n_features} features; expected (J - 1) * {per_joint} + {extra} "
            f"for a skeleton of J >= 2 joints"
        )
    return body + 1


# ----------------------------------------------------------------------------------------------------
# heading


def wrap_angle(angle: Tensor) -> Tensor:
    """``angle`` wrapped into ``[-pi, pi)``, elementwise."""
    return torch.remainder(angle + math.pi, 2 * math.pi) - math.pi


def yaw_to_quat(yaw: Tensor) -> Tensor:
    """The rotation by ``yaw`` ``(...,)`` radians about world z, as a quaternion ``(..., 4)``."""
    half = 0.5 * yaw
    zero = torch.zeros_like(half)
    return torch.stack([torch.cos(half), zero, zero, torch.sin(half)], dim=-1)


def split_heading(root_rotation: Tensor) -> tuple[Tensor, Tensor]:
    """Split a root orientation ``(..., 4)`` into its heading yaw ``(...,)`` and tilt ``(..., 4)``.

    ``root_rotation = yaw_to_quat(yaw) ⊗ tilt`` with ``tilt``'s rotation axis horizontal (its z
    component is zero) and ``yaw`` in ``[-pi, pi)``. Raises ``ValueError`` for a root turned upside down.
    """
    validation.check_tensor(root_rotation, "root_rotation", "split_heading", trailing=(4,))
    q = quat_normalize(root_rotation)
    w, z = q[..., 0], q[..., 3]
    upside_down = w * w + z * z < UPSIDE_DOWN_TOLERANCE
    if bool(upside_down.any()):
        where = tuple(int(i) for i in torch.nonzero(upside_down)[0])
        raise ValueError(
            f"split_heading: root orientation at index {where} is upside down; its heading is undefined"
        )
    yaw = wrap_angle(2.0 * torch.atan2(z, w))
    tilt = quat_mul(yaw_to_quat(-yaw), q)
    return yaw, tilt


def heading_yaw(root_rotation: Tensor) -> Tensor:
    """The heading yaw ``(...,)`` in ``[-pi, pi)`` of a root orientation ``(..., 4)`` (see
    :func:`split_heading`)."""
    return split_heading(root_rotation)[0]


def rotate_xy(xy: Tensor, angle: Tensor) -> Tensor:
    """Rotate horizontal vectors ``xy`` ``(..., 2)`` by ``angle`` (broadcast against ``(...,)``) about z."""
    cos, sin = torch.cos(angle), torch.sin(angle)
    x, y = xy[..., 0], xy[..., 1]
    return torch.stack([cos * x - sin * y, sin * x + cos * y], dim=-1)


def root_start(positions: Tensor, rotations: Tensor) -> RootStart:
    """The :class:`RootStart` of clips: root position ``(..., 3)`` and heading yaw ``(...,)`` at frame 0.

    Args:
        positions: global joint positions ``(..., T, J, 3)``, metres.
        rotations: local joint quaternions ``(..., T, J, 4)``; joint 0's is the root's global orientation.
    """
    validation.check_tensor(positions, "positions", "root_start", trailing=(None, 3), min_leading=1)
    validation.check_tensor(rotations, "rotations", "root_start", trailing=(None, 4), min_leading=1)
    return RootStart(positions[..., 0, 0, :], heading_yaw(rotations[..., 0, 0, :]))


# ----------------------------------------------------------------------------------------------------
# root control


def root_control(root_xy: Tensor, yaw: Tensor) -> Tensor:
    """Per-frame root control ``(..., T, 3)``: forward and sideways velocity (m/frame), yaw rate (rad/frame).

    Args:
        root_xy: the root's floor projection ``(..., T, 2)``, metres.
        yaw: heading yaw ``(..., T)``, radians.

    Frame ``t`` holds the step from ``t - 1`` to ``t``, the displacement in the heading frame of ``t - 1``;
    frame 0 is zero. :func:`integrate_root_control` inverts it.
    """
    validation.check_tensor(root_xy, "root_xy", "root_control", trailing=(2,), min_leading=1)
    validation.check_tensor(yaw, "yaw", "root_control", min_leading=1)
    if root_xy.shape[:-1] != yaw.shape:
        raise ValueError(
            f"root_control: root_xy (..., T, 2) and yaw (..., T) must share (..., T), "
            f"got {tuple(root_xy.shape)} and {tuple(yaw.shape)}"
        )
    step = rotate_xy(root_xy[..., 1:, :] - root_xy[..., :-1, :], -yaw[..., :-1])
    turn = wrap_angle(yaw[..., 1:] - yaw[..., :-1])
    control = torch.cat([step, turn[..., None]], dim=-1)
    return torch.cat([control.new_zeros(control.shape[:-2] + (1, 3)), control], dim=-2)


def integrate_root_control(control: Tensor, start_xy: Tensor, start_yaw: Tensor) -> tuple[Tensor, Tensor]:
    """Integrate root control ``(..., T, 3)`` from ``start_xy`` ``(..., 2)`` and ``start_yaw`` ``(...,)``.

    Returns the root's floor projection ``(..., T, 2)`` and the (unwrapped) heading yaw ``(..., T)``.
    Frame 0's control is ignored: the clip starts at ``start_xy`` facing ``start_yaw``.
    """
    func = "integrate_root_control"
    validation.check_tensor(control, "control", func, trailing=(3,), min_leading=1)
    validation.check_tensor(start_xy, "start_xy", func, trailing=(2,))
    validation.check_tensor(start_yaw, "start_yaw", func)
    if start_xy.shape[:-1] != control.shape[:-2] or start_yaw.shape != control.shape[:-2]:
        raise ValueError(
            f"{func}: start_xy must be {tuple(control.shape[:-2]) + (2,)} and start_yaw "
            f"{tuple(control.shape[:-2])} for control {tuple(control.shape)}, got "
            f"{tuple(start_xy.shape)} and {tuple(start_yaw.shape)}"
        )
    turn = control[..., 1:, 2]
    yaw = torch.cat([start_yaw[..., None], start_yaw[..., None] + torch.cumsum(turn, dim=-1)], dim=-1)
    steps = rotate_xy(control[..., 1:, :2], yaw[..., :-1])
    offsets = torch.cat([torch.zeros_like(control[..., :1, :2]), torch.cumsum(steps, dim=-2)], dim=-2)
    return start_xy[..., None, :] + offsets, yaw


# ----------------------------------------------------------------------------------------------------
# (a) Motion Cell


def to_motion_cell(rotations: Tensor, root_positions: Tensor) -> Tensor:
    """Motion Cell pose vectors ``(..., T, (J - 1) * 4 + 6)`` (90 for 22 joints).

    Args:
        rotations: local joint quaternions ``(..., T, J, 4)``, w first; joint 0's is the root's global
            orientation.
        root_positions: root (pelvis) positions ``(..., T, 3)``, metres.

    Layout per frame: joints 1..J-1's local quaternions as stored (no sign flips), then
    :data:`ROOT_FEATURES`: forward and sideways velocity in the heading frame (m/frame), root height (m),
    yaw rate (rad/frame), pitch and roll (rad). Pitch and roll are the tilt's rotation vector
    components about the heading frame's y (left; positive leans forward) and x (forward; positive
    drops the right side) axes. Invert with :func:`from_motion_cell`.
    """
    func = "to_motion_cell"
    validation.check_tensor(rotations, "rotations", func, trailing=(None, 4), min_leading=1)
    validation.check_tensor(root_positions, "root_positions", func, trailing=(3,), min_leading=1)
    if rotations.shape[:-2] != root_positions.shape[:-1] or rotations.shape[-2] < 2:
        raise ValueError(
            f"{func}: rotations (..., T, J, 4) with J >= 2 and root_positions (..., T, 3) must share "
            f"(..., T), got {tuple(rotations.shape)} and {tuple(root_positions.shape)}"
        )
    yaw, tilt = split_heading(rotations[..., 0, :])
    control = root_control(root_positions[..., :2], yaw)
    tilt_vector = quat_to_axis_angle(tilt)
    root = torch.stack(
        [
            control[..., 0],
            control[..., 1],
            root_positions[..., 2],
            control[..., 2],
            tilt_vector[..., 1],
            tilt_vector[..., 0],
        ],
        dim=-1,
    )
    return torch.cat([rotations[..., 1:, :].flatten(-2), root], dim=-1)


def from_motion_cell(features: Tensor, start: RootStart | None = None) -> tuple[Tensor, Tensor]:
    """Invert :func:`to_motion_cell`: local rotations ``(..., T, J, 4)`` and root positions ``(..., T, 3)``.

    The root path is integrated from ``start`` (its horizontal position and yaw; the height comes from
    the features), by default the origin facing +x. Joint quaternions are normalised, so the output is
    valid for any model output. Feed the result to :func:`motionlab.skeleton.forward_kinematics` for
    positions (or use ``representation("motion_cell").decode``).
    """
    func = "from_motion_cell"
    validation.check_tensor(features, "features", func, trailing=(None,), min_leading=1)
    n_joints = _n_joints(features.shape[-1], 4, len(ROOT_FEATURES), "features", func)
    start = _check_start(start, features.shape[:-2], features, func)
    joints = quat_normalize(features[..., : -len(ROOT_FEATURES)].unflatten(-1, (n_joints - 1, 4)))
    forward, sideways, height, turn, pitch, roll = features[..., -len(ROOT_FEATURES) :].unbind(-1)
    xy, yaw = integrate_root_control(
        torch.stack([forward, sideways, turn], dim=-1), start.position[..., :2], start.yaw
    )
    tilt = axis_angle_to_quat(torch.stack([roll, pitch, torch.zeros_like(roll)], dim=-1))
    root_rotation = quat_mul(yaw_to_quat(yaw), tilt)
    rotations = torch.cat([root_rotation[..., None, :], joints], dim=-2)
    return rotations, torch.cat([xy, height[..., None]], dim=-1)


# ----------------------------------------------------------------------------------------------------
# (b) ODMO


def to_odmo(positions: Tensor) -> Tensor:
    """ODMO features ``(..., T, (J - 1) * 3 + 3)`` (66 for 22 joints) from global positions ``(..., T, J,
    3)``.

    Layout per frame: the local movement profile, joints 1..J-1 minus the root position in world axes
    (not rotated, as in ODMO), then the root trajectory: root xyz minus the first frame's root xyz.
    Invert with :func:`from_odmo`.
    """
    validation.check_tensor(positions, "positions", "to_odmo", trailing=(None, 3), min_leading=1)
    if positions.shape[-2] < 2:
        raise ValueError(f"to_odmo: positions need at least 2 joints, got shape {tuple(positions.shape)}")
    root = positions[..., 0, :]
    local = positions[..., 1:, :] - root[..., None, :]
    trajectory = root - root[..., :1, :]
    return torch.cat([local.flatten(-2), trajectory], dim=-1)


def from_odmo(features: Tensor, start: RootStart | None = None) -> Tensor:
    """Invert :func:`to_odmo`: global positions ``(..., T, J, 3)``.

    The trajectory is placed at ``start.position`` (all three coordinates; the yaw is not used), by
    default the origin, which puts the first frame's pelvis at height 0.
    """
    func = "from_odmo"
    validation.check_tensor(features, "features", func, trailing=(None,), min_leading=1)
    n_joints = _n_joints(features.shape[-1], 3, 3, "features", func)
    start = _check_start(start, features.shape[:-2], features, func)
    root = features[..., -3:] + start.position[..., None, :]
    local = features[..., :-3].unflatten(-1, (n_joints - 1, 3))
    return torch.cat([root[..., None, :], local + root[..., None, :]], dim=-2)


# ----------------------------------------------------------------------------------------------------
# (c) MoGlow


def to_moglow(positions: Tensor, root_rotations: Tensor) -> Tensor:
    """MoGlow features ``(..., T, 1 + (J - 1) * 3 + 3)`` (67 for 22 joints).

    Args:
        positions: global joint positions ``(..., T, J, 3)``, metres.
        root_rotations: the root's global orientation ``(..., T, 4)``, which gives the heading.

    Layout per frame: the pose in the heading frame (origin on the floor below the root): root
    height, then joints 1..J-1's xyz; then :data:`CONTROL_FEATURES` (forward and sideways velocity in
    m/frame, yaw rate in rad/frame). The root's own horizontal position is always zero there, so it is
    left out. Invert with :func:`from_moglow`.
    """
    func = "to_moglow"
    validation.check_tensor(positions, "positions", func, trailing=(None, 3), min_leading=1)
    validation.check_tensor(root_rotations, "root_rotations", func, trailing=(4,), min_leading=1)
    if positions.shape[:-2] != root_rotations.shape[:-1] or positions.shape[-2] < 2:
        raise ValueError(
            f"{func}: positions (..., T, J, 3) with J >= 2 and root_rotations (..., T, 4) must share "
            f"(..., T), got {tuple(positions.shape)} and {tuple(root_rotations.shape)}"
        )
    yaw = heading_yaw(root_rotations)
    root_xy = positions[..., 0, :2]
    local_xy = rotate_xy(positions[..., 1:, :2] - root_xy[..., None, :], -yaw[..., None])
    local = torch.cat([local_xy, positions[..., 1:, 2:]], dim=-1)
    return torch.cat([positions[..., 0, 2:], local.flatten(-2), root_control(root_xy, yaw)], dim=-1)


def from_moglow(features: Tensor, start: RootStart | None = None) -> Tensor:
    """Invert :func:`to_moglow`: global positions ``(..., T, J, 3)``.

    The control is integrated from ``start`` (horizontal position and yaw; by default the origin facing
    +x) and each frame's pose is turned to its heading and placed above the root's floor projection.
    """
    func = "from_moglow"
    validation.check_tensor(features, "features", func, trailing=(None,), min_leading=1)
    n_joints = _n_joints(features.shape[-1], 3, 1 + len(CONTROL_FEATURES), "features", func)
    start = _check_start(start, features.shape[:-2], features, func)
    height = features[..., :1]
    local = features[..., 1 : -len(CONTROL_FEATURES)].unflatten(-1, (n_joints - 1, 3))
    root_xy, yaw = integrate_root_control(
        features[..., -len(CONTROL_FEATURES) :], start.position[..., :2], start.yaw
    )
    joints_xy = rotate_xy(local[..., :2], yaw[..., None]) + root_xy[..., None, :]
    joints = torch.cat([joints_xy, local[..., 2:]], dim=-1)
    root = torch.cat([root_xy, height], dim=-1)
    return torch.cat([root[..., None, :], joints], dim=-2)


# ----------------------------------------------------------------------------------------------------
# (d) TrajeVAE


def to_trajevae(positions: Tensor) -> Tensor:
    """TrajeVAE features ``(..., T, J * 3)`` (66 for 22 joints) from global positions ``(..., T, J, 3)``.

    All joints' global xyz, shifted horizontally so that the first frame's pelvis is above the origin;
    heights are untouched (the floor stays at z = 0). Joint 0's three channels are the root trajectory.
    Invert with :func:`from_trajevae`.
    """
    validation.check_tensor(positions, "positions", "to_trajevae", trailing=(None, 3), min_leading=1)
    first_pelvis = positions[..., 0, 0, :]
    shift = torch.cat([first_pelvis[..., :2], torch.zeros_like(first_pelvis[..., 2:])], dim=-1)
    return (positions - shift[..., None, None, :]).flatten(-2)


def from_trajevae(features: Tensor, start: RootStart | None = None) -> Tensor:
    """Invert :func:`to_trajevae`: global positions ``(..., T, J, 3)``, the first pelvis above ``start``'s
    xy."""
    func = "from_trajevae"
    validation.check_tensor(features, "features", func, trailing=(None,), min_leading=1)
    if features.shape[-1] % 3:
        raise ValueError(f"{func}: features has {features.shape[-1]} features; expected J * 3")
    start = _check_start(start, features.shape[:-2], features, func)
    shift = torch.cat([start.position[..., :2], torch.zeros_like(start.position[..., 2:])], dim=-1)
    return features.unflatten(-1, (-1, 3)) + shift[..., None, None, :]


# ----------------------------------------------------------------------------------------------------
# descriptions for data sets and models

Encoder = Callable[[Tensor, Tensor], Tensor]
"""``encode(positions (..., T, J, 3), rotations (..., T, J, 4)) -> features (..., T, D)``."""

Decoder = Callable[[Tensor, RootStart | None, Tensor | None, Tensor | None], Tensor]
"""``decode(features, start, offsets, parents) -> positions (..., T, J, 3)``."""


@dataclass(frozen=True)
class Representation:
    """What a representation's feature vector holds, and how to go there and back.

    Attributes:
        name: ``"motion_cell"``, ``"odmo"``, ``"moglow"`` or ``"trajevae"``.
        n_joints: the skeleton's joint count ``J``.
        dim: features per frame ``D``.
        channels: named groups of channels, each a slice of the last axis (groups may overlap, for
            example MoGlow's ``"pose"`` contains ``"root_height"``).
        encode: ``(positions (..., T, J, 3), rotations (..., T, J, 4)) -> features (..., T, D)``.
        decode: ``(features, start=None, offsets=None, parents=None) -> positions (..., T, J, 3)``;
            only Motion Cell needs the skeleton (``offsets`` ``(J, 3)`` or ``(..., J, 3)``, ``parents``
            ``(J,)``).
    """

    name: str
    n_joints: int
    dim: int
    channels: Mapping[str, slice]
    encode: Encoder
    decode: Decoder

    def select(self, features: Tensor, group: str) -> Tensor:
        """The channels of ``group`` from ``features`` ``(..., D)``."""
        if group not in self.channels:
            raise KeyError(f"{self.name} has no channel group {group!r}; groups: {sorted(self.channels)}")
        if features.shape[-1] != self.dim:
            raise ValueError(
                f"{self.name}: features must have {self.dim} channels, got shape {tuple(features.shape)}"
            )
        return features[..., self.channels[group]]


def _encode_motion_cell(positions: Tensor, rotations: Tensor) -> Tensor:
    return to_motion_cell(rotations, positions[..., 0, :])


def _decode_motion_cell(
    features: Tensor,
    start: RootStart | None = None,
    offsets: Tensor | None = None,
    parents: Tensor | None = None,
) -> Tensor:
    if offsets is None or parents is None:
        raise ValueError(
            "motion_cell decode: needs the skeleton's offsets and parents for forward kinematics"
        )
    rotations, root_positions = from_motion_cell(features, start)
    return forward_kinematics(rotations, root_positions, offsets, parents)[0]


def _encode_odmo(positions: Tensor, rotations: Tensor) -> Tensor:
    return to_odmo(positions)


def _decode_odmo(
    features: Tensor,
    start: RootStart | None = None,
    offsets: Tensor | None = None,
    parents: Tensor | None = None,
) -> Tensor:
    return from_odmo(features, start)


def _encode_moglow(positions: Tensor, rotations: Tensor) -> Tensor:
    return to_moglow(positions, rotations[..., 0, :])


def _decode_moglow(
    features: Tensor,
    start: RootStart | None = None,
    offsets: Tensor | None = None,
    parents: Tensor | None = None,
) -> Tensor:
    return from_moglow(features, start)


def _encode_trajevae(positions: Tensor, rotations: Tensor) -> Tensor:
    return to_trajevae(positions)


def _decode_trajevae(
    features: Tensor,
    start: RootStart | None = None,
    offsets: Tensor | None = None,
    parents: Tensor | None = None,
) -> Tensor:
    return from_trajevae(features, start)


def _motion_cell(n_joints: int) -> Representation:
    n_rot = (n_joints - 1) * 4
    channels = {"joint_rotations": slice(0, n_rot), "root": slice(n_rot, n_rot + len(ROOT_FEATURES))}
    channels |= {name: slice(n_rot + i, n_rot + i + 1) for i, name in enumerate(ROOT_FEATURES)}
    return Representation(
        "motion_cell",
        n_joints,
        n_rot + len(ROOT_FEATURES),
        channels,
        _encode_motion_cell,
        _decode_motion_cell,
    )


def _odmo(n_joints: int) -> Representation:
    n_local = (n_joints - 1) * 3
    channels = {"local_movement": slice(0, n_local), "trajectory": slice(n_local, n_local + 3)}
    return Representation("odmo", n_joints, n_local + 3, channels, _encode_odmo, _decode_odmo)


def _moglow(n_joints: int) -> Representation:
    n_pose = 1 + (n_joints - 1) * 3
    channels = {
        "pose": slice(0, n_pose),
        "root_height": slice(0, 1),
        "control": slice(n_pose, n_pose + len(CONTROL_FEATURES)),
    }
    return Representation(
        "moglow", n_joints, n_pose + len(CONTROL_FEATURES), channels, _encode_moglow, _decode_moglow
    )


def _trajevae(n_joints: int) -> Representation:
    channels = {"positions": slice(0, n_joints * 3), "root": slice(0, 3)}
    return Representation("trajevae", n_joints, n_joints * 3, channels, _encode_trajevae, _decode_trajevae)


_BUILDERS: dict[str, Callable[[int], Representation]] = {
    "motion_cell": _motion_cell,
    "odmo": _odmo,
    "moglow": _moglow,
    "trajevae": _trajevae,
}

REPRESENTATION_NAMES = tuple(_BUILDERS)
"""The names :func:`representation` knows."""


def representation(name: str, n_joints: int = 22) -> Representation:
    """The :class:`Representation` called ``name`` (one of :data:`REPRESENTATION_NAMES`) for ``n_joints``
    joints."""
    validation.check_choice(name, "name", "representation", REPRESENTATION_NAMES)
    validation.check_scalar(n_joints, "n_joints", "representation", kind=numbers.Integral, minimum=2)
    return _BUILDERS[name](int(n_joints))
