"""The Motion Cell chapter's pose vectors: from clips to model space and back to joint positions.

Every model of the chapter reads and writes *pose vectors* ``(..., 90)`` for the 22-joint skeleton: the
21 non-root local quaternions (w first, unit length, as in
:func:`~motionlab.data.representations.to_motion_cell`) followed by the 6 root channels (forward and sideways
velocity, root height, yaw rate, pitch, roll), standardised with the training data's mean and standard
deviation. Quaternions are not standardised: the losses compare them as rotations. :class:`PoseCodec` holds
the root statistics and the skeletons, travels inside each model's checkpoint, and turns pose vectors into
joint positions.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterator, Sequence
from typing import NamedTuple

import numpy as np
import torch
from torch import Tensor, nn

from motionlab.data.datasets import Standardizer, gather_windows
from motionlab.data.representations import RootStart, from_motion_cell, to_motion_cell
from motionlab.skeleton import forward_kinematics
from motionlab.validation import check_scalar, check_tensor

#: Root channels at the end of every pose vector (:data:`motionlab.data.representations.ROOT_FEATURES`).
ROOT_DIM = 6


def pose_dim(n_joints: int) -> int:
    """Channels of one pose vector of a ``n_joints`` skeleton: ``J - 1`` quaternions and the 6 root
    channels."""
    return (n_joints - 1) * 4 + ROOT_DIM


def motion_cell_features(rotations: Tensor | np.ndarray, positions: Tensor | np.ndarray) -> Tensor:
    """Motion Cell features ``(N, T, 90)`` (root channels in their units) of clips.

    Args:
        rotations: local quaternions ``(N, T, 22, 4)``; positions: global joint positions ``(N, T, 22, 3)``.
    """
    rotations = torch.as_tensor(np.asarray(rotations), dtype=torch.float32)
    positions = torch.as_tensor(np.asarray(positions), dtype=torch.float32)
    return to_motion_cell(rotations, positions[..., 0, :])


class PoseCodec(nn.Module):
    """Pose vectors <-> Motion Cell features <-> joint positions, for the skeletons of every body type.

    Buffers (so the codec is saved with a model): the root channels' :class:`Standardizer` and the rest
    ``offsets`` ``(n_bodies, J, 3)``. Call :meth:`fit` on training features before use.
    """

    offsets: Tensor

    def __init__(self, offsets: Tensor | np.ndarray, parents: Sequence[int]) -> None:
        super().__init__()
        offsets = torch.as_tensor(np.asarray(offsets), dtype=torch.float32)
        if offsets.dim() != 3 or offsets.shape[-1] != 3 or offsets.shape[1] != len(parents):
            raise ValueError(
                f"PoseCodec: offsets must be (n_bodies, J, 3) with J = len(parents) = {len(parents)}, "
                f"got {tuple(offsets.shape)}"
            )
        self.register_buffer("offsets", offsets.clone())
        self.parents = tuple(int(p) for p in parents)
        self.root = Standardizer(ROOT_DIM)

    @property
    def n_joints(self) -> int:
        return len(self.parents)

    @property
    def pose_dim(self) -> int:
        """Channels of a pose vector, ``(J - 1) * 4 + 6``."""
        return pose_dim(self.n_joints)

    def fit(self, features: Tensor) -> PoseCodec:
        """Learn the root channels' statistics from training features ``(..., 90)``; returns self."""
        self._check(features, "features", "fit")
        self.root.fit(features[..., -ROOT_DIM:])
        return self

    def copy(self) -> PoseCodec:
        """A new codec with the same skeletons and root statistics (models never share codec buffers)."""
        twin = PoseCodec(self.offsets, self.parents)
        twin.load_state_dict(self.state_dict())
        return twin

    def _check(self, x: Tensor, name: str, func: str) -> Tensor:
        return check_tensor(x, name, f"PoseCodec.{func}", trailing=(self.pose_dim,))

    def encode(self, features: Tensor) -> Tensor:
        """Pose vectors ``(..., 90)`` from Motion Cell features (root channels standardised)."""
        self._check(features, "features", "encode")
        return torch.cat([features[..., :-ROOT_DIM], self.root.transform(features[..., -ROOT_DIM:])], dim=-1)

    def decode(self, poses: Tensor) -> Tensor:
        """Motion Cell features ``(..., 90)`` from pose vectors (root channels back in their units)."""
        self._check(poses, "poses", "decode")
        return torch.cat([poses[..., :-ROOT_DIM], self.root.inverse(poses[..., -ROOT_DIM:])], dim=-1)

    def split(self, poses: Tensor) -> tuple[Tensor, Tensor]:
        """Joint quaternions ``(..., J - 1, 4)`` and standardised root channels ``(..., 6)`` of pose
        vectors."""
        self._check(poses, "poses", "split")
        return poses[..., :-ROOT_DIM].unflatten(-1, (self.n_joints - 1, 4)), poses[..., -ROOT_DIM:]

    def positions(self, poses: Tensor, body: Tensor, start: RootStart | None = None) -> Tensor:
        """Global joint positions ``(B, T, J, 3)`` of pose vectors ``(B, T, 90)`` (differentiable).

        Args:
            poses: pose vectors of ``B`` clips; quaternions need not be unit (they are normalised).
            body: body type of each clip ``(B,)``, which picks the skeleton.
            start: where each clip starts (default: at the origin facing +x).
        """
        self._check(poses, "poses", "positions")
        rotations, root_positions = from_motion_cell(self.decode(poses), start)
        return forward_kinematics(rotations, root_positions, self._offsets(poses, body), self.parents)[0]

    def local_positions(self, poses: Tensor, body: Tensor) -> Tensor:
        """Joint positions ``(B, T, J, 3)`` posed by the joint rotations alone: root at the origin,
        unrotated."""
        self._check(poses, "poses", "local_positions")
        quaternions, _ = self.split(poses)
        identity = torch.zeros_like(quaternions[..., :1, :])
        identity[..., 0] = 1.0
        rotations = torch.cat([identity, quaternions], dim=-2)
        origin = poses.new_zeros(rotations.shape[:-2] + (3,))
        return forward_kinematics(rotations, origin, self._offsets(poses, body), self.parents)[0]

    def _offsets(self, poses: Tensor, body: Tensor) -> Tensor:
        """Rest offsets ``(B, 1, J, 3)`` of each clip's body type, for poses ``(B, T, 90)``."""
        body = torch.as_tensor(body, dtype=torch.int64)
        if poses.dim() != 3 or body.shape != poses.shape[:1]:
            raise ValueError(
                f"PoseCodec: expected poses (B, T, {self.pose_dim}) and body (B,), got "
                f"{tuple(poses.shape)} and {tuple(body.shape)}"
            )
        if body.numel() and (int(body.min()) < 0 or int(body.max()) >= self.offsets.shape[0]):
            raise ValueError(
                f"PoseCodec: body types must lie in [0, {self.offsets.shape[0]}), got "
                f"{sorted(set(body.tolist()))}"
            )
        return self.offsets[body][:, None]


class WindowBatch(NamedTuple):
    """One training batch: pose vectors ``(B, L, 90)`` and the control attributes ``(B,)`` each."""

    poses: Tensor
    action: Tensor
    body: Tensor


class WindowBatches:
    """Random fixed-length windows of clips, a batch source for :func:`motionlab.train.train_or_load`.

    An epoch visits every clip once in a random order; each visit takes one window of ``length`` frames
    starting at a random frame. All randomness comes from the loop's generator.

    Args:
        poses: pose vectors of the clips ``(N, T, 90)``; action, body: ``(N,)`` integer attributes.
        length: frames per window (at most ``T``).
        shuffle: visit the clips in a random order (``False``: in their stored order; validation).
        drop_last: drop the final short batch (the default, so every step sees ``batch_size`` windows;
            ``False``: every clip gives a window, validation).
    """

    def __init__(
        self,
        poses: Tensor,
        action: Tensor | np.ndarray,
        body: Tensor | np.ndarray,
        length: int,
        shuffle: bool = True,
        drop_last: bool = True,
    ) -> None:
        check_tensor(poses, "poses", "WindowBatches", ndim=3)
        self.poses = poses
        self.action = torch.as_tensor(np.asarray(action), dtype=torch.int64)
        self.body = torch.as_tensor(np.asarray(body), dtype=torch.int64)
        if self.action.shape != poses.shape[:1] or self.body.shape != poses.shape[:1]:
            raise ValueError(
                f"WindowBatches: action and body must be ({poses.shape[0]},), got "
                f"{tuple(self.action.shape)} and {tuple(self.body.shape)}"
            )
        self.length = check_scalar(
            length, "length", "WindowBatches", kind=numbers.Integral, minimum=1, maximum=poses.shape[1]
        )
        for name, value in (("shuffle", shuffle), ("drop_last", drop_last)):
            if not isinstance(value, bool):
                raise TypeError(f"WindowBatches: {name} must be a bool, got {value!r}")
        self.shuffle, self.drop_last = shuffle, drop_last

    def __len__(self) -> int:
        return int(self.poses.shape[0])

    def __call__(self, epoch: int, generator: torch.Generator, batch_size: int) -> Iterator[WindowBatch]:
        n, n_frames = self.poses.shape[:2]
        if self.drop_last and n < batch_size:
            raise ValueError(f"WindowBatches: {n} clips cannot fill a batch of {batch_size}")
        order = torch.randperm(n, generator=generator) if self.shuffle else torch.arange(n)
        stop = n - n % batch_size if self.drop_last else n
        for begin in range(0, stop, batch_size):
            index = order[begin : begin + batch_size]
            start = torch.randint(0, n_frames - self.length + 1, (len(index),), generator=generator)
            yield WindowBatch(
                gather_windows(self.poses, index, start, self.length), self.action[index], self.body[index]
            )


def cut_windows(poses: Tensor, length: int) -> Tensor:
    """Consecutive non-overlapping windows ``(N * (T // length), length, D)`` of clips ``(N, T, D)``."""
    check_tensor(poses, "poses", "cut_windows", ndim=3)
    check_scalar(length, "length", "cut_windows", kind=numbers.Integral, minimum=1)
    n_windows = poses.shape[1] // length
    if n_windows < 1:
        raise ValueError(
            f"cut_windows: clips of {poses.shape[1]} frames are shorter than one window of {length}"
        )
    return poses[:, : n_windows * length].reshape(poses.shape[0] * n_windows, length, poses.shape[2])
