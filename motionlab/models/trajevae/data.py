"""Training batches and evaluation windows for trajectory completion.

A window is a whole benchmark clip (4 s) in the TrajeVAE representation
(:func:`motionlab.data.representations.to_trajevae`): all joints' global xyz in metres, shifted so that the
first frame's pelvis stands above the origin. Shapes: ``(N, T, J * 3)``, frame 0 the initial pose.

**Frame rate.** The chapter resamples the 30 fps clips to :data:`FPS` = 15 fps by keeping every
:data:`FRAME_STEP`-th frame (the motion is smooth, so nothing visible is lost), which halves the frames every
attention layer looks at: a window has 60 frames. The evaluation classifiers were trained at 30 fps, so
completions are interpolated back (:func:`motionlab.models.trajevae.evaluate.upsample_frames`) before
they are classified.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from motionlab.data.augment import check_clips, random_yaw
from motionlab.data.representations import to_trajevae
from motionlab.models.trajevae.masks import (
    KEEP_PROBABILITY,
    check_mask,
    given_trajectories,
    sample_joint_masks,
)
from motionlab.validation import Checked, check_scalar, check_tensor, flag, real

#: Every FRAME_STEP-th frame of the 30 fps clips is kept.
FRAME_STEP = 2

#: Frame rate of the chapter's windows.
FPS = 15


def decimate(clips: np.ndarray | Tensor) -> Tensor:
    """Every :data:`FRAME_STEP`-th frame of clips ``(N, T, ...)`` as a float32 tensor ``(N, ceil(T / 2),
    ...)``."""
    clips = check_tensor(torch.as_tensor(clips, dtype=torch.float32), "clips", "decimate", min_leading=2)
    return clips[:, ::FRAME_STEP]


def completion_windows(positions: np.ndarray | Tensor) -> Tensor:
    """Clips ``(N, T, J, 3)`` (global positions, metres) as windows ``(N, T, J * 3)`` float32."""
    positions = torch.as_tensor(positions, dtype=torch.float32)
    check_tensor(positions, "positions", "completion_windows", trailing=(None, 3), ndim=4)
    return to_trajevae(positions)


def completion_task(windows: Tensor, mask: Tensor) -> tuple[Tensor, Tensor]:
    """What a model is given: the initial pose ``(B, J * 3)`` and the trajectories ``(B, T - 1, J * 3)``.

    Args:
        windows: ``(B, T, J * 3)`` ground-truth windows.
        mask: ``(B, J)`` or ``(J,)`` bool, True for joints whose trajectory is given (``(J,)`` applies to
        all).
    """
    where = "completion_task"
    check_tensor(windows, "windows", where, ndim=3)
    check_mask(mask, "mask", where)
    if mask.dim() == 1:
        mask = mask.expand(windows.shape[0], -1)
    return windows[:, 0], given_trajectories(windows[:, 1:], mask)


def check_batch(windows: Tensor, mask: Tensor, n_frames: int, n_joints: int, where: str) -> None:
    """Check a training batch: windows ``(B, n_frames, n_joints * 3)`` (finite floats) and masks ``(B,
    n_joints)`` bool."""
    check_tensor(windows, "windows", where, trailing=(n_frames, 3 * n_joints), ndim=3)
    check_mask(mask, "mask", where, shape=(windows.shape[0], n_joints))


def check_task(
    initial_pose: Tensor,
    trajectories: Tensor,
    n_samples: int,
    temperature: float,
    n_frames: int,
    n_joints: int,
    where: str,
) -> int:
    """Check a sampling request of a completion model (the arguments of ``sample``); return its batch size.

    Args:
        initial_pose: ``(B, J * 3)`` the pose at frame 0.
        trajectories: ``(B, n_frames - 1, J * 3)`` the given joints' positions in frames ``1 ..``, zeros for
            the joints to complete (``Y = X ⊙ M``).
        n_samples: completions per task, an integer >= 1; temperature: a finite number >= 0.
    """
    channels = 3 * n_joints
    check_tensor(initial_pose, "initial_pose", where, trailing=(channels,), ndim=2)
    check_tensor(trajectories, "trajectories", where, trailing=(n_frames - 1, channels), ndim=3)
    batch = initial_pose.shape[0]
    if trajectories.shape[0] != batch:
        raise ValueError(
            f"{where}: trajectories must have shape ({batch}, {n_frames - 1}, {channels}) like initial_pose, "
            f"got {tuple(trajectories.shape)}"
        )
    check_scalar(n_samples, "n_samples", where, kind=numbers.Integral, minimum=1)
    check_scalar(temperature, "temperature", where, minimum=0)
    return batch


@dataclass(frozen=True, eq=False)
class CompletionBatches(Checked):
    """The training batch source: shuffled clips, each with a random joint mask, optionally turned by a random
    yaw.

    Called by the training loop as ``batches(epoch, generator, batch_size)``; yields ``(windows, mask)``
    with windows ``(B, T, J * 3)`` and masks ``(B, J)`` bool. All randomness (order, yaw, masks) comes from
    ``generator``, so an epoch is the same whenever it is replayed.

    Attributes:
        positions: training clips ``(N, T, J, 3)``; rotations: their local quaternions ``(N, T, J, 4)``
            (the yaw augmentation turns the root orientation too).
        augment: turn every clip about the vertical axis by an angle uniform in ``[-pi, pi)``.
        keep_probability: chance that a joint's trajectory is given.
        shuffle: draw the clips' order from ``generator`` (the default); ``False`` keeps the stored order
            (validation).
        drop_last: drop the final short batch (the default, so every step sees ``batch_size`` clips);
            ``False`` serves every clip (validation).
    """

    positions: Tensor
    rotations: Tensor
    augment: bool = flag()
    keep_probability: float = real(KEEP_PROBABILITY, minimum=0, maximum=1)
    shuffle: bool = flag(True)
    drop_last: bool = flag(True)

    def __post_init__(self) -> None:
        super().__post_init__()
        where = "CompletionBatches"
        positions = torch.as_tensor(self.positions, dtype=torch.float32)
        rotations = torch.as_tensor(self.rotations, dtype=torch.float32)
        check_tensor(positions, "positions", where, ndim=4, finite=False)  # (N, T, J, 3)
        check_clips(positions, rotations, where)
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "rotations", rotations)

    def __len__(self) -> int:
        return int(self.positions.shape[0])

    def __call__(
        self, epoch: int, generator: torch.Generator, batch_size: int
    ) -> Iterator[tuple[Tensor, Tensor]]:
        n = len(self)
        check_scalar(
            batch_size,
            "batch_size",
            "CompletionBatches",
            kind=numbers.Integral,
            minimum=1,
            maximum=n if self.drop_last else None,
        )
        order = torch.randperm(n, generator=generator) if self.shuffle else torch.arange(n)
        for begin in range(0, n - n % batch_size if self.drop_last else n, batch_size):
            index = order[begin : begin + batch_size]
            positions = self.positions[index]
            if self.augment:
                positions, _ = random_yaw(positions, self.rotations[index], generator)
            mask = sample_joint_masks(len(index), generator, positions.shape[-2], self.keep_probability)
            yield to_trajevae(positions), mask


@dataclass(frozen=True, eq=False)
class CompletionData:
    """The chapter's data at :data:`FPS`: training clips, the test windows every model is measured on and the
    validation clips the runs' held-out curves are measured on.

    Attributes:
        train_positions: training clips ``(N, T, J, 3)``, global positions in metres (float32).
        train_rotations: their local quaternions ``(N, T, J, 4)``.
        test_windows: test windows ``(M, T, J * 3)`` (:func:`completion_windows`), spread over all modes.
        test_action: the action label of each test window ``(M,)``.
        multimodal: DLow's multimodal ground truth of each test window, futures ``(M_i, T - 1, J * 3)``
            (:func:`motionlab.models.trajevae.evaluate.multimodal_futures`).
        val_positions: validation clips ``(V, T, J, 3)``, like ``train_positions``; val_rotations: their
            local quaternions ``(V, T, J, 4)``.
    """

    train_positions: Tensor
    train_rotations: Tensor
    test_windows: Tensor
    test_action: np.ndarray
    multimodal: Sequence[np.ndarray]
    val_positions: Tensor
    val_rotations: Tensor
