r"""MDM's data: benchmark clips as per-joint 6-D rotations plus the root's position, and the way back.

**The representation** (:func:`to_mdm`, :func:`from_mdm`). MDM's action-to-motion models read SMPL joint
rotations in the 6-D representation of Zhou et al. with the root translation as one more "joint"
(repository: ``data_rep='rot6d'``, ``pose_rep='rot6d'``, ``translation=True``, ``glob=True``), and compute
joint positions for the geometric losses by forward kinematics of the SMPL body at its mean shape
(``rot2xyz`` with ``betas=None``). The course's analogue, per frame:

* ``6 J`` channels: each joint's local rotation as the first two columns of its matrix
  (:func:`motionlab.geometry.matrix_to_sixd`), joint 0's being the root's global orientation;
* 3 channels: the root (pelvis) position in metres.

That is ``6 · 22 + 3 = 135`` channels. The repository pads the translation to 6 numbers to make it a
25th "joint" of a ``(25, 6)`` array; we keep the 3. Positions come from
:func:`motionlab.skeleton.forward_kinematics` with the average of the two body types
(:func:`~motionlab.skeleton.average_skeleton`), the counterpart of SMPL's mean shape: the model is not
told the body type. With a clip's own offsets the way back is exact.

**Preparation** (:func:`prepare`): each clip is turned about the vertical so that it starts facing +x and
moved horizontally so that its first root stands above the origin (heights kept, so the floor stays at
``z = 0``; the repository's action-to-motion loader also starts every clip's translation at the origin),
then every ``frame_stride``-th frame is kept: the default stride 2 gives 15 fps and 60 frames per 4-second
clip, the length of MDM's action-to-motion clips (60 frames). :func:`to_positions` interpolates back to 30
fps for the course's evaluators.

**Normalisation.** The network works on standardised channels (zero mean, unit variance per channel,
fitted on the training clips: :class:`~motionlab.data.datasets.Standardizer`, held by the model), so the
noise of the diffusion has the same scale in every channel. The repository's action-to-motion data is
not standardised (6-D rotations already lie in ``[-1, 1]``; its translations are a few metres at most);
its text-to-motion data is, with the data set's mean and std. Our root positions span several metres in
the walks and runs, hence the standardiser.

**Editing masks** (:func:`known_mask`): which channels of which frames are given, for in-betweening (known
frames) and body-part editing (known joints), as MDM's editing uses them (:mod:`.sampling`).
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from motionlab.data.augment import rotate_yaw
from motionlab.data.representations import heading_yaw
from motionlab.data.store import MotionSet
from motionlab.geometry import matrix_to_quat, matrix_to_sixd, quat_to_matrix, sixd_to_matrix
from motionlab.models.odmo.data import upsample_frames
from motionlab.skeleton import PARENTS, average_skeleton, forward_kinematics
from motionlab.train import TensorBatches
from motionlab.validation import check_scalar, check_tensor

#: Channels of one joint's rotation (the 6-D representation) and of the root position.
ROTATION_CHANNELS = 6
ROOT_CHANNELS = 3


def n_features(n_joints: int) -> int:
    """Channels per frame for ``n_joints`` joints: ``6 J + 3``."""
    return ROTATION_CHANNELS * n_joints + ROOT_CHANNELS


def n_joints_of(features: Tensor, where: str) -> int:
    """The joint count ``J`` of features ``(..., 6 J + 3)``; ``ValueError`` when the size does not fit."""
    size = features.shape[-1] - ROOT_CHANNELS
    if size < ROTATION_CHANNELS or size % ROTATION_CHANNELS:
        raise ValueError(f"{where}: features must be (..., 6 J + 3) with J >= 1, got {tuple(features.shape)}")
    return size // ROTATION_CHANNELS


def to_mdm(rotations: Tensor, root_positions: Tensor) -> Tensor:
    """MDM features ``(..., T, 6 J + 3)`` from local quaternions ``(..., T, J, 4)`` (joint 0's is the root's
    global orientation) and root positions ``(..., T, 3)`` in metres. Invert with :func:`from_mdm`."""
    where = "to_mdm"
    check_tensor(rotations, "rotations", where, trailing=(None, 4), min_leading=1)
    check_tensor(root_positions, "root_positions", where, trailing=(3,), min_leading=1)
    if rotations.shape[:-2] != root_positions.shape[:-1]:
        raise ValueError(
            f"{where}: rotations (..., T, J, 4) and root_positions (..., T, 3) must share (..., T), got "
            f"{tuple(rotations.shape)} and {tuple(root_positions.shape)}"
        )
    sixd = matrix_to_sixd(quat_to_matrix(rotations))
    return torch.cat([sixd.flatten(-2), root_positions], dim=-1)


def from_mdm(features: Tensor) -> tuple[Tensor, Tensor]:
    """Local quaternions ``(..., T, J, 4)`` and root positions ``(..., T, 3)`` from MDM features
    ``(..., T, 6 J + 3)``; any 6-D vectors with non-parallel halves are valid (Gram–Schmidt makes them
    rotations)."""
    check_tensor(features, "features", "from_mdm", min_leading=1)
    n_joints = n_joints_of(features, "from_mdm")
    sixd = features[..., : ROTATION_CHANNELS * n_joints].unflatten(-1, (n_joints, ROTATION_CHANNELS))
    return matrix_to_quat(sixd_to_matrix(sixd)), features[..., -ROOT_CHANNELS:]


def skeleton_offsets(offsets: Tensor | np.ndarray | None, n_joints: int, like: Tensor) -> Tensor:
    """The rest offsets for forward kinematics: ``offsets`` ``(J, 3)`` or ``(..., J, 3)``, by default the
    average skeleton's, in ``like``'s dtype."""
    if offsets is None:
        offsets = average_skeleton().offsets
    offsets = torch.as_tensor(offsets, dtype=like.dtype)
    if offsets.dim() < 2 or offsets.shape[-2:] != (n_joints, 3):
        raise ValueError(
            f"skeleton_offsets: offsets must be ({n_joints}, 3) or (..., {n_joints}, 3), "
            f"got {tuple(offsets.shape)}"
        )
    return offsets


def joint_positions(features: Tensor, offsets: Tensor | np.ndarray | None = None) -> Tensor:
    """Joint positions ``(..., T, J, 3)`` in metres of MDM features ``(..., T, 6 J + 3)`` by forward
    kinematics (differentiable; the geometric losses use it); ``offsets`` as in :func:`skeleton_offsets`."""
    check_tensor(features, "features", "joint_positions", min_leading=1)
    n_joints = n_joints_of(features, "joint_positions")
    if n_joints != len(PARENTS):
        raise ValueError(f"joint_positions: the course skeleton has {len(PARENTS)} joints, got {n_joints}")
    rotations, root = from_mdm(features)
    offsets = skeleton_offsets(offsets, n_joints, features)
    if offsets.dim() > 2:  # per clip (N, J, 3): one skeleton for all of a clip's frames
        offsets = offsets.unsqueeze(-3)
    return forward_kinematics(rotations, root, offsets, PARENTS)[0]


def to_positions(features: Tensor, frame_stride: int, offsets: Tensor | np.ndarray | None = None) -> Tensor:
    """Joint positions at the data's frame rate ``(N, T · frame_stride, J, 3)`` from MDM features ``(N, T, 6 J
    + 3)`` (model frames interpolated, :func:`~motionlab.models.odmo.data.upsample_frames`)."""
    check_tensor(features, "features", "to_positions", ndim=3)
    check_scalar(frame_stride, "frame_stride", "to_positions", kind=numbers.Integral, minimum=1)
    with torch.no_grad():
        return upsample_frames(joint_positions(features, offsets), frame_stride)


@dataclass(frozen=True, eq=False)
class MDMData:
    """Clips prepared for MDM.

    Attributes:
        features: ``(N, T, 6 J + 3)`` float32, in metres (not standardised; the model standardises).
        action: ``(N,)`` int64 action class (the condition); mode, body: ``(N,)`` int64 true style mode and
            body type (for evaluation only: the model never sees them).
        frame_stride: frames of the 30 fps data per model frame.
    """

    features: Tensor
    action: Tensor
    mode: Tensor
    body: Tensor
    frame_stride: int

    def __len__(self) -> int:
        return int(self.features.shape[0])

    def batches(self) -> TensorBatches:
        """The training loop's batch source: shuffled ``(features (B, T, F), action (B,))`` batches."""
        return TensorBatches((self.features, self.action))


def face_origin(positions: Tensor, rotations: Tensor) -> tuple[Tensor, Tensor]:
    """Clips ``(N, T, J, 3)``, ``(N, T, J, 4)`` turned about z to start facing +x (heading yaw 0), their first
    root moved horizontally to the origin (heights kept)."""
    check_tensor(positions, "positions", "face_origin", trailing=(None, 3), ndim=4)
    check_tensor(rotations, "rotations", "face_origin", trailing=(None, 4), ndim=4)
    positions, rotations = rotate_yaw(positions, rotations, -heading_yaw(rotations[:, 0, 0, :]))
    start = positions[:, :1, :1, :].clone()
    start[..., 2] = 0
    return positions - start, rotations


def prepare(data: MotionSet, frame_stride: int = 2) -> MDMData:
    """MDM features of a motion set (see the module notes)."""
    check_scalar(frame_stride, "frame_stride", "prepare", kind=numbers.Integral, minimum=1)
    if data.n_frames < 2 * frame_stride:
        raise ValueError(
            f"prepare: clips of {data.n_frames} frames are too short for frame_stride {frame_stride}"
        )
    positions, rotations = face_origin(
        torch.as_tensor(data.positions, dtype=torch.float64),
        torch.as_tensor(data.rotations, dtype=torch.float64),
    )
    features = to_mdm(rotations, positions[..., 0, :])[:, ::frame_stride].float().contiguous()
    labels = [torch.as_tensor(values, dtype=torch.int64) for values in (data.action, data.mode, data.body)]
    return MDMData(features, *labels, frame_stride)


def known_mask(
    n_frames: int,
    n_joints: int,
    *,
    frames: Sequence[int] = (),
    joints: Sequence[int] = (),
    root_position: bool = False,
) -> Tensor:
    """Which channels are given for an edit: ``(n_frames, 6 J + 3)`` bool, True where known.

    ``frames``: frames given whole (in-betweening: a prefix and a suffix); ``joints``: joints whose rotation
    channels are given in every frame (body-part editing); ``root_position``: the root position channels
    given in every frame. The three are combined with "or".
    """
    where = "known_mask"
    check_scalar(n_frames, "n_frames", where, kind=numbers.Integral, minimum=1)
    check_scalar(n_joints, "n_joints", where, kind=numbers.Integral, minimum=1)
    if not isinstance(root_position, bool):
        raise TypeError(f"{where}: root_position must be True or False, got {root_position!r}")
    mask = torch.zeros(n_frames, n_features(n_joints), dtype=torch.bool)
    for name, values, size in (("frames", frames, n_frames), ("joints", joints, n_joints)):
        for value in values:
            check_scalar(
                value, f"every entry of {name}", where, kind=numbers.Integral, minimum=0, maximum=size - 1
            )
    mask[list(frames)] = True
    for joint in joints:
        mask[:, ROTATION_CHANNELS * joint : ROTATION_CHANNELS * (joint + 1)] = True
    if root_position:
        mask[:, -ROOT_CHANNELS:] = True
    return mask
