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

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from motionlab.data.augment import random_yaw
from motionlab.data.representations import check_tensor, to_trajevae
from motionlab.models.trajevae.masks import KEEP_PROBABILITY, given_trajectories, sample_joint_masks

#: Every FRAME_STEP-th frame of the 30 fps clips is kept.
FRAME_STEP = 2

#: Frame rate of the chapter's windows.
FPS = 15


def decimate(clips: np.ndarray | Tensor) -> Tensor:
    """Every :data:`FRAME_STEP`-th frame of clips ``(N, T, ...)`` as a float32 tensor ``(N, ceil(T / 2),
    ...)``."""
    clips = torch.as_tensor(clips, dtype=torch.float32)
    if clips.dim() < 2:
        raise ValueError(f"decimate: clips need a frame axis (N, T, ...), got shape {tuple(clips.shape)}")
    return clips[:, ::FRAME_STEP]


def completion_windows(positions: np.ndarray | Tensor) -> Tensor:
    """Clips ``(N, T, J, 3)`` (global positions, metres) as windows ``(N, T, J * 3)`` float32."""
    positions = check_tensor(
        torch.as_tensor(positions, dtype=torch.float32),
        "positions",
        "completion_windows",
        (None, 3),
        min_leading=2,
    )
    if positions.dim() != 4:
        raise ValueError(
            f"completion_windows: positions must have shape (N, T, J, 3), got {tuple(positions.shape)}"
        )
    return to_trajevae(positions)


def completion_task(windows: Tensor, mask: Tensor) -> tuple[Tensor, Tensor]:
    """What a model is given: the initial pose ``(B, J * 3)`` and the trajectories ``(B, T - 1, J * 3)``.

    Args:
        windows: ``(B, T, J * 3)`` ground-truth windows.
        mask: ``(B, J)`` or ``(J,)`` bool, True for joints whose trajectory is given (``(J,)`` applies to
        all).
    """
    if mask.dim() == 1:
        mask = mask.expand(windows.shape[0], -1)
    return windows[:, 0], given_trajectories(windows[:, 1:], mask)


@dataclass(frozen=True, eq=False)
class CompletionBatches:
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
    """

    positions: Tensor
    rotations: Tensor
    augment: bool
    keep_probability: float = KEEP_PROBABILITY

    def __post_init__(self) -> None:
        func = "CompletionBatches"
        positions = check_tensor(
            torch.as_tensor(self.positions, dtype=torch.float32), "positions", func, (None, 3)
        )
        rotations = check_tensor(
            torch.as_tensor(self.rotations, dtype=torch.float32), "rotations", func, (None, 4)
        )
        if positions.dim() != 4 or positions.shape[:-1] != rotations.shape[:-1]:
            raise ValueError(
                f"{func}: positions (N, T, J, 3) and rotations (N, T, J, 4) must share N, T, J; got "
                f"{tuple(positions.shape)} and {tuple(rotations.shape)}"
            )
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "rotations", rotations)

    def __len__(self) -> int:
        return int(self.positions.shape[0])

    def __call__(
        self, epoch: int, generator: torch.Generator, batch_size: int
    ) -> Iterator[tuple[Tensor, Tensor]]:
        n = len(self)
        if not 1 <= batch_size <= n:
            raise ValueError(f"CompletionBatches: batch_size must lie in [1, {n}], got {batch_size}")
        order = torch.randperm(n, generator=generator)
        for begin in range(0, n - n % batch_size, batch_size):
            index = order[begin : begin + batch_size]
            positions = self.positions[index]
            if self.augment:
                positions, _ = random_yaw(positions, self.rotations[index], generator)
            mask = sample_joint_masks(batch_size, generator, positions.shape[-2], self.keep_probability)
            yield to_trajevae(positions), mask
