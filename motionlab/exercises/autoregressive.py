"""Chapter 06's exercises: MoGlow's history dropout, checked against
:func:`motionlab.models.moglow.conditioning.history_keep_mask`, and its autoregressive sampling loop, checked
against the package's loop :func:`motionlab.models.moglow.sampling.sample_loop` with a small
stand-in for the flow's inverse.

The reader's loop receives ``invert_frame(z_t, cond_t, state) -> (pose_t, state)``, the one-frame inverse
of a MoGlow (the Glow steps undone in reverse order, as in :func:`~motionlab.models.moglow.sampling.
sample_plain`). The checker hands it a recording stand-in, so it can say at which frame and in which
part (latent, conditioning, carried state, output) the reader's loop departs from the right one.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import torch

from motionlab.exercises.checking import CheckResult, Diagnosis, as_result, checker, close
from motionlab.models.moglow.conditioning import history_keep_mask
from motionlab.models.moglow.sampling import sample_loop

InvertFrame = Callable[[torch.Tensor, torch.Tensor, Any], tuple[torch.Tensor, Any]]
KeepMask = Callable[[int, int, int, float, torch.Generator, bool], torch.Tensor]
SampleLoop = Callable[[InvertFrame, torch.Tensor, torch.Tensor, torch.Tensor, float], torch.Tensor]

BATCH, HISTORY, POSE, CONTROL, FRAMES, TEMPERATURE = 2, 3, 4, 2, 6, 0.7


class _Stop(Exception):
    """Raised by the stand-in when a call cannot go on; the checker first looks at the calls before it."""


@dataclass(frozen=True, eq=False)
class _State:
    """The stand-in's memory after a frame (compared by identity: it must be handed back unchanged)."""

    hidden: torch.Tensor


@dataclass
class _Frame:
    """A recording stand-in for a MoGlow frame inverse: a small fixed nonlinear map of ``(z_t, c_t, h)``."""

    z_weight: torch.Tensor
    cond_weight: torch.Tensor
    memory_weight: torch.Tensor
    calls: list[tuple[torch.Tensor, torch.Tensor, Any]] = field(default_factory=list)
    returned: list[_State] = field(default_factory=list)

    @classmethod
    def new(cls, seed: int) -> _Frame:
        generator = torch.Generator().manual_seed(seed)
        cond_dim = HISTORY * POSE + (HISTORY + 1) * CONTROL

        def draw(*shape: int) -> torch.Tensor:
            return torch.randn(*shape, generator=generator, dtype=torch.float64) / shape[0] ** 0.5

        return cls(draw(POSE, POSE), draw(cond_dim, POSE), draw(cond_dim, POSE))

    def __call__(self, z_t: torch.Tensor, cond_t: torch.Tensor, state: Any) -> tuple[torch.Tensor, _State]:
        self.calls.append((z_t, cond_t, state))
        z_t, cond_t = as_result(z_t, "z_t"), as_result(cond_t, "cond_t")
        if cond_t.dim() != 2 or cond_t.shape[1] != self.cond_weight.shape[0]:
            raise _Stop(
                f"frame {len(self.calls) - 1}: cond_t should be (B, H * P + (H + 1) * C) = "
                f"({BATCH}, {self.cond_weight.shape[0]}), got {tuple(cond_t.shape)}"
            )
        hidden = state.hidden if isinstance(state, _State) else torch.zeros(z_t.shape[0], POSE).to(z_t)
        hidden = torch.tanh(cond_t.to(z_t) @ self.memory_weight + 0.5 * hidden)
        pose = torch.tanh(z_t @ self.z_weight + cond_t.to(z_t) @ self.cond_weight + hidden)
        self.returned.append(_State(hidden))
        return pose, self.returned[-1]


def _inputs(seed: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    generator = torch.Generator().manual_seed(seed)
    control = torch.randn(BATCH, HISTORY + FRAMES, CONTROL, generator=generator, dtype=torch.float64)
    seed_pose = torch.randn(BATCH, HISTORY, POSE, generator=generator, dtype=torch.float64)
    noise = torch.randn(BATCH, FRAMES, POSE, generator=generator, dtype=torch.float64)
    return control, seed_pose, noise


def _reference(
    control: torch.Tensor, seed_pose: torch.Tensor, noise: torch.Tensor, temperature: float
) -> tuple[torch.Tensor, _Frame]:
    """The right loop's poses ``(B, N, P)``, and the stand-in that recorded its calls."""
    frame = _Frame.new(0)
    return sample_loop(frame, control, seed_pose, noise, temperature), frame


def _history_problem(got: torch.Tensor, want: torch.Tensor, seed_part: torch.Tensor, t: int) -> str:
    """What is wrong with the past-pose part ``(B, H * P)`` of ``c_t``."""
    as_frames = want.view(BATCH, HISTORY, POSE)
    if t > 0 and close(got, seed_part):
        return (
            f"frame {t} is conditioned on the seed poses again: update the history after each frame "
            "(drop the oldest pose, append the new one)"
        )
    if close(got, as_frames.flip(1).flatten(1)):
        return "the history is in the wrong order: oldest first, past[:, -1] is the pose of frame t - 1"
    if close(got, as_frames.transpose(1, 2).flatten(1)):
        return "flatten the history frame by frame: past (B, H, P).flatten(1), not its transpose"
    if bool(((got == 0) & (want != 0)).any()):
        return (
            "some previous poses are zeroed: the history dropout is for training only; generation sees "
            "all H previous poses"
        )
    return f"the previous-pose part of c_t is wrong at frame {t}: the last H generated (or seed) poses"


def _control_problem(got: torch.Tensor, control: torch.Tensor, t: int) -> str:
    """What is wrong with the control part ``(B, (H + 1) * C)`` of ``c_t``."""
    right = control[:, t : t + HISTORY + 1]
    if close(got, right.flip(1).flatten(1)):
        return "the control window is in the wrong order: oldest first, the current control last"
    for start in range(control.shape[1] - HISTORY):
        if start != t and close(got, control[:, start : start + HISTORY + 1].flatten(1)):
            return (
                f"frame {t} read the controls from frame {start} on: generated frame t has index H + t, so "
                "its window is control[:, t : t + history + 1] (the H previous controls and the current one)"
            )
    return f"the control part of c_t is wrong at frame {t}: control[:, t : t + history + 1], flattened"


def _latent_problem(got: torch.Tensor, noise: torch.Tensor, temperature: float, t: int) -> str | None:
    if close(got, temperature * noise[:, t]):
        return None
    if close(got, noise[:, t]):
        return "the latent is not scaled: z_t = temperature * noise[:, t]"
    if got.shape == noise[:, t].shape and any(
        close(got, temperature * noise[:, s]) for s in range(noise.shape[1])
    ):
        return f"frame {t} used another frame's latent: z_t = temperature * noise[:, t]"
    return f"z_t is wrong at frame {t}: temperature * noise[:, t], shape (B, P)"


def _follow_the_calls(fn: SampleLoop) -> None:
    """Replay the reader's loop against the right one, call by call."""
    control, seed_pose, noise = _inputs(1)
    want, reference = _reference(control, seed_pose, noise, TEMPERATURE)
    frame = _Frame.new(0)
    try:
        out, stopped = fn(frame, control, seed_pose, noise, TEMPERATURE), None
    except _Stop as stop:
        out, stopped = None, str(stop)
        frame.calls.pop()
    if stopped is None and len(frame.calls) != FRAMES:
        raise Diagnosis(
            f"invert_frame should be called once per generated frame, {FRAMES} times for control "
            f"(B, H + {FRAMES}, C), got {len(frame.calls)} calls"
        )
    seed_part = seed_pose.flatten(1)
    for t, ((z_t, cond_t, state), (_, want_cond, _)) in enumerate(zip(frame.calls, reference.calls)):
        if t == 0 and state is not None:
            raise Diagnosis("the first frame starts from the model's zero state: pass state=None")
        if t > 0 and state is not frame.returned[t - 1]:
            raise Diagnosis(
                f"frame {t} did not get the state returned by frame {t - 1}: carry the LSTM state from "
                "one frame to the next"
            )
        problem = _latent_problem(as_result(z_t, "z_t"), noise, TEMPERATURE, t)
        if problem is not None:
            raise Diagnosis(problem)
        if close(cond_t, want_cond):
            continue
        past_dim = HISTORY * POSE
        if not close(cond_t[:, :past_dim], want_cond[:, :past_dim]):
            raise Diagnosis(_history_problem(cond_t[:, :past_dim], want_cond[:, :past_dim], seed_part, t))
        raise Diagnosis(_control_problem(cond_t[:, past_dim:], control, t))
    if stopped is not None:
        raise Diagnosis(stopped)
    _output_is_the_poses(as_result(out, "the loop"), want)


def _output_is_the_poses(got: torch.Tensor, want: torch.Tensor) -> None:
    if close(got, want):
        return
    if close(got, want.transpose(0, 1)):
        raise Diagnosis(
            f"stack the poses along dim 1: (B, N, P) = {tuple(want.shape)}, got {tuple(got.shape)}"
        )
    if got.shape != want.shape:
        raise Diagnosis(f"return the generated poses (B, N, P) = {tuple(want.shape)}, got {tuple(got.shape)}")
    raise Diagnosis("return the poses invert_frame gave, frame after frame (not the seed, not the latents)")


def _other_sizes(fn: SampleLoop) -> None:
    """One generated frame and a zero temperature: no constants from the first test left in the loop."""
    control, seed_pose, noise = _inputs(2)
    control, noise = control[:, : HISTORY + 1], noise[:, :1]
    want, _ = _reference(control, seed_pose, noise, 0.0)
    got = as_result(fn(_Frame.new(0), control, seed_pose, noise, 0.0), "the loop")
    if not close(got, want):
        raise Diagnosis(
            "wrong for one generated frame at temperature 0: take N = control.shape[1] - history, with "
            "history = seed_pose.shape[1], and the temperature from the arguments"
        )


@checker(
    [_follow_the_calls, _other_sizes],
    "conditions each frame on the last H poses and the current control window, scales the latent by "
    "the temperature, carries the state and appends each pose to the history",
)
def check_sample_loop(fn: SampleLoop) -> CheckResult:
    """Check ``fn(invert_frame, control, seed_pose, noise, temperature) -> (B, N, P)``: MoGlow's frame-by-
    frame generation with ``control (B, H + N, C)``, ``seed_pose (B, H, P)``, ``noise (B, N, P)``."""


def _keep_mask_reference(batch: int, frames: int, history: int, dropout: float, seed: int) -> torch.Tensor:
    generator = torch.Generator().manual_seed(seed)
    return history_keep_mask(batch, frames, history, dropout, generator, rescale=True)


def _keep_mask_call(fn: KeepMask, shape: tuple[int, int, int], dropout: float, seed: int, training: bool):
    got = as_result(fn(*shape, dropout, torch.Generator().manual_seed(seed), training), "my_keep_mask")
    if tuple(got.shape) != shape:
        raise Diagnosis(
            f"the keep flags should be (batch, frames, history) = {shape}, got {tuple(got.shape)}"
        )
    return got.to(torch.float32)


def _keep_mask_training(fn: KeepMask) -> None:
    shape, dropout = (64, 40, 5), 0.6
    got = _keep_mask_call(fn, shape, dropout, 0, True)
    want = _keep_mask_reference(*shape, dropout, 0)
    if close(got, want, 1e-6):
        return
    kept = want > 0
    if close(got, kept.float(), 1e-6):
        raise Diagnosis(
            "the kept poses are not rescaled: multiply them by 1 / (1 - p) (inverted dropout) so that a "
            "linear map of the history keeps its expectation"
        )
    if close(got, kept.float() * (1 - dropout), 1e-6):
        raise Diagnosis("the kept poses are multiplied by 1 - p: divide by it instead, 1 / (1 - p)")
    flipped = (~kept).float() / (1 - dropout)
    if close(got, flipped, 1e-6) or close(got, (~kept).float() / dropout, 1e-6):
        raise Diagnosis(
            "you keep a pose with probability p: p is the probability of *dropping* it, keep = (u >= p)"
        )
    again = _keep_mask_call(fn, shape, dropout, 0, True)
    if not close(got, again, 1e-6):
        raise Diagnosis("two calls with the same seed differ: draw the uniforms with generator=generator")
    values = set(got.unique().tolist())
    if values <= {0.0, 1 / (1 - dropout)} or values <= {0.0, 1.0}:
        raise Diagnosis(
            "the flags are not the package's draw: u = torch.rand(batch, frames, history, "
            "generator=generator), one uniform per sequence, frame and lag, kept where u >= p"
        )
    raise Diagnosis(
        "the keep flags are wrong: (u >= p) / (1 - p) with u uniform, shape (batch, frames, history)"
    )


def _keep_mask_generation_and_edges(fn: KeepMask) -> None:
    shape = (3, 7, 4)
    got = _keep_mask_call(fn, shape, 0.95, 1, False)
    if not close(got, torch.ones(shape), 1e-6):
        raise Diagnosis(
            "with training=False every flag should be 1: the history dropout is for training only, "
            "generation and the held-out likelihood see the whole history"
        )
    for dropout in (0.0, 1.0):
        try:
            got = _keep_mask_call(fn, shape, dropout, 2, True)
        except ZeroDivisionError:
            got = torch.full(shape, math.inf)
        if not torch.isfinite(got).all():
            raise Diagnosis(
                f"p = {dropout:g} gives NaN or inf (a division by 1 - p = 0): with p = 1 every pose is "
                "dropped, all flags 0; rescale only when p < 1"
            )
        if not close(got, _keep_mask_reference(*shape, dropout, 2), 1e-6):
            raise Diagnosis(f"p = {dropout:g} should give all flags {1 - dropout:g}, got other values")


@checker(
    [_keep_mask_training, _keep_mask_generation_and_edges],
    "matches history_keep_mask(..., rescale=True) in training, keeps everything at generation, and "
    "handles p = 0 and p = 1",
)
def check_keep_mask(fn: KeepMask) -> CheckResult:
    """Check ``fn(batch, frames, history, dropout, generator, training) -> keep (batch, frames, history)``:
    MoGlow's history dropout with kept poses rescaled by ``1 / (1 - dropout)``, all ones when not training."""
