"""Generating motion with MoGlow and its baseline: one frame at a time, in standard and in physical units.

The conditioning of frame ``t`` holds the pose generated at ``t - 1``, so generation inverts the flow frame
by frame, carrying the couplings' LSTM states from one frame to the next. This module holds the same loop
twice:

* :func:`sample_plain`, the idea in a dozen lines: condition on the history and the control, take the
  frame's latent ``z_t`` (drawn at the temperature), invert the Glow steps in reverse order with the
  model's own layers, add the linear prediction back, append the pose to the history.
* :func:`sample_frames` / :func:`generate_frames`, the fused loop that :meth:`MoGlow.sample
  <motionlab.models.moglow.model.MoGlow.sample>` runs, written to be fast at batch size 1. The two give
  the same frames up to float rounding (same seed, same draws).

**Why a fused loop.** At batch size 1 a frame is a few dozen tiny tensor operations. Each costs a few
microseconds of Python and dispatch overhead, while its arithmetic costs well under one, so the fused loop
is arranged to do few of them:

* Everything that the conditioning ``c_t`` enters linearly (the shared conditioning encoder and the linear
  predictor) is split into a control part, computed for all frames in one matrix product before the
  loop, and a past-pose part, one product per frame.
* The conditioning features enter every coupling's LSTM gates and output layer linearly too: those
  weights are stacked into one matrix (:attr:`GenerationPlan.feature_weight`), one product per frame for
  all couplings, instead of a concatenation and larger products in each.
* The loop itself, :func:`generate_frames`, runs in TorchScript (compiled once per process), with no
  Python interpreter between the operations; the same function also runs as plain Python
  (``scripted=False``, for debugging), with the same result up to float rounding.

**Physical units.** The models work in standard units (:mod:`.data`). :func:`generate_motion` takes
controls in metres and radians per frame (e.g. from :func:`control_programme` or :func:`splice_controls`),
turns the generated poses back into metres and integrates the root path from the control
(:func:`motionlab.data.representations.from_moglow`): MoGlow never predicts where the root goes, the
control says it, and the model's job is a body that moves accordingly. :func:`autoregressive_sample` is
the generic loop of the Gaussian baseline (any one-frame ``step``); :func:`sample_loop` is the same loop
in the form chapter 06's exercise asks for, which the chapter's small flow generates with.
"""

import functools
import numbers
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import (  # TorchScript reads these annotations: no ``from __future__ import annotations``
    Any,
    NamedTuple,
)

import torch
from torch import Tensor, nn

from motionlab.data.representations import from_moglow
from motionlab.models.flows.prior import check_temperature
from motionlab.models.moglow.conditioning import check_pose_control, frame_conditioning
from motionlab.models.moglow.coupling import FrameCoupling
from motionlab.models.moglow.data import CONTROL_DIM, MoGlowFeatures, Scalers
from motionlab.validation import Checked, check_scalar, check_tensor, real

FrameStep = Callable[[int, Tensor, Any], tuple[Tensor, Any]]
"""``step(t, cond_t (B, cond_dim), state) -> (pose_t (B, P), state)``: generated frame ``t`` (0-based)."""


def sampling_setup(
    cfg: Any,
    control: Tensor,
    seed_pose: Tensor,
    temperature: float,
    generator: torch.Generator | None,
    where: str,
) -> Tensor:
    """Checks and the draw shared by the models' ``sample``: the latents ``(B, N, P)``.

    ``cfg`` has ``pose_dim``, ``control_dim`` and ``history``. The latents are the standard-normal draw from
    ``generator`` scaled by the temperature. No history dropout is drawn: it is applied in training only
    (the paper's Fig. 3), and generation always sees the full history.
    """
    temperature = check_temperature(temperature, where)
    history = cfg.history
    check_pose_control(seed_pose, control, cfg.pose_dim, cfg.control_dim, history, where)
    if seed_pose.shape[1] != history or control.shape[1] <= history:
        raise ValueError(
            f"{where}: seed_pose must have H={history} frames and control more than that, "
            f"got {tuple(seed_pose.shape)} and {tuple(control.shape)}"
        )
    batch, frames = control.shape[0], control.shape[1] - history
    return temperature * torch.randn(batch, frames, cfg.pose_dim, generator=generator, dtype=control.dtype)


@torch.no_grad()
def sample_plain(
    model: torch.nn.Module,
    control: Tensor,
    seed_pose: Tensor,
    temperature: float = 1.0,
    generator: torch.Generator | None = None,
) -> Tensor:
    """MoGlow's generation loop, written to be read: poses ``(B, N, P)`` in standard units.

    Args:
        model: a :class:`~motionlab.models.moglow.model.MoGlow`.
        control: ``(B, H + N, C)``: the seed frames' controls, then those of the frames to generate.
        seed_pose: ``(B, H, P)``, the poses that start the history.
        temperature, generator: as for :meth:`MoGlow.sample <motionlab.models.moglow.model.MoGlow.sample>`,
            which draws the same latents and gives the same frames up to float rounding, faster
            (:func:`sample_frames`).
    """
    cfg = model.cfg
    # every frame's latent z_t ~ N(0, temperature**2 I), shape (B, N, P), drawn as MoGlow.sample draws them
    z = sampling_setup(cfg, control, seed_pose, temperature, generator, "sample_plain")
    layers = list(model.flow.layers)  # K steps of (ActNorm, 1x1 convolution, LSTM coupling)
    states = [None] * cfg.steps  # each coupling's LSTM state, carried from frame to frame
    past, poses = seed_pose, []
    for t in range(z.shape[1]):
        # condition on the last H poses (all of them: the history dropout is for training only) and the
        # controls up to frame t
        cond = frame_conditioning(past, control[:, t : t + cfg.history + 1])  # c_t (B, cond_dim)
        features = model.cond_encoder(cond)
        # invert the flow: z_t -> the Glow steps in reverse order -> the linear predictor's residual
        x = z[:, t]
        for k in reversed(range(cfg.steps)):
            actnorm, conv, coupling = layers[3 * k : 3 * k + 3]
            x, states[k] = coupling.inverse_frame(x, features, states[k])
            x = actnorm.inverse(conv.inverse(x[:, :, None]))[:, :, 0]
        pose = model.linear.inverse(x[:, :, None], cond[:, :, None])[:, :, 0]
        poses.append(pose)
        past = torch.cat([past[:, 1:], pose[:, None]], dim=1)  # append: frame t joins the history
    return check_generated(torch.stack(poses, dim=1), "sample_plain")


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


def autoregressive_sample(
    step: FrameStep, control: Tensor, seed_pose: Tensor, state: Any = None, keep: Tensor | None = None
) -> Tensor:
    """Generate frame by frame: ``(B, N, P)`` poses for controls ``(B, H + N, C)`` after ``H`` seed poses.

    Args:
        step: one frame of the model, ``step(t, cond_t, state) -> (pose_t, state)``; its state (the LSTM
            memory) is carried from frame to frame.
        control: controls of the seed frames then of the ``N`` frames to generate (standard units).
        seed_pose: the ``H`` poses ``(B, H, P)`` that start the history (standard units).
        state: the initial state handed to ``step`` (``None``: the model's zero state).
        keep: optional keep flags ``(B, N, H)`` that zero previous poses in the conditioning (``None``,
            the default and what the models' ``sample`` uses: the full history, as in the paper).

    Raises ``ValueError`` naming the first frame when the generated poses stop being finite (a model can
    diverge on inputs far from its training data).
    """
    check_tensor(control, "control", "autoregressive_sample", ndim=3)
    check_tensor(seed_pose, "seed_pose", "autoregressive_sample", ndim=3)
    history = seed_pose.shape[1]
    frames = control.shape[1] - history
    if control.shape[0] != seed_pose.shape[0] or frames < 1:
        raise ValueError(
            f"autoregressive_sample: control must be (B, H + N, C) with N >= 1 for seed_pose (B, H, P) = "
            f"{tuple(seed_pose.shape)}, got {tuple(control.shape)}"
        )
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


def sample_loop(
    invert_frame: Callable[[Tensor, Tensor, Any], tuple[Tensor, Any]],
    control: Tensor,
    seed_pose: Tensor,
    noise: Tensor,
    temperature: float,
) -> Tensor:
    """Chapter 06's exercise loop: poses ``(B, N, P)`` from any one-frame flow inverse.

    Args:
        invert_frame: ``invert_frame(z_t (B, P), cond_t (B, cond_dim), state) -> (pose_t (B, P), state)``,
            the inverse of one frame's flow with its carried state (``None`` at the start).
        control: ``(B, H + N, C)``; seed_pose: ``(B, H, P)`` (standard units).
        noise: standard-normal ``(B, N, P)``, scaled by ``temperature`` to give frame ``t``'s latent.
    """
    check_tensor(noise, "noise", "sample_loop", ndim=3)
    temperature = check_temperature(temperature, "sample_loop")
    return autoregressive_sample(
        lambda t, cond_t, state: invert_frame(temperature * noise[:, t], cond_t, state), control, seed_pose
    )


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
    channels, ``H`` history frames, ``C`` control channels, ``K`` steps, ``U`` LSTM units); a snapshot,
    built again after training.

    The conditioning encoder and the linear predictor read the same vector ``c_t``, so their weights are
    side by side: ``[features | mean] = past @ past_weight + controls @ control_weight + bias`` ``(B, F +
    P)``. ``feature_weight`` ``(F, K * (4U + 2 C_b))`` maps the features to every step's LSTM-gate part
    (``4U``) and output part (``2 C_b``), step after step in inverse order, as in ``steps``. The generated
    pose is ``mean + x * residual_scale``.
    """

    past_weight: Tensor  # (H * P, F + P)
    control_weight: Tensor  # ((H + 1) * C, F + P)
    bias: Tensor  # (F + P,)
    feature_weight: Tensor  # (F, K * (4U + 2 C_b))
    residual_scale: Tensor  # (P,)
    steps: list[InverseStep]


def generate_frames(
    plan: GenerationPlan, control_part: Tensor, past: Tensor, keep: Tensor, noise: Tensor
) -> Tensor:
    """The frame-by-frame loop: poses ``(B, N, P)`` in standard units.

    Args:
        plan: the model's weights (:meth:`motionlab.models.moglow.model.MoGlow.generation_plan`).
        control_part: ``(B, N, F + P)``, the controls' part of ``[features | mean]`` of every frame, bias
        included. past: ``(B, H * P)``, the seed poses, oldest first, flattened.
        keep: ``(B, N, H * P)``, keep flags of every frame's previous poses (all ones when generating from
        the full history), repeated over each pose's channels.
        noise: ``(B, N, P)``, the latents ``z_t`` (temperature applied).
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
    """Raise ``ValueError`` unless the inputs' shapes fit each other and the plan, ``TypeError`` unless they
    share one dtype."""
    if not _shapes_fit(plan, control, seed_pose, keep, noise):
        raise ValueError(
            f"sample_frames: shapes disagree: control {tuple(control.shape)} must be (B, H + N, C), "
            f"seed_pose {tuple(seed_pose.shape)} (B, H, P), noise {tuple(noise.shape)} (B, N, P), keep "
            f"{None if keep is None else tuple(keep.shape)} (B, N, H), with the plan's H * P = "
            f"{plan.past_weight.shape[0]}, P = {plan.residual_scale.shape[0]}, (H + 1) * C = "
            f"{plan.control_weight.shape[0]}"
        )
    if len({x.dtype for x in (control, seed_pose, noise, plan.bias)}) != 1:
        raise TypeError(
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
        control: ``(B, H + N, C)``, the seed frames' controls then those of the frames to generate.
        seed_pose: ``(B, H, P)``.
        keep: optional keep flags ``(B, N, H)`` (1 keep, 0 zero the previous pose), or ``None``: the full
            history, as the models' ``sample`` generates (the paper's history dropout is for training only).
        noise: the latents ``(B, N, P)``.
        scripted: run the TorchScript-compiled loop (``False``: the same function as plain Python).

    Raises ``ValueError`` when the shapes disagree with each other or with the plan, ``TypeError`` when
    the dtypes do.
    """
    _check_inputs(plan, control, seed_pose, keep, noise)
    batch, history, pose_dim = seed_pose.shape
    frames = noise.shape[1]
    windows = control.unfold(1, history + 1, 1).transpose(2, 3).reshape(batch * frames, -1)  # (B N, (H+1) C)
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


class AutoregressiveModel(nn.Module):
    """MoGlow or the Gaussian baseline: a config ``cfg`` with ``history``, ``pose_dim`` and ``control_dim``,
    and :meth:`sample`, which checks a request and draws its latents once (:func:`sampling_setup`) and
    hands them to the model's :meth:`draw`."""

    cfg: Any

    @torch.no_grad()
    def sample(
        self,
        control: Tensor,
        seed_pose: Tensor,
        temperature: float = 1.0,
        generator: torch.Generator | None = None,
    ) -> Tensor:
        """Generate poses ``(B, N, P)`` frame by frame.

        Args:
            control: ``(B, H + N, C)``: the seed frames' controls, then those of the frames to generate.
            seed_pose: ``(B, H, P)``, the poses that start the history.
            temperature: the prior's temperature (MoGlow: 0 gives the zero-latent path, each frame the image
                of the latent mode ``z_t = 0``, which is not the mode of ``p(x_t | past)``; 1 the model's
                distribution).
            generator: draws the latents of all frames (generation never drops history inputs).

        Raises ``ValueError`` on bad inputs (and, for MoGlow, naming the first frame when the generated
        poses stop being finite).
        """
        where = f"{type(self).__name__}.sample"
        return self.draw(
            control, seed_pose, sampling_setup(self.cfg, control, seed_pose, temperature, generator, where)
        )

    def draw(self, control: Tensor, seed_pose: Tensor, latents: Tensor) -> Tensor:
        """Poses ``(B, N, P)`` from checked inputs and the latents ``(B, N, P)`` (each model defines it)."""
        raise NotImplementedError(f"{type(self).__name__} does not define draw")


@dataclass(frozen=True)
class Segment(Checked):
    """A stretch of constant command: ``seconds`` long, ``speed`` forward (m/s), ``turn`` (rad/s, positive
    to the left), ``sideways`` (m/s, positive to the left)."""

    seconds: float = real(above=0)
    speed: float = real()
    turn: float = real(0.0)
    sideways: float = real(0.0)


def control_programme(segments: Sequence[Segment], fps: float = 30.0, ramp: float = 0.5) -> Tensor:
    """Per-frame control ``(T, 3)`` (forward and sideways m/frame, yaw rad/frame) following ``segments``.

    Changes between segments are smoothed by a moving average over ``ramp`` seconds (0: abrupt), as a
    joystick moved by a hand would be.
    """
    if not segments or not all(isinstance(s, Segment) for s in segments):
        raise ValueError(
            f"control_programme: segments must be a non-empty sequence of Segment, got {segments!r}"
        )
    check_scalar(fps, "fps", "control_programme", minimum=0.0, include_minimum=False)
    check_scalar(ramp, "ramp", "control_programme", minimum=0.0)
    rows = [
        torch.tensor([[s.speed, s.sideways, s.turn]], dtype=torch.float64).expand(round(s.seconds * fps), 3)
        for s in segments
    ]
    control = torch.cat(rows) / fps
    width = round(ramp * fps)
    if width > 1:
        padded = torch.cat(
            [control[:1].expand(width // 2, 3), control, control[-1:].expand(width - 1 - width // 2, 3)]
        )
        control = padded.unfold(0, width, 1).mean(dim=-1)
    return control.float()


def splice_controls(pieces: Sequence[Tensor], blend: int = 15) -> Tensor:
    """Join control sequences ``(T_i, 3)`` end to end, cross-fading linearly over ``blend`` frames at each
    joint.

    Recorded controls carry the gait's own rhythm (the pelvis sways and turns a little with every step),
    which a constant command lacks; splicing pieces of recorded control gives realistic commands that
    still change abruptly, such as walk, then stand still, then jog. Each junction takes ``blend`` frames
    from the end of one piece and the start of the next, so the result has ``sum(T_i) - blend * (n - 1)``
    frames.
    """
    if not pieces:
        raise ValueError("splice_controls: pieces must hold at least one control sequence, got none")
    check_scalar(blend, "blend", "splice_controls", kind=numbers.Integral, minimum=0)
    for i, piece in enumerate(pieces):
        check_tensor(piece, f"pieces[{i}]", "splice_controls", finite=False)
    if any(p.dim() != 2 or p.shape[1] != CONTROL_DIM or p.shape[0] <= 2 * blend for p in pieces):
        raise ValueError(
            f"splice_controls: pieces must be (T, {CONTROL_DIM}) with T > 2 * blend = {2 * blend}, got "
            f"{[tuple(p.shape) for p in pieces]}"
        )
    out = pieces[0]
    weight = torch.linspace(0.0, 1.0, blend + 2, dtype=out.dtype)[1:-1, None]
    for piece in pieces[1:]:
        mixed = (1 - weight) * out[-blend:] + weight * piece[:blend] if blend else out[:0]
        out = torch.cat([out[: out.shape[0] - blend], mixed, piece[blend:]])
    return out


def seed_features(
    clips: MoGlowFeatures, indices: Sequence[int], history: int, start: int = 1
) -> MoGlowFeatures:
    """Frames ``start .. start + history - 1`` of the chosen clips ``(B, history, ·)``: a generation seed.

    ``start = 1`` skips frame 0, whose control is undefined.
    """
    check_scalar(history, "history", "seed_features", kind=numbers.Integral, minimum=1)
    check_scalar(start, "start", "seed_features", kind=numbers.Integral, minimum=0)
    if start + history > clips.pose.shape[1]:
        raise ValueError(
            f"seed_features: start + history must be at most the clips' {clips.pose.shape[1]} frames, "
            f"got {start} + {history}"
        )
    index = torch.as_tensor(list(indices), dtype=torch.long)
    return MoGlowFeatures(
        clips.pose[index, start : start + history], clips.control[index, start : start + history]
    )


class GeneratedMotion(NamedTuple):
    """Generated clips: ``pose`` ``(B, T, 64)`` and ``control`` ``(B, T, 3)`` in physical units, and world
    ``positions`` ``(B, T, 22, 3)``. The first ``history`` frames are the seed."""

    pose: Tensor
    control: Tensor
    positions: Tensor


def generate_motion(
    model: AutoregressiveModel,
    scalers: Scalers,
    control: Tensor,
    seed: MoGlowFeatures,
    temperature: float = 1.0,
    generator: torch.Generator | None = None,
) -> GeneratedMotion:
    """Generate ``N`` frames after ``seed`` following ``control``.

    Args:
        model: a trained MoGlow or Gaussian baseline.
        scalers: the standardisers the model was trained with.
        control: ``(B, N, 3)`` in m/frame and rad/frame (for example rows of :func:`control_programme`).
        seed: raw features ``(B, H, ·)`` of the frames that start the history (:func:`seed_features`).
        temperature, generator: as for the model's ``sample``.
    """
    check_tensor(control, "control", "generate_motion", trailing=(CONTROL_DIM,), ndim=3)
    if seed.pose.shape[0] != control.shape[0]:
        raise ValueError(
            f"generate_motion: control must be (B, N, {CONTROL_DIM}) with the seed's batch "
            f"{seed.pose.shape[0]}, got {tuple(control.shape)}"
        )
    all_control = torch.cat([seed.control, control.to(seed.control)], dim=1)
    generated = model.sample(
        scalers.control.transform(all_control), scalers.pose.transform(seed.pose), temperature, generator
    )
    pose = torch.cat([seed.pose, scalers.pose.inverse(generated)], dim=1)
    return GeneratedMotion(pose, all_control, from_moglow(torch.cat([pose, all_control], dim=-1)))
