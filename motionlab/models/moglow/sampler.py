"""MoGlow's generation loop: the flow inverted one frame at a time, written to be fast at batch size 1.

The conditioning of frame ``t`` holds the pose generated at ``t - 1``, so generation inverts the flow frame
by frame: for each Glow step in reverse order, the coupling's LSTM reads the untouched half ``x_a`` and the
conditioning features, updates its state and gives the shift and scale that undo the affine coupling; then
the step's ActNorm and 1x1 convolution, folded into one matrix, are undone. Last, the linear predictor's
mean is added back.

At batch size 1 a frame is a few dozen tiny tensor operations. Each costs a few microseconds of Python
and dispatch overhead, while its arithmetic costs well under one, so the loop is arranged to do few of them:

* Everything that the conditioning ``c_t`` enters linearly (the shared conditioning encoder and the linear
  predictor) is split into a control part, computed for all frames in one matrix product before the
  loop, and a past-pose part, one product per frame.
* The conditioning features enter every coupling's LSTM gates and output layer linearly too: those
  weights are stacked into one matrix (:attr:`GenerationPlan.feature_weight`), one product per frame for
  all couplings, instead of a concatenation and larger products in each.
* The loop itself, :func:`generate_frames`, runs in TorchScript (compiled once per process), with no
  Python interpreter between the operations; the same function also runs as plain Python
  (``scripted=False``, for reading and debugging), with the same result up to float rounding.
"""

import functools
import warnings
from collections.abc import Callable
from typing import (
    NamedTuple,
)  # TorchScript reads these annotations: no ``from __future__ import annotations``

import torch
from torch import Tensor

from motionlab.models.moglow.coupling import FrameCoupling


class InverseStep(NamedTuple):
    """One Glow step's weights for inverting a frame ``(B, P)`` whose untouched half ``x_a`` is ``(B, C_a)``.

    ``coupling`` holds the coupling's weights (:class:`~.coupling.FrameCoupling`; the loop reads its
    conditioning features' parts through :attr:`GenerationPlan.feature_weight`). The step's ActNorm and 1x1
    convolution are undone by ``x = x_a @ matrix_a + x_b @ matrix_b + shift``.
    """

    coupling: FrameCoupling
    matrix_a: Tensor  # (C_a, P)
    matrix_b: Tensor  # (C_b, P)
    shift: Tensor  # (P,)


class GenerationPlan(NamedTuple):
    """A MoGlow's weights arranged for :func:`generate_frames` (``F`` conditioning features, ``P`` pose
    channels, ``tau`` history frames, ``C`` control channels, ``K`` steps); a snapshot, built again after
    training.

    The conditioning encoder and the linear predictor read the same vector ``c_t``, so their weights are
    side by side: ``[features | mean] = past @ past_weight + controls @ control_weight + bias`` ``(B, F +
    P)``. ``feature_weight`` ``(F, K * (4H + 2 C_b))`` maps the features to every step's LSTM-gate part
    (``4H``) and output part (``2 C_b``), step after step in inverse order, as in ``steps``. The generated
    pose is ``mean + x * residual_scale``.
    """

    past_weight: Tensor  # (tau * P, F + P)
    control_weight: Tensor  # ((tau + 1) * C, F + P)
    bias: Tensor  # (F + P,)
    feature_weight: Tensor  # (F, K * (4H + 2 C_b))
    residual_scale: Tensor  # (P,)
    steps: list[InverseStep]


def generate_frames(
    plan: GenerationPlan, control_part: Tensor, past: Tensor, keep: Tensor, noise: Tensor
) -> Tensor:
    """The frame-by-frame loop: poses ``(B, N, P)`` in standard units.

    Args:
        plan: the model's weights (:meth:`motionlab.models.moglow.model.MoGlow.generation_plan`).
        control_part: ``(B, N, F + P)``, the controls' part of ``[features | mean]`` of every frame, bias
        included. past: ``(B, tau * P)``, the seed poses, oldest first, flattened.
        keep: ``(B, N, tau * P)``, the history dropout flags of every frame, repeated over each pose's
        channels. noise: ``(B, N, P)``, the latents ``z_t`` (temperature applied).
    """
    batch, frames, pose_dim = noise.shape
    features = plan.feature_weight.shape[0]
    n_a = plan.steps[0].matrix_a.shape[0]
    hidden = plan.steps[0].coupling.lstm_hidden.shape[1]
    gates, step_width = 4 * hidden, 4 * hidden + 2 * (pose_dim - n_a)
    h = [noise.new_zeros(batch, hidden) for _ in plan.steps]
    c = [noise.new_zeros(batch, hidden) for _ in plan.steps]
    poses: list[Tensor] = []
    for t in range(frames):
        features_and_mean = torch.addmm(control_part[:, t], past * keep[:, t], plan.past_weight)
        features_by_step = torch.mm(features_and_mean[:, :features], plan.feature_weight)
        x = noise[:, t]
        for k, step in enumerate(plan.steps):
            weights, offset = step.coupling, k * step_width
            x_a = x[:, :n_a]
            h[k], c[k] = torch.lstm_cell(
                x_a,
                (h[k], c[k]),
                weights.lstm_input_a,
                weights.lstm_hidden,
                features_by_step[:, offset : offset + gates],
                weights.lstm_bias,
            )
            params = torch.addmm(weights.out_bias, h[k], weights.out_hidden).addmm_(x_a, weights.out_input_a)
            shift, raw_scale = params.add_(features_by_step[:, offset + gates : offset + step_width]).chunk(
                2, dim=1
            )
            x_b = x[:, n_a:].div(torch.sigmoid(raw_scale)).sub_(shift)
            x = torch.addmm(step.shift, x_a, step.matrix_a).addmm_(x_b, step.matrix_b)
        pose = features_and_mean[:, features:].addcmul(x, plan.residual_scale)
        poses.append(pose)
        past = torch.cat([past[:, pose_dim:], pose], dim=1)
    return torch.stack(poses, dim=1)


@functools.cache
def _scripted_loop() -> Callable[..., Tensor]:
    """:func:`generate_frames` compiled by TorchScript (once per process)."""
    with warnings.catch_warnings():
        # TorchScript is deprecated in favour of torch.compile, which does not help here: at batch 1 its
        # compiled frame still runs under Python (measured: no faster than the plain loop).
        warnings.filterwarnings(
            "ignore", message=".*torch.jit.script.*is deprecated", category=DeprecationWarning
        )
        return torch.jit.script(generate_frames)


def _shapes_fit(
    plan: GenerationPlan, control: Tensor, seed_pose: Tensor, keep: Tensor | None, noise: Tensor
) -> bool:
    """Whether the inputs' shapes fit each other and the plan (see :func:`sample_frames`)."""
    if not control.dim() == seed_pose.dim() == noise.dim() == 3:
        return False
    batch, history, pose_dim = seed_pose.shape
    frames = noise.shape[1]
    return (
        control.shape[:2] == (batch, history + frames)
        and noise.shape == (batch, frames, pose_dim)
        and (keep is None or keep.shape == (batch, frames, history))
        and plan.past_weight.shape[0] == history * pose_dim
        and plan.residual_scale.shape[0] == pose_dim
        and plan.control_weight.shape[0] == (history + 1) * control.shape[2]
    )


def _check_inputs(
    plan: GenerationPlan, control: Tensor, seed_pose: Tensor, keep: Tensor | None, noise: Tensor
) -> None:
    """Raise ``ValueError`` unless the inputs' shapes and dtype fit each other and the plan."""
    if not _shapes_fit(plan, control, seed_pose, keep, noise):
        raise ValueError(
            f"sample_frames: shapes disagree: control {tuple(control.shape)} must be (B, tau + N, C), "
            f"seed_pose {tuple(seed_pose.shape)} (B, tau, P), noise {tuple(noise.shape)} (B, N, P), keep "
            f"{None if keep is None else tuple(keep.shape)} (B, N, tau), with the plan's tau * P = "
            f"{plan.past_weight.shape[0]}, P = {plan.residual_scale.shape[0]}, (tau + 1) * C = "
            f"{plan.control_weight.shape[0]}"
        )
    if len({x.dtype for x in (control, seed_pose, noise, plan.bias)}) != 1:
        raise ValueError(
            f"sample_frames: control, seed_pose, noise and the model must share one dtype, got "
            f"{control.dtype}, {seed_pose.dtype}, {noise.dtype} and {plan.bias.dtype}"
        )


def sample_frames(
    plan: GenerationPlan,
    control: Tensor,
    seed_pose: Tensor,
    keep: Tensor | None,
    noise: Tensor,
    scripted: bool = True,
) -> Tensor:
    """Generate ``N`` poses ``(B, N, P)`` after the seed (standard units; values checked by the caller).

    Args:
        plan: the model's weights (:meth:`motionlab.models.moglow.model.MoGlow.generation_plan`).
        control: ``(B, tau + N, C)``, the seed frames' controls then those of the frames to generate.
        seed_pose: ``(B, tau, P)``.
        keep: history dropout flags ``(B, N, tau)`` (1 keep, 0 drop), or ``None`` for no dropout.
        noise: the latents ``(B, N, P)``.
        scripted: run the TorchScript-compiled loop (``False``: the same function as plain Python).

    Raises ``ValueError`` when the shapes or dtypes disagree with each other or with the plan.
    """
    _check_inputs(plan, control, seed_pose, keep, noise)
    batch, history, pose_dim = seed_pose.shape
    frames = noise.shape[1]
    windows = (
        control.unfold(1, history + 1, 1).transpose(2, 3).reshape(batch * frames, -1)
    )  # (B N, (tau+1) C)
    control_part = torch.addmm(plan.bias, windows, plan.control_weight).view(batch, frames, -1)
    if keep is None:
        keep = noise.new_ones(batch, frames, history)
    loop = _scripted_loop() if scripted else generate_frames
    return loop(
        plan,
        control_part,
        seed_pose.reshape(batch, history * pose_dim),
        keep.to(noise.dtype).repeat_interleave(pose_dim, dim=2),
        noise,
    )
