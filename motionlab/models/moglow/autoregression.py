"""The autoregressive conditioning shared by MoGlow and its baseline, its dropout, and a generic sampling
loop.

The loop, :func:`autoregressive_sample`, runs any one-frame ``step`` function (the baseline's); MoGlow has
its own loop, arranged for speed (:mod:`.sampler`), which builds the same conditioning.

The pose of frame ``t`` is generated given the conditioning vector

    c_t = [x_{t-tau}, ..., x_{t-1},  u_{t-tau}, ..., u_{t-1}, u_t]

of the ``tau`` previous poses ``x`` and the ``tau + 1`` latest controls ``u`` (the current one included,
so a change of control acts at once: zero latency). No future control is used: the model is causal.

**History dropout.** Each previous pose in ``c_t`` is replaced by zeros (the mean pose, in standard units)
with probability ``p``, independently per frame and lag. Without it the easiest way to predict ``x_t`` is
to continue ``x_{t-1}``, and the model learns to ignore the control; with it the model has to read the
control (and its own LSTM memory) to know what comes next. The erasure is part of the model: it is
applied when generating and when measuring likelihoods too, not only in training. A model trained with
``p = 0.95`` has almost never seen all ``tau`` previous poses at once, and feeding it the full history
is far outside what it learned (on our data its held-out NLL is tens of nats per frame worse that way).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import torch
from torch import Tensor

from motionlab.models.flows.prior import check_temperature

FrameStep = Callable[[int, Tensor, Any], tuple[Tensor, Any]]
"""``step(t, cond_t (B, cond_dim), state) -> (pose_t (B, P), state)``: generated frame ``t`` (0-based)."""


def check_pose_control(
    pose: Tensor, control: Tensor, pose_dim: int, control_dim: int, min_frames: int, where: str
) -> None:
    """Raise ``ValueError`` unless ``pose`` ``(B, T, P)`` and ``control`` ``(B, T', C)`` are finite and sized
    right.

    ``T >= min_frames`` is required of ``pose``; ``control`` must match its batch (frame counts are
    checked by the callers, which differ in what they need).
    """
    for name, x, size in (("pose", pose, pose_dim), ("control", control, control_dim)):
        if not isinstance(x, Tensor) or not x.is_floating_point() or x.dim() != 3 or x.shape[2] != size:
            shape = tuple(x.shape) if isinstance(x, Tensor) else type(x).__name__
            raise ValueError(
                f"{where}: {name} must be a floating tensor (batch, frames, {size}), got {shape}"
            )
        if not bool(torch.isfinite(x).all()):
            raise ValueError(f"{where}: {name} contains NaN or inf")
    if pose.shape[0] != control.shape[0]:
        raise ValueError(
            f"{where}: pose and control must have the same batch size, got {pose.shape[0]} and "
            f"{control.shape[0]}"
        )
    if pose.shape[1] < min_frames:
        raise ValueError(f"{where}: pose needs at least {min_frames} frames, got {pose.shape[1]}")


def history_keep_mask(
    batch: int, frames: int, history: int, dropout: float, generator: torch.Generator | None = None
) -> Tensor:
    """Bernoulli keep flags ``(batch, frames, history)`` (1 keep, 0 drop), each dropped with prob.
    ``dropout``."""
    return (torch.rand(batch, frames, history, generator=generator) >= dropout).float()


def sampling_setup(
    cfg: Any,
    control: Tensor,
    seed_pose: Tensor,
    temperature: float,
    generator: torch.Generator | None,
    where: str,
) -> tuple[Tensor | None, Tensor]:
    """Checks and first draws shared by the models' ``sample``: ``(keep, noise)``.

    ``cfg`` has ``pose_dim``, ``control_dim``, ``history`` and ``dropout``. ``keep`` are the history dropout
    flags of every generated frame (``None`` without dropout), then ``noise`` ``(B, N, P)`` is the
    standard-normal draw scaled by the temperature, in that order from ``generator``.
    """
    temperature = check_temperature(temperature, where)
    history = cfg.history
    check_pose_control(seed_pose, control, cfg.pose_dim, cfg.control_dim, history, where)
    if seed_pose.shape[1] != history or control.shape[1] <= history:
        raise ValueError(
            f"{where}: seed_pose must have tau={history} frames and control more than that, "
            f"got {tuple(seed_pose.shape)} and {tuple(control.shape)}"
        )
    batch, frames = control.shape[0], control.shape[1] - history
    keep = None
    if cfg.dropout > 0:
        keep = history_keep_mask(batch, frames, history, cfg.dropout, generator).to(control.dtype)
    noise = temperature * torch.randn(batch, frames, cfg.pose_dim, generator=generator, dtype=control.dtype)
    return keep, noise


def autoregressive_conditioning(
    pose: Tensor, control: Tensor, history: int, keep: Tensor | None = None
) -> Tensor:
    """Conditioning ``(B, T - tau, cond_dim)`` for predicting frames ``tau .. T-1`` of a sequence.

    Args:
        pose: poses ``(B, T, P)`` (standard units).
        control: controls ``(B, T, C)`` of the same frames.
        history: ``tau``.
        keep: optional keep flags ``(B, T - tau, tau)`` from :func:`history_keep_mask`.

    Row ``i`` holds, for frame ``t = tau + i``, poses ``t - tau .. t - 1`` (oldest first, flattened), then
    controls ``t - tau .. t``: the layout of :func:`frame_conditioning`.
    """
    batch, frames, _ = pose.shape
    if frames <= history:
        raise ValueError(f"autoregressive_conditioning: needs more than tau={history} frames, got {frames}")
    past = pose.unfold(1, history, 1)[:, : frames - history].transpose(2, 3)  # (B, T - tau, tau, P)
    if keep is not None:
        if keep.shape != (batch, frames - history, history):
            raise ValueError(
                f"autoregressive_conditioning: keep must be {(batch, frames - history, history)}, "
                f"got {tuple(keep.shape)}"
            )
        past = past * keep[..., None].to(past)
    controls = control.unfold(1, history + 1, 1).transpose(2, 3)  # (B, T - tau, tau + 1, C)
    return torch.cat([past.flatten(2), controls.flatten(2)], dim=2)


def frame_conditioning(past: Tensor, controls: Tensor) -> Tensor:
    """Conditioning ``(B, cond_dim)`` of one frame from ``past`` poses ``(B, tau, P)`` and ``controls``
    ``(B, tau + 1, C)``."""
    return torch.cat([past.flatten(1), controls.flatten(1)], dim=1)


def autoregressive_sample(
    step: FrameStep, control: Tensor, seed_pose: Tensor, state: Any = None, keep: Tensor | None = None
) -> Tensor:
    """Generate frame by frame: ``(B, N, P)`` poses for controls ``(B, tau + N, C)`` after ``tau`` seed poses.

    Args:
        step: one frame of the model, ``step(t, cond_t, state) -> (pose_t, state)``; its state (the LSTM
            memory) is carried from frame to frame.
        control: controls of the seed frames then of the ``N`` frames to generate (standard units).
        seed_pose: the ``tau`` poses ``(B, tau, P)`` that start the history (standard units).
        state: the initial state handed to ``step`` (``None``: the model's zero state).
        keep: history dropout flags ``(B, N, tau)`` for the generated frames (as in training), or ``None``.

    Raises ``ValueError`` naming the first frame when the generated poses stop being finite (a model can
    diverge on inputs far from its training data).
    """
    history = seed_pose.shape[1]
    frames = control.shape[1] - history
    if keep is not None and keep.shape != (seed_pose.shape[0], frames, history):
        raise ValueError(
            f"autoregressive_sample: keep must be {(seed_pose.shape[0], frames, history)}, "
            f"got {tuple(keep.shape)}"
        )
    past, poses = seed_pose, []
    for t in range(frames):
        visible = past if keep is None else past * keep[:, t, :, None]
        pose_t, state = step(t, frame_conditioning(visible, control[:, t : t + history + 1]), state)
        poses.append(pose_t)
        past = torch.cat([past[:, 1:], pose_t[:, None]], dim=1)
    return check_generated(torch.stack(poses, dim=1), "autoregressive_sample")


def check_generated(generated: Tensor, where: str) -> Tensor:
    """Return generated poses ``(B, N, P)``; raise ``ValueError`` naming the first frame that is not finite
    (a model can diverge on inputs far from its training data)."""
    finite = torch.isfinite(generated).all(dim=(0, 2))
    if not bool(finite.all()):
        raise ValueError(
            f"{where}: generation diverged: non-finite poses from generated frame "
            f"{int(torch.nonzero(~finite)[0])} of {generated.shape[1]}"
        )
    return generated
