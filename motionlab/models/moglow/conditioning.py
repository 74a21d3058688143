"""The autoregressive conditioning shared by MoGlow and its baseline, and its history dropout.

The pose of frame ``t`` is generated given the conditioning vector

    c_t = [x_{t-H}, ..., x_{t-1},  u_{t-H}, ..., u_{t-1}, u_t]

of the ``H`` previous poses ``x`` (the paper's τ, eqs. 16-18) and the ``H + 1`` latest controls ``u`` (the
current one included, so a change of control acts at once: zero latency). No future control is used: the
model is causal.

**History dropout.** Each previous pose in ``c_t`` is replaced by zeros (the mean pose, in standard units)
with probability ``p``, independently per frame and lag. Without it the easiest way to predict ``x_t`` is
to continue ``x_{t-1}``, and the model learns to ignore the control; with it the model has to read the
control (and its own LSTM memory) to know what comes next. As in the paper (§5.3, Fig. 3: "dropout is
only applied at training time") the erasure is a training device: the models draw it in training mode
only, and generate and measure held-out likelihoods with the full history. For that switch to be
harmless, the kept poses are scaled by ``1 / (1 - p)`` in training (standard "inverted" dropout, the
default, ``MoGlowConfig.dropout_rescale``), so that a linear map of the history (our least-squares first
layer, the conditioning projection) sees in expectation the input it gets at generation. Without the
rescaling (the authors' released code zeroes the poses and does not rescale), a linear map fitted to
inputs where one previous pose in twenty is visible adds up all ``H`` of them at generation.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import torch
from torch import Tensor

from motionlab.models.moglow.data import CONTROL_DIM, POSE_DIM
from motionlab.validation import Checked, check_scalar, check_tensor, integer


@dataclass(frozen=True)
class HistoryConfig(Checked):
    """The conditioning sizes of an autoregressive model of MoGlow's features (the base of
    :class:`~.model.MoGlowConfig` and :class:`~.baselines.GaussianARConfig`).

    Attributes:
        pose_dim: pose features per frame (64: root height and 21 joints' xyz).
        control_dim: control features per frame (3: forward, sideways, yaw velocity).
        history: ``H``, the previous poses in the conditioning (with ``H + 1`` control frames, the
            current one included: zero-latency control).
    """

    pose_dim: int = integer(POSE_DIM, minimum=1)
    control_dim: int = integer(CONTROL_DIM, minimum=1)
    history: int = integer(5, minimum=1)

    @property
    def cond_dim(self) -> int:
        """Conditioning features per frame: ``H`` poses and ``H + 1`` controls."""
        return self.history * self.pose_dim + (self.history + 1) * self.control_dim


def check_pose_control(
    pose: Tensor,
    control: Tensor,
    pose_dim: int,
    control_dim: int,
    min_frames: int,
    where: str,
    same_frames: bool = False,
) -> None:
    """Check poses ``(B, T, P)`` and controls ``(B, T', C)``: floating, finite, sized right, one batch.

    ``T >= min_frames`` is required of ``pose``, and ``T' = T`` with ``same_frames`` (a likelihood reads
    both of every frame; sampling has its own rule). ``TypeError`` for a non-tensor or a non-floating
    dtype, ``ValueError`` for a wrong shape or a NaN or infinite entry.
    """
    check_tensor(pose, "pose", where, trailing=(pose_dim,), ndim=3)
    check_tensor(control, "control", where, trailing=(control_dim,), ndim=3)
    if pose.shape[0] != control.shape[0]:
        raise ValueError(
            f"{where}: pose and control must have the same batch size, got {pose.shape[0]} and "
            f"{control.shape[0]}"
        )
    if pose.shape[1] < min_frames:
        raise ValueError(f"{where}: pose needs at least {min_frames} frames, got {pose.shape[1]}")
    if same_frames and control.shape[1] != pose.shape[1]:
        raise ValueError(
            f"{where}: pose and control must have the same frames, got {pose.shape[1]} and {control.shape[1]}"
        )


def history_keep_mask(
    batch: int,
    frames: int,
    history: int,
    dropout: float,
    generator: torch.Generator | None = None,
    rescale: bool = False,
) -> Tensor:
    """Bernoulli keep flags ``(batch, frames, history)``, each dropped (0) with probability ``dropout``.

    A kept previous pose is multiplied by 1 or, with ``rescale``, by ``1 / (1 - dropout)`` (standard
    "inverted" dropout): then any linear map of the history has the same expectation in training as
    on the full history that the model sees when generating.
    """
    for name, value in (("batch", batch), ("frames", frames), ("history", history)):
        check_scalar(value, name, "history_keep_mask", kind=numbers.Integral, minimum=0)
    check_scalar(dropout, "dropout", "history_keep_mask", minimum=0.0, maximum=1.0)
    keep = (torch.rand(batch, frames, history, generator=generator) >= dropout).float()
    return keep / (1.0 - dropout) if rescale and dropout < 1.0 else keep


def autoregressive_conditioning(
    pose: Tensor, control: Tensor, history: int, keep: Tensor | None = None
) -> Tensor:
    """Conditioning ``(B, T - H, cond_dim)`` for predicting frames ``H .. T-1`` of a sequence.

    Args:
        pose: poses ``(B, T, P)`` (standard units).
        control: controls ``(B, T, C)`` of the same frames.
        history: ``H``.
        keep: optional keep flags ``(B, T - H, H)`` from :func:`history_keep_mask`.

    Row ``i`` holds, for frame ``t = H + i``, poses ``t - H .. t - 1`` (oldest first, flattened), then
    controls ``t - H .. t``: the layout of :func:`frame_conditioning`.
    """
    where = "autoregressive_conditioning"
    check_tensor(pose, "pose", where, ndim=3, finite=False)
    check_tensor(control, "control", where, ndim=3, finite=False)
    check_scalar(history, "history", where, kind=numbers.Integral, minimum=1)
    batch, frames, _ = pose.shape
    if control.shape[:2] != pose.shape[:2]:
        raise ValueError(
            f"{where}: control must have the pose's (batch, frames) {tuple(pose.shape[:2])}, "
            f"got {tuple(control.shape)}"
        )
    if frames <= history:
        raise ValueError(f"{where}: needs more than H={history} frames, got {frames}")
    past = pose.unfold(1, history, 1)[:, : frames - history].transpose(2, 3)  # (B, T - H, H, P)
    if keep is not None:
        if keep.shape != (batch, frames - history, history):
            raise ValueError(
                f"{where}: keep must be {(batch, frames - history, history)}, got {tuple(keep.shape)}"
            )
        past = past * keep[..., None].to(past)
    controls = control.unfold(1, history + 1, 1).transpose(2, 3)  # (B, T - H, H + 1, C)
    return torch.cat([past.flatten(2), controls.flatten(2)], dim=2)


def frame_conditioning(past: Tensor, controls: Tensor) -> Tensor:
    """Conditioning ``(B, cond_dim)`` of one frame from ``past`` poses ``(B, H, P)`` and ``controls``
    ``(B, H + 1, C)``."""
    check_tensor(past, "past", "frame_conditioning", ndim=3, finite=False)
    check_tensor(controls, "controls", "frame_conditioning", ndim=3, finite=False)
    if controls.shape[0] != past.shape[0] or controls.shape[1] != past.shape[1] + 1:
        raise ValueError(
            f"frame_conditioning: controls must be (B, H + 1, C) for past (B, H, P) = "
            f"{tuple(past.shape)}, got {tuple(controls.shape)}"
        )
    return torch.cat([past.flatten(1), controls.flatten(1)], dim=1)
