"""MoGlow's data: root-local xyz poses with root-velocity control, augmented, standardised, windowed.

Per frame (:func:`motionlab.data.representations.to_moglow`, 22 joints): the **pose** ``(64,)`` — root
height, then joints 1..21's xyz in the heading frame (origin on the floor below the pelvis, x forward,
z up) — and the **control** ``(3,)`` — forward and sideways root velocity (m/frame) and yaw rate
(rad/frame) from the previous frame. Frame 0 of a clip has no previous frame, so its control is zero.

Augmentation as in the paper: **mirroring** (left and right swapped, :mod:`motionlab.data.augment`) and
**time reversal** (the clip played backwards: walking backwards, with the control recomputed from the
reversed root path), applied before the features are computed, so that the control always matches the
pose. Both double the data. Standardisation is per channel, fitted on the (augmented) training frames.

The models train on windows of a few seconds (:func:`sequence_windows`); :func:`prepare_data` makes the
standardised training and test windows of a benchmark, and :func:`data_identity` says what defines them in
the checkpoint cache key.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any, NamedTuple

import numpy as np
import torch
from torch import Tensor

from motionlab.data.augment import mirror_positions, mirror_rotations
from motionlab.data.cmu_mocap import MIRROR, N_JOINTS, MocapClips
from motionlab.data.cmu_mocap import heading_yaw as cmu_heading_yaw
from motionlab.data.datasets import Standardizer
from motionlab.data.representations import CONTROL_FEATURES, representation, to_moglow, yaw_to_quat
from motionlab.data.store import MotionSet
from motionlab.data.synthetic import generator_fingerprint
from motionlab.evaluation.benchmark import Benchmark, benchmark_sizes
from motionlab.validation import Checked, check_scalar, check_tensor, flag, tuple_of

#: The actions of the locomotion experiments.
LOCOMOTION = ("walk", "jog")

_REPRESENTATION = representation("moglow")
POSE_DIM = _REPRESENTATION.channels["pose"].stop - _REPRESENTATION.channels["pose"].start
CONTROL_DIM = len(CONTROL_FEATURES)


class MoGlowFeatures(NamedTuple):
    """Clips (or windows) as MoGlow features: ``pose`` ``(N, T, 64)`` and ``control`` ``(N, T, 3)``."""

    pose: Tensor
    control: Tensor


@dataclass(frozen=True)
class MoGlowDataConfig(Checked):
    """Which clips and which augmentation (part of the cache key of every model trained on them).

    Attributes:
        actions: action names to keep (see ``MotionSet.action_names``).
        mirror: add the left/right mirrored clips.
        reverse_time: add the time-reversed clips (of the mirrored ones too).
    """

    actions: tuple[str, ...] = tuple_of(LOCOMOTION, kind=str, nonempty=True)
    mirror: bool = flag(True)
    reverse_time: bool = flag(True)


def select_actions(data: MotionSet, actions: Sequence[str]) -> MotionSet:
    """The clips of ``data`` whose action is one of ``actions`` (names), in their stored order."""
    names = [str(name) for name in data.action_names]
    unknown = [a for a in actions if a not in names]
    if unknown:
        raise ValueError(f"select_actions: unknown actions {unknown}; the data has {names}")
    wanted = np.array([names.index(a) for a in actions])
    return data.subset(np.isin(data.action, wanted))


def augment_clips(
    positions: Tensor, rotations: Tensor, mirror: bool, reverse_time: bool
) -> tuple[Tensor, Tensor]:
    """Stack the augmented copies of clips ``(N, T, J, 3)`` / ``(N, T, J, 4)`` along the first axis.

    Order: the originals, then (with ``mirror``) the mirrored clips; then (with ``reverse_time``) all of
    those again played backwards. Returns ``(positions, rotations)`` with 1, 2 or 4 times ``N`` clips.
    """
    check_tensor(positions, "positions", "augment_clips", trailing=(None, 3), ndim=4, finite=False)
    check_tensor(rotations, "rotations", "augment_clips", trailing=(None, 4), ndim=4, finite=False)
    if positions.shape[:3] != rotations.shape[:3]:
        raise ValueError(
            f"augment_clips: positions (N, T, J, 3) and rotations (N, T, J, 4) must share (N, T, J), "
            f"got {tuple(positions.shape)} and {tuple(rotations.shape)}"
        )
    if mirror:
        positions = torch.cat([positions, mirror_positions(positions)])
        rotations = torch.cat([rotations, mirror_rotations(rotations)])
    if reverse_time:
        positions = torch.cat([positions, positions.flip(1)])
        rotations = torch.cat([rotations, rotations.flip(1)])
    return positions, rotations


def moglow_features(positions: Tensor, rotations: Tensor) -> MoGlowFeatures:
    """Pose ``(..., T, 64)`` and control ``(..., T, 3)`` of clips ``(..., T, 22, 3)`` / ``(..., T, 22,
    4)``."""
    features = to_moglow(positions, rotations[..., 0, :])
    return MoGlowFeatures(
        _REPRESENTATION.select(features, "pose"), _REPRESENTATION.select(features, "control")
    )


def clip_features(data: MotionSet, cfg: MoGlowDataConfig, augment: bool) -> MoGlowFeatures:
    """Raw features of the clips of ``cfg.actions`` in ``data`` (augmented as ``cfg`` says when
    ``augment``)."""
    clips = select_actions(data, cfg.actions)
    positions, rotations = torch.from_numpy(clips.positions), torch.from_numpy(clips.rotations)
    if augment:
        positions, rotations = augment_clips(positions, rotations, cfg.mirror, cfg.reverse_time)
    return moglow_features(positions, rotations)


class Scalers(NamedTuple):
    """Per-channel standardisers of the pose ``(64,)`` and of the control ``(3,)``."""

    pose: Standardizer
    control: Standardizer


def fit_scalers(train: MoGlowFeatures) -> Scalers:
    """Standardisers fitted on every frame of the training features."""
    return Scalers(
        Standardizer(train.pose.shape[-1]).fit(train.pose),
        Standardizer(train.control.shape[-1]).fit(train.control),
    )


def standardize(features: MoGlowFeatures, scalers: Scalers) -> MoGlowFeatures:
    """``features`` in standard units (per channel zero mean, unit variance on the training frames)."""
    return MoGlowFeatures(scalers.pose.transform(features.pose), scalers.control.transform(features.control))


def sequence_windows(features: MoGlowFeatures, length: int, stride: int, first: int = 1) -> MoGlowFeatures:
    """Windows of ``length`` frames every ``stride`` frames from each clip, starting at frame ``first``.

    ``first = 1`` skips frame 0, whose control is undefined (zero). Returns ``(N * W, length, ·)``.
    """
    n_frames = features.pose.shape[1]
    check_scalar(length, "length", "sequence_windows", kind=numbers.Integral, minimum=1)
    check_scalar(stride, "stride", "sequence_windows", kind=numbers.Integral, minimum=1)
    check_scalar(first, "first", "sequence_windows", kind=numbers.Integral, minimum=0)
    if first + length > n_frames:
        raise ValueError(
            f"sequence_windows: first + length must be at most the clips' {n_frames} frames, "
            f"got first={first}, length={length}"
        )
    starts = range(first, n_frames - length + 1, stride)
    return MoGlowFeatures(*(torch.cat([x[:, s : s + length] for s in starts]) for x in features))


class PreparedData(NamedTuple):
    """Standardised training windows (augmented), held-out test windows, the scalers, and validation windows.

    ``train``/``test``/``val``: windows ``(M, length, ·)`` (the test and validation windows are not
    augmented); ``val`` is ``None`` where there is no validation split (real motion capture).
    """

    train: MoGlowFeatures
    test: MoGlowFeatures
    scalers: Scalers
    val: MoGlowFeatures | None = None


def prepare_data(benchmark: Benchmark, cfg: MoGlowDataConfig, length: int, stride: int) -> PreparedData:
    """Windows of ``length`` frames (every ``stride``) from the benchmark's clips of ``cfg.actions``.

    The scalers are fitted on the augmented training clips; frame 0 of every clip (no control) is skipped.
    The validation windows (the benchmark's val split) give the runs their held-out curve; nothing is tuned
    on them.
    """
    train = clip_features(benchmark.train, cfg, augment=True)
    scalers = fit_scalers(train)

    def held_out(clips: MotionSet) -> MoGlowFeatures:
        return sequence_windows(
            standardize(clip_features(clips, cfg, augment=False), scalers), length, stride
        )

    return PreparedData(
        sequence_windows(standardize(train, scalers), length, stride),
        held_out(benchmark.test),
        scalers,
        held_out(benchmark.val),
    )


def data_identity(cfg: MoGlowDataConfig, length: int, stride: int) -> dict[str, Any]:
    """What defines the training data, for the checkpoint cache key (with the benchmark sizes and
    generator)."""
    return {
        "data": asdict(cfg),
        "length": length,
        "stride": stride,
        "sizes": list(benchmark_sizes()),
        "generator": generator_fingerprint(),
    }


# ----------------------------------------------------------------------------------------------------
# real motion (chapter 10): CMU clips of positions only


def real_features(positions: Tensor) -> MoGlowFeatures:
    """Pose ``(..., T, 58)`` and control ``(..., T, 3)`` of real clips ``(..., T, 20, 3)`` (z up, metres).

    The data has no joint rotations, so the heading comes from the hips and shoulders
    (:func:`motionlab.data.cmu_mocap.heading_yaw`) instead of the root's orientation.
    """
    check_tensor(positions, "positions", "real_features", trailing=(N_JOINTS, 3), min_leading=1)
    yaw = torch.as_tensor(cmu_heading_yaw(positions.numpy()), dtype=positions.dtype)
    features = to_moglow(positions, yaw_to_quat(yaw))
    return MoGlowFeatures(features[..., :-CONTROL_DIM], features[..., -CONTROL_DIM:])


def real_clip_windows(
    clips: MocapClips, cfg: MoGlowDataConfig, length: int, stride: int, augment: bool
) -> MoGlowFeatures:
    """Raw windows of ``length`` frames every ``stride`` frames of the clips of ``cfg.actions`` (names of
    ``clips.action_names``), augmented as ``cfg`` says when ``augment`` (mirrored with
    :data:`~motionlab.data.cmu_mocap.MIRROR`, played backwards). Clips shorter than ``length + 1`` frames
    are left out; frame 0 of every clip (no control) is skipped."""
    names = list(clips.action_names)
    unknown = [a for a in cfg.actions if a not in names]
    if unknown:
        raise ValueError(f"real_clip_windows: unknown actions {unknown}; the clips have {names}")
    wanted = np.isin(clips.action, [names.index(a) for a in cfg.actions]) & (clips.lengths > length)
    windows = []
    for index in np.flatnonzero(wanted):
        positions = torch.as_tensor(clips.positions[index], dtype=torch.float32)[None]
        if augment and cfg.mirror:
            positions = torch.cat([positions, mirror_positions(positions, torch.tensor(MIRROR))])
        if augment and cfg.reverse_time:
            positions = torch.cat([positions, positions.flip(1)])
        windows.append(sequence_windows(real_features(positions), length, stride))
    if not windows:
        raise ValueError(f"real_clip_windows: no clip of {cfg.actions} has more than {length} frames")
    return MoGlowFeatures(*(torch.cat(parts) for parts in zip(*windows)))


def prepare_real(
    train: MocapClips,
    test: MocapClips,
    cfg: MoGlowDataConfig,
    length: int,
    stride: int,
    val: MocapClips | None = None,
) -> PreparedData:
    """Standardised windows of real clips: the training windows augmented, the test windows (and the
    validation windows of ``val``, when given) not, the scalers fitted on the training windows' frames."""
    raw = real_clip_windows(train, cfg, length, stride, augment=True)
    scalers = fit_scalers(raw)

    def held_out(clips: MocapClips) -> MoGlowFeatures:
        return standardize(real_clip_windows(clips, cfg, length, stride, augment=False), scalers)

    return PreparedData(
        standardize(raw, scalers), held_out(test), scalers, None if val is None else held_out(val)
    )
