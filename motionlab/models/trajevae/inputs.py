"""Input checks shared by the completion models: clear errors for wrong shapes, NaNs and bad settings."""

from __future__ import annotations

import math

import torch
from torch import Tensor

from motionlab.data.representations import check_tensor


def check_finite_tensor(x: Tensor, name: str, func: str, shape: tuple[int | None, ...]) -> Tensor:
    """Check that ``x`` is a finite floating tensor of exactly ``shape`` (``None`` accepts any size); return
    it."""
    if isinstance(x, Tensor) and x.dim() != len(shape):
        layout = "(" + ", ".join("*" if size is None else str(size) for size in shape) + ")"
        raise ValueError(f"{func}: {name} must have shape {layout}, got {tuple(x.shape)}")
    return check_tensor(x, name, func, shape)


def check_windows(windows: Tensor, n_frames: int, n_channels: int, func: str) -> Tensor:
    """Windows ``(B, n_frames, n_channels)``: frame 0 the initial pose, the rest the poses to complete."""
    return check_finite_tensor(windows, "windows", func, (None, n_frames, n_channels))


def check_masks(mask: Tensor, batch: int, n_joints: int, func: str) -> Tensor:
    """Joint masks ``(batch, n_joints)`` of dtype bool."""
    if not isinstance(mask, Tensor) or mask.dtype != torch.bool:
        raise ValueError(
            f"{func}: mask must be a bool tensor ({batch}, {n_joints}), got "
            f"{getattr(mask, 'dtype', type(mask).__name__)}"
        )
    if tuple(mask.shape) != (batch, n_joints):
        raise ValueError(f"{func}: mask must have shape ({batch}, {n_joints}), got {tuple(mask.shape)}")
    return mask


def check_task(initial_pose: Tensor, trajectories: Tensor, n_future: int, n_channels: int, func: str) -> int:
    """Check a completion task; return its batch size.

    Args:
        initial_pose: ``(B, n_channels)`` the pose at frame 0.
        trajectories: ``(B, n_future, n_channels)`` the given joints' positions in frames ``1 ..``, zeros for
            the joints to complete (``Y = X ⊙ M``).
    """
    check_finite_tensor(initial_pose, "initial_pose", func, (None, n_channels))
    check_finite_tensor(trajectories, "trajectories", func, (initial_pose.shape[0], n_future, n_channels))
    return initial_pose.shape[0]


def check_sampling(n_samples: int, temperature: float, func: str) -> None:
    """``n_samples`` a positive int, ``temperature`` a finite number >= 0."""
    if isinstance(n_samples, bool) or not isinstance(n_samples, int) or n_samples < 1:
        raise ValueError(f"{func}: n_samples must be a positive integer, got {n_samples!r}")
    if (
        isinstance(temperature, bool)
        or not isinstance(temperature, (int, float))
        or not math.isfinite(temperature)
        or temperature < 0
    ):
        raise ValueError(f"{func}: temperature must be a finite number >= 0, got {temperature!r}")
