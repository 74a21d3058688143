"""Torch data sets of fixed-length windows over clips, seeded clip splits, and a per-channel standardiser.

The pieces, in the order a chapter uses them (or all at once through :func:`build_splits`):

1. :func:`split_clips` divides the *clips* (not the windows, so overlapping windows of one clip never
   land in two splits) into train / val / test, stratified by motion mode and seeded.
2. :func:`motion_windows` cuts windows of ``length`` frames every ``stride`` frames from the chosen
   clips, encodes each window as a clip of its own in a
   :class:`~motionlab.data.representations.Representation` (so ODMO's and TrajeVAE's "first frame at the
   origin" is the window's first frame) and returns a :class:`WindowDataset`.
3. :class:`Standardizer` learns per-channel mean and std on the train windows only.

Clips come in the generator's format (:class:`MotionClips`): ``positions (N, T, J, 3)``,
``rotations (N, T, J, 4)`` and integer labels ``action``, ``mode``, ``body`` ``(N,)``; NumPy arrays or
torch tensors.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Sequence
from typing import NamedTuple, Protocol

import numpy as np
import torch
from torch import Tensor, nn
from torch.utils.data import Dataset

from motionlab.data.representations import Representation, RootStart, root_start
from motionlab.validation import check_scalar, check_tensor

LABELS = ("action", "mode", "body")
"""The per-clip integer labels every item carries."""

#: Windows encoded at a time: bounds the memory of the raw windows and the encoders' intermediates.
ENCODE_CHUNK = 2048

Augment = Callable[[Tensor, Tensor], tuple[Tensor, Tensor]]
"""``augment(positions (W, L, J, 3), rotations (W, L, J, 4)) -> (positions, rotations)``, for example
``functools.partial(random_yaw, generator=g)``; applied once to the raw windows before encoding, in
chunks of :data:`ENCODE_CHUNK` windows."""


class MotionClips(Protocol):
    """What the data sets read: the generator's ``MotionSet`` or anything with these attributes."""

    positions: np.ndarray | Tensor  # (N, T, J, 3) global joint positions, metres
    rotations: np.ndarray | Tensor  # (N, T, J, 4) local quaternions, w first
    action: np.ndarray | Tensor  # (N,) int
    mode: np.ndarray | Tensor  # (N,) int
    body: np.ndarray | Tensor  # (N,) int


def _labels(values: np.ndarray | Tensor, name: str, func: str, length: int | None = None) -> Tensor:
    """``values`` as a 1-D int64 tensor (of ``length`` items if given)."""
    labels = torch.as_tensor(values)
    if labels.is_floating_point() or labels.is_complex() or labels.dtype == torch.bool:
        raise TypeError(f"{func}: {name} must be a 1-D integer array (N,), got dtype {labels.dtype}")
    if labels.dim() != 1:
        raise ValueError(f"{func}: {name} must be a 1-D integer array (N,), got shape {tuple(labels.shape)}")
    if length is not None and labels.shape[0] != length:
        raise ValueError(f"{func}: {name} has {labels.shape[0]} entries but there are {length} items")
    return labels.to(torch.int64)


# ----------------------------------------------------------------------------------------------------
# windows


def window_starts(n_frames: int, length: int, stride: int) -> Tensor:
    """First frames ``(n_windows,)`` of the windows ``[s, s + length)`` taken every ``stride`` frames.

    There are ``(n_frames - length) // stride + 1`` of them; frames after the last whole window are
    left out. Raises ``ValueError`` when a window is longer than the clip.
    """
    func = "window_starts"
    arguments = {"n_frames": n_frames, "length": length, "stride": stride}
    n_frames, length, stride = (
        int(check_scalar(value, name, func, kind=numbers.Integral, minimum=1))
        for name, value in arguments.items()
    )
    if length > n_frames:
        raise ValueError(f"{func}: window length {length} is longer than the clips ({n_frames} frames)")
    return torch.arange(0, n_frames - length + 1, stride)


def gather_windows(x: Tensor, clip: Tensor, start: Tensor, length: int) -> Tensor:
    """Windows ``(W, length, ...)`` of ``x`` ``(N, T, ...)``.

    Window ``i`` is ``x[clip[i], start[i]:start[i] + length]``; ``clip`` and ``start`` are ``(W,)`` int64.
    """
    frames = start[:, None] + torch.arange(length)
    return x[clip[:, None], frames]


class WindowDataset(Dataset):
    """Windows of encoded motion with their labels; item ``i`` is a dict of tensors.

    Keys: ``"features"`` ``(L, D)`` float (standardised if the data set was built with a standardiser);
    ``"action"``, ``"mode"``, ``"body"`` (int64 scalars); ``"clip"`` (the window's clip index in the
    source clips) and ``"start"`` (its first frame in that clip); ``"root_position"`` ``(3,)`` and
    ``"root_yaw"`` ``()``, the root's position and heading at the window's first frame, so that
    ``representation.decode(features, RootStart(root_position, root_yaw), ...)`` puts a window (or a
    reconstruction of it) back where it was in the world.

    Attributes:
        features: ``(W, L, D)``; root_start: :class:`RootStart` of ``(W, 3)`` and ``(W,)``;
        clip, start, action, mode, body: ``(W,)`` int64; representation: what the features are in.
    """

    def __init__(
        self,
        features: Tensor,
        representation: Representation,
        *,
        root_start: RootStart,
        clip: Tensor,
        start: Tensor,
        action: Tensor,
        mode: Tensor,
        body: Tensor,
    ) -> None:
        func = "WindowDataset"
        check_tensor(features, "features", func, trailing=(None, representation.dim), min_leading=1)
        if features.dim() != 3:
            raise ValueError(
                f"{func}: features must have shape (W, L, {representation.dim}), got {tuple(features.shape)}"
            )
        n_windows = features.shape[0]
        position = check_tensor(root_start.position, "root_start.position", func, trailing=(3,))
        yaw = check_tensor(root_start.yaw, "root_start.yaw", func)
        if position.shape != (n_windows, 3) or yaw.shape != (n_windows,):
            raise ValueError(
                f"{func}: root_start must hold ({n_windows}, 3) positions and ({n_windows},) yaws, got "
                f"{tuple(position.shape)} and {tuple(yaw.shape)}"
            )
        self.features = features
        self.representation = representation
        self.root_start = RootStart(position, yaw)
        self.clip = _labels(clip, "clip", func, n_windows)
        self.start = _labels(start, "start", func, n_windows)
        self.action = _labels(action, "action", func, n_windows)
        self.mode = _labels(mode, "mode", func, n_windows)
        self.body = _labels(body, "body", func, n_windows)

    def __len__(self) -> int:
        return self.features.shape[0]

    def __getitem__(self, index: int) -> dict[str, Tensor]:
        return {
            "features": self.features[index],
            "action": self.action[index],
            "mode": self.mode[index],
            "body": self.body[index],
            "clip": self.clip[index],
            "start": self.start[index],
            "root_position": self.root_start.position[index],
            "root_yaw": self.root_start.yaw[index],
        }

    def with_features(self, features: Tensor) -> WindowDataset:
        """The same windows and labels with other ``features`` ``(W, L, D)`` (for example standardised
        ones)."""
        return WindowDataset(
            features,
            self.representation,
            root_start=self.root_start,
            clip=self.clip,
            start=self.start,
            action=self.action,
            mode=self.mode,
            body=self.body,
        )


def motion_windows(
    clips: MotionClips,
    representation: Representation,
    length: int,
    stride: int,
    clip_indices: Sequence[int] | Tensor | None = None,
    standardizer: Standardizer | None = None,
    augment: Augment | None = None,
) -> WindowDataset:
    """A :class:`WindowDataset` of the windows of ``clip_indices`` (default: every clip) in
    ``representation``.

    Windows are ordered clip by clip (in the order of ``clip_indices``), then by start frame. Each window is
    encoded as a clip of its own. ``augment`` (optional) changes the raw windows before encoding;
    ``standardizer`` (optional, fitted) standardises the features.
    """
    func = "motion_windows"
    positions = check_tensor(torch.as_tensor(clips.positions), "clips.positions", func, trailing=(None, 3))
    rotations = check_tensor(torch.as_tensor(clips.rotations), "clips.rotations", func, trailing=(None, 4))
    if positions.dim() != 4 or positions.shape[:-1] != rotations.shape[:-1]:
        raise ValueError(
            f"{func}: clips need positions (N, T, J, 3) and rotations (N, T, J, 4) with the same "
            f"N, T, J; got {tuple(positions.shape)} and {tuple(rotations.shape)}"
        )
    n_clips, n_frames, n_joints = positions.shape[:3]
    if n_joints != representation.n_joints:
        raise ValueError(
            f"{func}: clips have {n_joints} joints but the {representation.name} representation "
            f"expects {representation.n_joints}"
        )
    labels = {name: _labels(getattr(clips, name), f"clips.{name}", func, n_clips) for name in LABELS}
    chosen = torch.arange(n_clips) if clip_indices is None else torch.as_tensor(clip_indices)
    if chosen.numel() == 0:
        raise ValueError(f"{func}: clip_indices is empty; there are no clips to cut windows from")
    chosen = _labels(chosen, "clip_indices", func)
    if int(chosen.min()) < 0 or int(chosen.max()) >= n_clips:
        raise ValueError(
            f"{func}: clip_indices must lie in [0, {n_clips}), got {int(chosen.min())}..{int(chosen.max())}"
        )
    starts = window_starts(n_frames, length, stride)
    clip = chosen.repeat_interleave(starts.numel())
    start = starts.repeat(chosen.numel())
    encoded = positions.new_empty((clip.numel(), length, representation.dim))
    world = RootStart(positions.new_empty((clip.numel(), 3)), positions.new_empty(clip.numel()))
    for chunk in torch.split(torch.arange(clip.numel()), ENCODE_CHUNK):
        window_positions = gather_windows(positions, clip[chunk], start[chunk], length)
        window_rotations = gather_windows(rotations, clip[chunk], start[chunk], length)
        if augment is not None:
            window_positions, window_rotations = augment(window_positions, window_rotations)
        encoded[chunk] = representation.encode(window_positions, window_rotations)
        world.position[chunk], world.yaw[chunk] = root_start(window_positions, window_rotations)
    if standardizer is not None:
        encoded = standardizer.transform(encoded)
    return WindowDataset(
        encoded,
        representation,
        root_start=world,
        clip=clip,
        start=start,
        **{name: labels[name][clip] for name in LABELS},
    )


# ----------------------------------------------------------------------------------------------------
# splits


class ClipSplit(NamedTuple):
    """Sorted clip indices ``(n,)`` int64 of each split; the three are disjoint and cover every clip."""

    train: Tensor
    val: Tensor
    test: Tensor


def split_clips(
    mode: np.ndarray | Tensor, fractions: tuple[float, float, float] = (0.8, 0.1, 0.1), seed: int = 0
) -> ClipSplit:
    """Split clips into train / val / test, stratified by ``mode`` ``(N,)`` and seeded.

    With ``torch.Generator().manual_seed(seed)`` the modes are put in a random order and the clips of
    each mode shuffled; the clips are then dealt out in that order, mode after mode, each to the split
    furthest behind its share (largest ``f_s * dealt - count_s``). So every split holds within one clip of
    ``f_s * N`` clips, each mode's share of a split is within two clips of ``f_s * n_mode`` (even when
    ``f_s * n_mode < 1``), and which modes get the odd clips changes with the seed.
    Raises ``ValueError`` when a split would be empty.
    """
    func = "split_clips"
    mode = _labels(mode, "mode", func)
    if (
        len(fractions) != 3
        or any(not math.isfinite(f) or f <= 0 for f in fractions)
        or not math.isclose(sum(fractions), 1.0, abs_tol=1e-9)
    ):
        raise ValueError(
            f"{func}: fractions must be three positive numbers (train, val, test) summing to 1, "
            f"got {tuple(fractions)}"
        )
    check_scalar(seed, "seed", func, kind=numbers.Integral, minimum=0)
    generator = torch.Generator().manual_seed(int(seed))
    modes = torch.unique(mode)
    order = []
    for value in modes[torch.randperm(modes.numel(), generator=generator)]:
        members = torch.nonzero(mode == value).flatten()
        order.append(members[torch.randperm(members.numel(), generator=generator)])
    share = torch.tensor(fractions, dtype=torch.float64)
    counts = torch.zeros(3, dtype=torch.float64)
    assigned = torch.empty(mode.numel(), dtype=torch.int64)
    for dealt, clip in enumerate(torch.cat(order).tolist(), start=1):
        behind = int(torch.argmax(share * dealt - counts))
        counts[behind] += 1
        assigned[clip] = behind
    split = {name: torch.nonzero(assigned == s).flatten() for s, name in enumerate(ClipSplit._fields)}
    for name, indices in split.items():
        if indices.numel() == 0:
            raise ValueError(
                f"{func}: the {name} split is empty ({mode.numel()} clips with fractions "
                f"{tuple(fractions)}); use more clips or a larger {name} fraction"
            )
    return ClipSplit(**split)


# ----------------------------------------------------------------------------------------------------
# standardisation


class Standardizer(nn.Module):
    """Per-channel standardisation ``z = (x - mean) / std`` with a floor on ``std``.

    Fit on the train split only (:meth:`fit`). ``mean``, ``std`` ``(D,)`` and ``count`` (frames seen) are
    buffers, so the fitted standardiser travels in a model's ``state_dict`` and checkpoint. Build an
    empty one with the right ``n_features`` and ``load_state_dict`` to restore it.
    """

    mean: Tensor
    std: Tensor
    count: Tensor

    def __init__(self, n_features: int, min_std: float = 1e-4) -> None:
        super().__init__()
        check_scalar(n_features, "n_features", "Standardizer", kind=numbers.Integral, minimum=1)
        check_scalar(min_std, "min_std", "Standardizer", minimum=0, include_minimum=False)
        self.n_features = int(n_features)
        self.min_std = float(min_std)
        self.register_buffer("mean", torch.zeros(self.n_features))
        self.register_buffer("std", torch.ones(self.n_features))
        self.register_buffer("count", torch.zeros((), dtype=torch.int64))

    def extra_repr(self) -> str:
        return f"n_features={self.n_features}, min_std={self.min_std}, fitted={self.fitted}"

    @property
    def fitted(self) -> bool:
        """Whether :meth:`fit` (or a loaded state) has set the statistics."""
        return int(self.count) > 0

    def fit(self, features: Tensor) -> Standardizer:
        """Set mean and std ``(D,)`` from ``features`` ``(..., D)`` (all leading entries pooled); returns
        self.

        The std is the population std (divide by the count), floored at ``min_std``; statistics are
        computed in float64.
        """
        check_tensor(features, "features", "Standardizer.fit", trailing=(self.n_features,))
        flat = features.reshape(-1, self.n_features).double()
        if flat.shape[0] < 2:
            raise ValueError(f"Standardizer.fit: needs at least 2 rows of features, got {flat.shape[0]}")
        self.mean.copy_(flat.mean(dim=0))
        self.std.copy_(flat.std(dim=0, correction=0).clamp(min=self.min_std))
        self.count.fill_(flat.shape[0])
        return self

    def _statistics(self, func: str) -> tuple[Tensor, Tensor]:
        if not self.fitted:
            raise RuntimeError(
                f"Standardizer.{func}: not fitted; call fit(train_features) or load a state_dict first"
            )
        return self.mean, self.std

    def transform(self, features: Tensor) -> Tensor:
        """Standardised ``(features - mean) / std``, ``(..., D)``."""
        mean, std = self._statistics("transform")
        check_tensor(features, "features", "Standardizer.transform", trailing=(self.n_features,))
        return (features - mean.to(features)) / std.to(features)

    def inverse(self, standardized: Tensor) -> Tensor:
        """Undo :meth:`transform`: ``standardized * std + mean``, ``(..., D)``."""
        mean, std = self._statistics("inverse")
        check_tensor(standardized, "standardized", "Standardizer.inverse", trailing=(self.n_features,))
        return standardized * std.to(standardized) + mean.to(standardized)


class SplitData(NamedTuple):
    """Everything :func:`build_splits` makes: three standardised window data sets, the standardiser, the
    split."""

    train: WindowDataset
    val: WindowDataset
    test: WindowDataset
    standardizer: Standardizer
    split: ClipSplit


def build_splits(
    clips: MotionClips,
    representation: Representation,
    length: int,
    stride: int,
    seed: int = 0,
    fractions: tuple[float, float, float] = (0.8, 0.1, 0.1),
    min_std: float = 1e-4,
    augment: Augment | None = None,
) -> SplitData:
    """Split ``clips`` by mode (:func:`split_clips`), cut and encode windows, standardise with train
    statistics.

    ``augment`` applies to the train windows only. All three data sets hold standardised features;
    ``standardizer.inverse`` gives back the representation's units.
    """
    split = split_clips(clips.mode, fractions, seed)
    raw = motion_windows(clips, representation, length, stride, split.train, augment=augment)
    standardizer = Standardizer(representation.dim, min_std).fit(raw.features)
    train = raw.with_features(standardizer.transform(raw.features))
    val, test = (
        motion_windows(clips, representation, length, stride, indices, standardizer)
        for indices in (split.val, split.test)
    )
    return SplitData(train, val, test, standardizer, split)
