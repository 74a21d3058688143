"""Data augmentation for clips: left/right mirroring and random turns about the vertical axis.

Both act on the generator's data format, batched over leading dimensions: global joint positions
``(..., T, J, 3)`` (metres, z up) and local joint quaternions ``(..., T, J, 4)`` (w first; joint 0's is
the root's global orientation). The random versions draw one choice per clip (per leading index) from an
explicit ``torch.Generator``, so the same seed gives the same augmented data.

**Mirroring** reflects the world through the xz plane, ``M = diag(1, -1, 1)``: a character facing +x
is reflected across its own sagittal plane. Positions map ``y -> -y``; a rotation ``R`` maps to ``M R M``,
which for a quaternion is ``(w, x, y, z) -> (w, -x, y, -z)``; then the ``left_*`` and ``right_*`` joints
swap places. Because ``M G_parent M`` times ``M L_joint M`` is ``M G_joint M``, forward kinematics of the
mirrored rotations with the mirrored offsets (:func:`mirror_positions` applied to the offsets) gives the
mirrored positions. A left/right symmetric skeleton mirrors to itself. In derived features the sideways
velocity, the yaw rate and the roll change sign.

**Yaw rotation** turns whole clips by an angle about the vertical axis through the origin: positions are
rotated, the root's global orientation is pre-multiplied by the turn, other local rotations stay.
Bone lengths, heights and the heading-frame features of Motion Cell and MoGlow do not change.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
from torch import Tensor

from motionlab.data.representations import rotate_xy, yaw_to_quat
from motionlab.geometry import quat_mul
from motionlab.skeleton import JOINT_NAMES
from motionlab.validation import check_scalar, check_tensor

_SIDES = ("left_", "right_")


def mirror_permutation(joint_names: Sequence[str]) -> Tensor:
    """Indices ``(J,)`` that swap every ``left_<part>`` joint with ``right_<part>`` (others map to
    themselves).

    Raises ``ValueError`` when a left or right joint has no partner.
    """
    index = {name: i for i, name in enumerate(joint_names)}
    if len(index) != len(joint_names):
        raise ValueError(f"mirror_permutation: joint names are not unique: {list(joint_names)}")
    permutation = list(range(len(joint_names)))
    for i, name in enumerate(joint_names):
        for side, other in (_SIDES, _SIDES[::-1]):
            if name.startswith(side):
                partner = other + name[len(side) :]
                if partner not in index:
                    raise ValueError(f"mirror_permutation: joint {name!r} has no partner {partner!r}")
                permutation[i] = index[partner]
    return torch.tensor(permutation, dtype=torch.long)


#: The left/right swap for the default 22-joint skeleton.
DEFAULT_MIRROR = mirror_permutation(JOINT_NAMES)


def _permutation(permutation: Tensor | None, n_joints: int, func: str) -> Tensor:
    permutation = DEFAULT_MIRROR if permutation is None else torch.as_tensor(permutation, dtype=torch.long)
    if permutation.shape != (n_joints,) or not torch.equal(
        torch.sort(permutation).values, torch.arange(n_joints)
    ):
        raise ValueError(
            f"{func}: permutation must be a permutation of {n_joints} joint indices, "
            f"got {permutation.tolist()}"
        )
    return permutation


def mirror_positions(positions: Tensor, permutation: Tensor | None = None) -> Tensor:
    """Mirror joint positions or skeleton offsets ``(..., J, 3)``: ``y -> -y``, then swap left and right.

    ``permutation`` ``(J,)`` defaults to :data:`DEFAULT_MIRROR` (22 joints).
    """
    check_tensor(positions, "positions", "mirror_positions", trailing=(None, 3))
    permutation = _permutation(permutation, positions.shape[-2], "mirror_positions")
    reflected = positions * positions.new_tensor([1.0, -1.0, 1.0])
    return reflected[..., permutation, :]


def mirror_rotations(rotations: Tensor, permutation: Tensor | None = None) -> Tensor:
    """Mirror joint quaternions ``(..., J, 4)``: ``(w, x, y, z) -> (w, -x, y, -z)``, then swap left and right.

    ``permutation`` ``(J,)`` defaults to :data:`DEFAULT_MIRROR` (22 joints).
    """
    check_tensor(rotations, "rotations", "mirror_rotations", trailing=(None, 4))
    permutation = _permutation(permutation, rotations.shape[-2], "mirror_rotations")
    reflected = rotations * rotations.new_tensor([1.0, -1.0, 1.0, -1.0])
    return reflected[..., permutation, :]


def check_clips(positions: Tensor, rotations: Tensor, func: str) -> None:
    """Check clips' global positions ``(..., T, J, 3)`` and local quaternions ``(..., T, J, 4)`` of the same
    ``(..., T, J)`` (``func`` names the caller in the messages)."""
    check_tensor(positions, "positions", func, trailing=(None, 3), min_leading=1)
    check_tensor(rotations, "rotations", func, trailing=(None, 4), min_leading=1)
    if positions.shape[:-1] != rotations.shape[:-1]:
        raise ValueError(
            f"{func}: positions (..., T, J, 3) and rotations (..., T, J, 4) must share (..., T, J), "
            f"got {tuple(positions.shape)} and {tuple(rotations.shape)}"
        )


def random_mirror(
    positions: Tensor,
    rotations: Tensor,
    generator: torch.Generator,
    p: float = 0.5,
    permutation: Tensor | None = None,
) -> tuple[Tensor, Tensor]:
    """Mirror each clip with probability ``p``; returns new ``(positions, rotations)``.

    Args:
        positions: ``(..., T, J, 3)``; rotations: ``(..., T, J, 4)``.
        generator: draws ``torch.rand(...)`` once, one number per clip; a clip is mirrored when its
            number is below ``p``.
        permutation: the left/right swap, :data:`DEFAULT_MIRROR` by default.
    """
    check_clips(positions, rotations, "random_mirror")
    check_scalar(p, "p (a probability)", "random_mirror", minimum=0, maximum=1)
    flip = torch.rand(positions.shape[:-3], generator=generator) < p
    flip = flip.to(positions.device)[..., None, None, None]
    mirrored_positions = mirror_positions(positions, permutation)
    mirrored_rotations = mirror_rotations(rotations, permutation)
    return torch.where(flip, mirrored_positions, positions), torch.where(flip, mirrored_rotations, rotations)


def rotate_yaw(positions: Tensor, rotations: Tensor, angle: Tensor) -> tuple[Tensor, Tensor]:
    """Turn clips by ``angle`` ``(...,)`` radians (counter-clockwise seen from above) about the world z axis.

    Args:
        positions: ``(..., T, J, 3)``, rotated about the vertical axis through the origin.
        rotations: ``(..., T, J, 4)``; only joint 0 (the root's global orientation) changes, to
            ``yaw_to_quat(angle) ⊗ q_root``.
    """
    check_clips(positions, rotations, "rotate_yaw")
    angle = check_tensor(
        torch.as_tensor(angle, dtype=positions.dtype, device=positions.device), "angle", "rotate_yaw"
    )
    if angle.shape != positions.shape[:-3]:
        raise ValueError(
            f"rotate_yaw: angle must have the clips' leading shape {tuple(positions.shape[:-3])}, "
            f"got {tuple(angle.shape)}"
        )
    turned_xy = rotate_xy(positions[..., :2], angle[..., None, None])
    turned_positions = torch.cat([turned_xy, positions[..., 2:]], dim=-1)
    root = rotations[..., 0, :]
    turned_root = quat_mul(yaw_to_quat(angle)[..., None, :].expand(root.shape), root)
    turned_rotations = torch.cat([turned_root[..., None, :], rotations[..., 1:, :]], dim=-2)
    return turned_positions, turned_rotations


def random_yaw(positions: Tensor, rotations: Tensor, generator: torch.Generator) -> tuple[Tensor, Tensor]:
    """Turn each clip by an angle drawn uniformly from ``[-pi, pi)`` (see :func:`rotate_yaw`).

    ``generator`` draws ``torch.rand(...)`` once, one number ``u`` per clip, and the angle is
    ``(2 u - 1) pi``.
    """
    check_clips(positions, rotations, "random_yaw")
    angle = (
        2.0 * torch.rand(positions.shape[:-3], generator=generator, dtype=positions.dtype) - 1.0
    ) * math.pi
    return rotate_yaw(positions, rotations, angle.to(positions.device))
