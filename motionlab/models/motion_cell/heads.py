"""Rotation output heads: how a decoder's raw numbers become joint rotations.

The paper tests three joint-angle outputs (its §3, with the result in §5.1: quaternions and rotation
matrices comparable, both better than axis-angle): quaternions divided by their norm, rotation matrices
(9 numbers, made orthonormal by Gram–Schmidt) and axis-angle vectors (3 numbers, not normalised). Each
head reads ``params_per_joint`` raw numbers per joint and returns unit quaternions ``(..., 4)``, so every
loss and every downstream step stays the same. Raw outputs are offsets from the identity rotation (a raw
output of zero means "no rotation"), so a freshly initialised decoder starts near the rest pose
for every head.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Generic, NamedTuple, Protocol, TypeVar

import torch
from torch import Tensor, nn

from motionlab.geometry import axis_angle_to_quat, gram_schmidt, matrix_to_quat, quat_normalize
from motionlab.models.motion_cell.data import ROOT_DIM, PoseCodec
from motionlab.validation import Checked, check_tensor, choice

#: Rotation outputs a decoder can produce (compared in the chapter; the paper's §3 and §5.1).
OUTPUT_KINDS = ("quaternion", "matrix", "axis_angle")

_IDENTITY = {
    "quaternion": (1.0, 0.0, 0.0, 0.0),
    "matrix": (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),  # row-major 3 x 3
    "axis_angle": (0.0, 0.0, 0.0),
}


@dataclass(frozen=True)
class OutputHead(Checked):
    """Raw decoder outputs ``(..., params_per_joint)`` per joint -> unit quaternions ``(..., 4)``.

    Attributes:
        kind: one of :data:`OUTPUT_KINDS`.
    """

    kind: str = choice(OUTPUT_KINDS)

    @property
    def params_per_joint(self) -> int:
        """Raw numbers per joint: 4, 9 or 3."""
        return len(_IDENTITY[self.kind])

    def raw_dim(self, n_joints: int) -> int:
        """Raw numbers per pose: ``(J - 1) * params_per_joint`` rotations plus the 6 root channels."""
        return (n_joints - 1) * self.params_per_joint + ROOT_DIM

    def identity_offset(self, raw: Tensor) -> Tensor:
        """``raw`` ``(..., params_per_joint)`` moved so that zero means the identity rotation."""
        check_tensor(
            raw,
            "raw",
            f"OutputHead({self.kind}).identity_offset",
            trailing=(self.params_per_joint,),
            finite=False,
        )
        return raw + torch.tensor(_IDENTITY[self.kind], dtype=raw.dtype)

    def quaternions(self, params: Tensor) -> Tensor:
        """Unit quaternions ``(..., 4)`` from identity-offset parameters (see :meth:`identity_offset`)."""
        if self.kind == "quaternion":
            return quat_normalize(params)
        if self.kind == "matrix":
            return matrix_to_quat(gram_schmidt(params.unflatten(-1, (3, 3))))
        return axis_angle_to_quat(params)


def split_raw_pose(raw: Tensor, head: OutputHead, n_joints: int) -> tuple[Tensor, Tensor]:
    """Identity-offset rotation parameters ``(..., J - 1, p)`` and root channels ``(..., 6)`` of raw poses."""
    if raw.shape[-1] != head.raw_dim(n_joints):
        raise ValueError(
            f"split_raw_pose: a raw {head.kind} pose has {head.raw_dim(n_joints)} numbers, got "
            f"{tuple(raw.shape)}"
        )
    rotations = raw[..., :-ROOT_DIM].unflatten(-1, (n_joints - 1, head.params_per_joint))
    return head.identity_offset(rotations), raw[..., -ROOT_DIM:]


def assemble_pose(quaternions: Tensor, root: Tensor) -> Tensor:
    """A pose vector ``(..., (J - 1) * 4 + 6)`` from joint quaternions ``(..., J - 1, 4)`` and root
    channels."""
    return torch.cat([quaternions.flatten(-2), root], dim=-1)


class PosePrediction(NamedTuple):
    """Predicted pose vectors ``(B, T, 90)`` and the rotation outputs before projection ``(B, T, J - 1,
    p)``."""

    poses: Tensor
    rotation_params: Tensor


class _JointCount(Protocol):
    n_joints: int


C = TypeVar("C", bound=_JointCount)


class PoseNetwork(nn.Module, Generic[C]):
    """What the chapter's pose networks share: their config ``cfg`` (with ``n_joints``), the ``codec``
    with the root statistics and skeletons (checked to have as many joints), and the :class:`OutputHead` of
    ``kind`` that reads their raw outputs."""

    def __init__(self, cfg: C, codec: PoseCodec, kind: str) -> None:
        super().__init__()
        if codec.n_joints != cfg.n_joints:
            raise ValueError(
                f"{type(self).__name__}: the codec has {codec.n_joints} joints, the config {cfg.n_joints}"
            )
        self.cfg = cfg
        self.codec = codec
        self.head = OutputHead(kind)
