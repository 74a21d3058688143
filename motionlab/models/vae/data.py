"""What the VAE chapter trains on, and the way back to joint positions.

* Single poses: the pose channels of the MoGlow representation (root height, then the 21 other joints' xyz
  in the heading frame: 64 numbers), taken every few frames of every clip. :func:`pose_to_positions`
  puts a pose back on the floor at the origin, facing +x.
* Short clips: windows of the MoGlow representation (pose plus root control, 67 numbers a frame),
  standardised per channel. A :class:`ClipCodec` turns a model's standardised output back into global
  positions ``(..., L, 22, 3)``, which is what the evaluation classifiers and the stick figures read.

:class:`BenchmarkPoses` and :class:`BenchmarkClips` name the chapter's two data sets on the course benchmark
(small and picklable, so a training run in a worker process builds its data itself); ``load()`` builds them
once per process, and so does ``validation_inputs()`` the benchmark's validation split, prepared like the
training data, on which the runs draw their held-out curve.
"""

from __future__ import annotations

import functools
import numbers
from dataclasses import dataclass
from typing import NamedTuple

import torch
from torch import Tensor

from motionlab import config
from motionlab.data.datasets import MotionClips, Standardizer, WindowDataset, motion_windows
from motionlab.data.representations import CONTROL_FEATURES, from_moglow, representation
from motionlab.evaluation.benchmark import load_benchmark
from motionlab.validation import Checked, check_scalar, check_tensor, integer

#: Numbers in a MoGlow pose vector for the 22-joint skeleton (root height + 21 x 3).
POSE_FEATURES = 64

#: Features per frame of the clip windows (the MoGlow representation: pose plus root control).
CLIP_FEATURES = 67


def pose_features(clips: MotionClips, every: int = 10) -> Tensor:
    """Pose vectors ``(N * ceil(T / every), 64)`` from every ``every``-th frame of every clip, in metres.

    Uses the root's orientation for the heading (``rotations[..., 0, :]``), so each pose is seen from the
    character's own frame: facing +x, left +y, root above the origin.
    """
    check_scalar(every, "every", "pose_features", kind=numbers.Integral, minimum=1)
    rep = representation("moglow")
    positions = torch.as_tensor(clips.positions)[:, ::every]
    rotations = torch.as_tensor(clips.rotations)[:, ::every]
    features = rep.encode(positions, rotations)
    return rep.select(features, "pose").reshape(-1, POSE_FEATURES)


def pose_to_positions(poses: Tensor) -> Tensor:
    """Joint positions ``(..., 22, 3)`` of pose vectors ``(..., 64)``: root above the origin, facing +x."""
    check_tensor(poses, "poses", "pose_to_positions", trailing=(POSE_FEATURES,))
    still = poses.new_zeros(poses.shape[:-1] + (len(CONTROL_FEATURES),))
    return from_moglow(torch.cat([poses, still], dim=-1)[..., None, :])[..., 0, :, :]


@dataclass(frozen=True, eq=False)
class ClipCodec:
    """Standardised MoGlow windows <-> global joint positions.

    Attributes:
        standardizer: per-channel statistics of the training windows (:data:`CLIP_FEATURES` channels).
        length: frames per window.
    """

    standardizer: Standardizer
    length: int

    def to_positions(self, features: Tensor) -> Tensor:
        """Positions ``(..., L, 22, 3)`` of standardised windows ``(..., L, 67)``; each starts at the origin
        facing +x."""
        where = "ClipCodec.to_positions"
        check_tensor(features, "features", where, trailing=(self.length, CLIP_FEATURES), finite=False)
        return from_moglow(self.standardizer.inverse(features.detach()))


def clip_windows(
    train: MotionClips, others: tuple[MotionClips, ...], length: int, stride: int
) -> tuple[ClipCodec, WindowDataset, tuple[WindowDataset, ...]]:
    """Standardised MoGlow windows of the training clips and of other splits (train statistics).

    Returns the codec, the training windows and the other splits' windows, each a
    :class:`~motionlab.data.datasets.WindowDataset` whose ``features`` are ``(W, length, 67)``.
    """
    check_scalar(length, "length", "clip_windows", kind=numbers.Integral, minimum=1)
    check_scalar(stride, "stride", "clip_windows", kind=numbers.Integral, minimum=1)
    rep = representation("moglow")
    raw = motion_windows(train, rep, length, stride)
    standardizer = Standardizer(rep.dim).fit(raw.features)
    train_windows = raw.with_features(standardizer.transform(raw.features))
    other_windows = tuple(
        motion_windows(clips, rep, length, stride, standardizer=standardizer) for clips in others
    )
    return ClipCodec(standardizer, length), train_windows, other_windows


class PoseSplits(NamedTuple):
    """The chapter's pose data: training and held-out poses, standardised with the training statistics.

    Attributes:
        standardizer: per-channel statistics of the training poses (64 channels).
        train: standardised training poses ``(N, 64)``.
        test: standardised held-out poses ``(M, 64)``.
        test_poses: the held-out poses in metres ``(M, 64)`` (what :func:`pose_to_positions` reads).
    """

    standardizer: Standardizer
    train: Tensor
    test: Tensor
    test_poses: Tensor


class ClipSplits(NamedTuple):
    """The chapter's clip data: standardised windows ``(W, L, 67)`` of the training and held-out clips and
    their :class:`ClipCodec` (training statistics)."""

    codec: ClipCodec
    train: WindowDataset
    test: WindowDataset


@functools.cache
def _benchmark_poses(every: int, profile: str) -> PoseSplits:
    """:meth:`BenchmarkPoses.load`, cached per process; ``profile`` only keys the cache (the benchmark's
    size depends on it)."""
    benchmark = load_benchmark()
    poses = pose_features(benchmark.train, every=every)
    test_poses = pose_features(benchmark.test, every=every)
    standardizer = Standardizer(POSE_FEATURES).fit(poses)
    return PoseSplits(
        standardizer, standardizer.transform(poses), standardizer.transform(test_poses), test_poses
    )


@functools.cache
def _benchmark_val_poses(every: int, profile: str) -> Tensor:
    """:meth:`BenchmarkPoses.validation_inputs`' poses ``(V, 64)``: the benchmark's validation clips taken as
    :func:`_benchmark_poses` takes the test clips (the training poses' standardizer), cached per process."""
    poses = pose_features(load_benchmark().val, every=every)
    return _benchmark_poses(every, profile).standardizer.transform(poses)


@functools.cache
def _benchmark_clips(length: int, stride: int, profile: str) -> ClipSplits:
    """:meth:`BenchmarkClips.load`, cached per process; ``profile`` only keys the cache."""
    benchmark = load_benchmark()
    codec, train, (test,) = clip_windows(benchmark.train, (benchmark.test,), length, stride)
    return ClipSplits(codec, train, test)


@functools.cache
def _benchmark_val_clips(length: int, stride: int, profile: str) -> WindowDataset:
    """:meth:`BenchmarkClips.validation_inputs`' windows ``(V, length, 67)``: the benchmark's validation clips
    cut and standardised as :func:`clip_windows` does the test clips (the training windows' standardizer),
    cached per process."""
    standardizer = _benchmark_clips(length, stride, profile).codec.standardizer
    return motion_windows(
        load_benchmark().val, representation("moglow"), length, stride, standardizer=standardizer
    )


@dataclass(frozen=True)
class BenchmarkPoses(Checked):
    """Poses of the course benchmark: every ``every``-th frame of its train, test and validation clips
    (:func:`pose_features`).

    The unconditional pose models train on :meth:`training_inputs` and validate on :meth:`validation_inputs`.
    """

    every: int = integer(minimum=1)

    def load(self) -> PoseSplits:
        """The poses (built once per process and profile; treat the tensors as read-only)."""
        return _benchmark_poses(self.every, config.profile())

    def training_inputs(self) -> tuple[Tensor, None]:
        """``(x, None)``: the standardised training poses ``(N, 64)``, no labels."""
        return self.load().train, None

    def validation_inputs(self) -> tuple[Tensor, None]:
        """``(x, None)``: the benchmark's validation poses ``(V, 64)``, taken and standardised like the
        training poses (their statistics, not refitted), no labels. Built once per process and profile."""
        return _benchmark_val_poses(self.every, config.profile()), None


@dataclass(frozen=True)
class BenchmarkClips(Checked):
    """Windows of the course benchmark's clips: ``length`` frames every ``stride`` frames
    (:func:`clip_windows`).

    The clip CVAEs train on :meth:`training_inputs` and validate on :meth:`validation_inputs`.
    """

    length: int = integer(minimum=1)
    stride: int = integer(minimum=1)

    def load(self) -> ClipSplits:
        """The windows (built once per process and profile; treat the tensors as read-only)."""
        return _benchmark_clips(self.length, self.stride, config.profile())

    def training_inputs(self) -> tuple[Tensor, Tensor]:
        """``(x, action)``: standardised training windows ``(W, length, 67)`` and their actions ``(W,)``."""
        train = self.load().train
        return train.features, train.action

    def validation_inputs(self) -> tuple[Tensor, Tensor]:
        """``(x, action)``: the benchmark's validation windows ``(V, length, 67)``, cut and standardised like
        the training windows (their statistics, not refitted), and their actions ``(V,)``. Built once per
        process and profile."""
        val = _benchmark_val_clips(self.length, self.stride, config.profile())
        return val.features, val.action
