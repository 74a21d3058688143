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

Training batches are class-balanced (:class:`BalancedBatches`): every batch holds the same number of clips
of every action, which the contrastive term's pairs need
(:func:`~motionlab.models.odmo.losses.balanced_pairs`); so do the validation batches, each class's clips in
their stored order.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from motionlab.data.augment import rotate_yaw
from motionlab.data.cmu_mocap import MocapClips, face_x, random_windows
from motionlab.data.representations import RootStart, from_odmo, heading_yaw, to_odmo
from motionlab.data.store import MotionSet
from motionlab.validation import check_scalar, check_tensor


@dataclass(frozen=True, eq=False)
class ODMOData:
    """Clips prepared for ODMO.

    Attributes:
        features: ``(N, T, 3 (J - 1) + 3)`` float32; local movement profile then root trajectory (metres).
        action: ``(N,)`` int64 action class; mode: ``(N,)`` int64 true style mode; body: ``(N,)`` int64 body
            type (mode and body are for evaluation only: the model never sees them).
        frame_stride: frames of the 30 fps data per model frame.
        floor_clearance: mean height (metres) of the lowest joint in the first frame of the training clips.
        val: validation clips prepared as these (the same frame stride and floor clearance), on which the
            chapter's runs validate; ``None``: none (real motion capture, or clips that are validation clips
            themselves).
    """

    features: Tensor
    action: Tensor
    mode: Tensor
    body: Tensor
    frame_stride: int
    floor_clearance: float
    val: ODMOData | None = None

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
    check_tensor(positions, "positions", "face_forward", trailing=(None, 3), ndim=4)
    check_tensor(rotations, "rotations", "face_forward", trailing=(None, 4), ndim=4)
    yaw = heading_yaw(rotations[:, 0, 0, :])
    return rotate_yaw(positions, rotations, -yaw)[0]


def lowest_first_joint(features: Tensor) -> Tensor:
    """Height of each clip's lowest non-root joint relative to the root in its first frame ``(N,)``."""
    return features[:, 0, :-3].unflatten(-1, (-1, 3))[..., 2].min(dim=-1).values


def prepare(
    data: MotionSet, frame_stride: int = 3, floor_clearance: float | None = None, val: MotionSet | None = None
) -> ODMOData:
    """ODMO features of a motion set (see the module notes); ``floor_clearance`` defaults to this set's
    own. ``val``: validation clips, prepared alike (the same frame stride, this set's floor clearance) as the
    result's ``val``."""
    check_scalar(frame_stride, "frame_stride", "prepare", kind=numbers.Integral, minimum=1)
    if floor_clearance is not None:
        check_scalar(floor_clearance, "floor_clearance", "prepare")
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
        None if val is None else prepare(val, frame_stride, float(floor_clearance)),
    )


def upsample_frames(x: Tensor, factor: int) -> Tensor:
    """Linear interpolation along the frame axis ``(N, T, ...) -> (N, T · factor, ...)``.

    Model frame ``t`` becomes data frame ``t · factor``; the frames between are interpolated, and the
    ``factor - 1`` frames after the last one continue its last velocity.
    """
    check_tensor(x, "x", "upsample_frames", min_leading=2, finite=False)
    check_scalar(factor, "factor", "upsample_frames", kind=numbers.Integral, minimum=1)
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
    check_tensor(features, "features", "to_positions", ndim=3)
    check_scalar(frame_stride, "frame_stride", "to_positions", kind=numbers.Integral, minimum=1)
    check_scalar(floor_clearance, "floor_clearance", "to_positions")
    if features.shape[-1] % 3 or features.shape[-1] < 6:
        raise ValueError(
            f"to_positions: features must be (N, T, 3 (J - 1) + 3) with J >= 2 joints, got "
            f"{tuple(features.shape)}"
        )
    height = floor_clearance - lowest_first_joint(features)
    start = torch.zeros(features.shape[0], 3, dtype=features.dtype)
    start[:, 2] = height
    positions = from_odmo(features, RootStart(start, torch.zeros(features.shape[0], dtype=features.dtype)))
    return upsample_frames(positions, frame_stride)


class BalancedBatches:
    """A batch source of class-balanced batches ``(features (B, T, F), labels (B,))`` for the training loop.

    Every batch has ``batch_size / n_classes`` clips of each class. An epoch shuffles each class's clips and
    deals them out; it ends when the smallest class runs out (so every clip is used once at most).

    Args:
        features: clips ``(N, T, F)``; labels: their classes ``(N,)``, every one of the ``n_classes`` with
            at least 2 clips.
        shuffle: deal each class's clips in a random order (``False``: in their stored order; validation).
        drop_last: end the epoch with the last full batch (the default, so every step sees ``batch_size``
            clips; ``False``: then one smaller balanced batch of the smallest class's remaining clips, and as
            many of every other class, when at least 2 remain for a same-class pair; validation: with
            equally many clips of every class, every clip once).
    """

    def __init__(
        self, features: Tensor, labels: Tensor, n_classes: int, shuffle: bool = True, drop_last: bool = True
    ) -> None:
        where = "BalancedBatches"
        check_tensor(features, "features", where, min_leading=1)
        check_tensor(labels, "labels", where, ndim=1, floating=False)
        if labels.is_floating_point():
            raise TypeError(f"{where}: labels must be an integer tensor, got dtype {labels.dtype}")
        check_scalar(n_classes, "n_classes", where, kind=numbers.Integral, minimum=2)
        if labels.shape[0] != features.shape[0]:
            raise ValueError(f"{where}: labels must be ({features.shape[0]},), got {tuple(labels.shape)}")
        counts = torch.bincount(labels, minlength=n_classes)
        if counts.numel() != n_classes or bool((counts < 2).any()):
            raise ValueError(
                f"{where}: every one of the {n_classes} classes needs at least 2 clips, "
                f"got counts {counts.tolist()}"
            )
        for name, value in (("shuffle", shuffle), ("drop_last", drop_last)):
            if not isinstance(value, bool):
                raise TypeError(f"{where}: {name} must be a bool, got {value!r}")
        self.shuffle, self.drop_last = shuffle, drop_last
        self.features = features
        self.labels = labels
        self.n_classes = n_classes
        self.members = [torch.nonzero(labels == c).flatten() for c in range(n_classes)]

    def per_class(self, batch_size: int) -> int:
        """Clips of each class in a batch of ``batch_size`` (which must be a multiple of the class count)."""
        check_scalar(batch_size, "batch_size", "BalancedBatches", kind=numbers.Integral, minimum=1)
        if batch_size % self.n_classes or batch_size < 2 * self.n_classes:
            raise ValueError(
                f"BalancedBatches: batch_size must be a multiple of {self.n_classes} classes with at "
                f"least 2 clips each, got {batch_size}"
            )
        return batch_size // self.n_classes

    def __call__(
        self, epoch: int, generator: torch.Generator, batch_size: int
    ) -> Iterator[tuple[Tensor, Tensor]]:
        k = self.per_class(batch_size)
        members = (
            [m[torch.randperm(m.numel(), generator=generator)] for m in self.members]
            if self.shuffle
            else self.members
        )
        smallest = min(m.numel() for m in members)
        per_class = [k] * (smallest // k)  # clips of each class in each batch
        if not self.drop_last and smallest % k >= 2:
            per_class.append(smallest % k)
        if not per_class:
            raise ValueError(f"BalancedBatches: the smallest class has fewer than {k} clips for one batch")
        start = 0
        for size in per_class:
            index = torch.cat([m[start : start + size] for m in members])
            start += size
            yield self.features[index], self.labels[index]


def prepare_real(
    clips: MocapClips, window: int = 100, frame_stride: int = 2, draws: int = 4, seed: int = 0
) -> ODMOData:
    """ODMO features of real clips (:class:`~motionlab.data.cmu_mocap.MocapClips`, 20 joints): ``draws``
    random ``window``-frame windows of every clip (ODMO's protocol: shorter clips padded with their last
    frame), each turned to face +x at its first frame, every ``frame_stride``-th frame kept.

    ODMO draws a fresh window of every clip each epoch; ``draws`` fixed draws per clip stand in for that
    (the batches then cycle through them). The data has no style labels: ``mode`` and ``body`` are zeros.
    The floor clearance is measured on the clips as given (level their floors first,
    :func:`~motionlab.data.cmu_mocap.level_floor`).
    """
    where = "prepare_real"
    for name, value in (("window", window), ("frame_stride", frame_stride), ("draws", draws)):
        check_scalar(value, name, where, kind=numbers.Integral, minimum=1)
    if window < 2 * frame_stride:
        raise ValueError(f"{where}: windows of {window} frames are too short for frame_stride {frame_stride}")
    windows = [random_windows(clips, window, np.random.default_rng([seed, d])) for d in range(draws)]
    first_pose = np.stack([p[w.start[i]] for w in windows for i, p in enumerate(clips.positions)])
    positions = torch.as_tensor(np.concatenate([face_x(w.positions) for w in windows]), dtype=torch.float32)
    features = to_odmo(positions)[:, ::frame_stride].contiguous()
    action = torch.as_tensor(np.concatenate([w.action for w in windows]), dtype=torch.int64)
    zeros = torch.zeros_like(action)
    return ODMOData(
        features.float(), action, zeros, zeros, frame_stride, float(first_pose[:, 1:, 2].min(axis=1).mean())
    )
