"""What chapter 06 measures on generated motion (control adherence, long-horizon stability) and the test
inputs it measures them on (:func:`control_test`, :func:`long_clips`).

**Control mismatch** (gait speed against commanded speed). The foot that carries the body (the lowest of
the ankles and toes) moves backwards relative to the pelvis at the walking speed the legs produce. From
the pose alone (heading-frame joint positions) this gives the *gait speed*
``g_t = -(x_j(t+1) - x_j(t)) * fps`` with ``j`` the lowest foot joint at ``t`` and ``x`` its forward
coordinate. The mismatch is ``|mean(v_t - g_t)|`` over windows of one second, averaged over windows, with
``v_t`` the commanded forward speed: a character that keeps stepping while told to stand still scores its
walking speed, one whose legs move slower or faster than commanded scores the difference. Averaging
over a window before taking the absolute value cancels frame-to-frame jitter, which is a different
failure (measured by the foot slide below), so the two do not mix.

**Support-foot slide**. At every frame take the lowest of the foot joints (ankles and
toes) -- the foot carrying the body -- and measure its horizontal speed in the world. A gait that matches
the commanded root velocity keeps that foot planted (speed near 0). A character that keeps stepping while
the control says *stand still* drags its support foot backwards at its walking speed, and one whose legs
move slower or faster than the commanded speed slides by the difference: roughly
``|commanded speed - gait speed|``. So this single number captures both the failure the MoGlow paper
reports for models trained without autoregressive dropout (§5.3: stepping while the control says the body
does not move through space) and a gait slower or faster than commanded.

**Joint-speed ratio** (collapse). The mean speed of the root-local joints over the last seconds of a long
sample divided by that over its first seconds. A model that drifts into a frozen mean pose (the classic
failure of autoregressive motion models) gives a ratio near 0; a healthy one stays near 1.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import torch
from torch import Tensor

from motionlab.data.synthetic import load_or_generate
from motionlab.models.moglow.data import MoGlowDataConfig, MoGlowFeatures, Scalers, clip_features
from motionlab.models.moglow.sampling import (
    AutoregressiveModel,
    GeneratedMotion,
    generate_motion,
    seed_features,
    splice_controls,
)
from motionlab.models.motion_cell import smoothing
from motionlab.validation import check_scalar, check_tensor

#: Ankle and toe joints of the default skeleton (left ankle, right ankle, left foot, right foot).
FOOT_JOINTS = (7, 8, 10, 11)


def support_foot_slide(positions: Tensor, fps: float = 30.0, feet: tuple[int, ...] = FOOT_JOINTS) -> Tensor:
    """Mean horizontal speed (m/s) of the lowest foot joint, per clip ``(...,)``.

    Args:
        positions: world joint positions ``(..., T, J, 3)``, metres, z up, ``T >= 2``.
        fps: frames per second.
        feet: the candidate support joints.

    Frame ``t``'s support joint is the lowest of ``feet`` at ``t``; its speed is its displacement from
    ``t`` to ``t + 1`` times ``fps``.
    """
    check_tensor(positions, "positions", "support_foot_slide", trailing=(None, 3), min_leading=1)
    check_scalar(fps, "fps", "support_foot_slide", minimum=0.0, include_minimum=False)
    if positions.shape[-3] < 2:
        raise ValueError(f"support_foot_slide: positions need T >= 2 frames, got {tuple(positions.shape)}")
    foot = positions[..., list(feet), :]  # (..., T, F, 3)
    lowest = foot[..., :-1, :, 2].argmin(dim=-1, keepdim=True)  # (..., T-1, 1)
    step = (foot[..., 1:, :, :2] - foot[..., :-1, :, :2]).norm(dim=-1)  # (..., T-1, F)
    return step.gather(-1, lowest)[..., 0].mean(dim=-1) * fps


def _foot_pose_indices(feet: tuple[int, ...]) -> list[int]:
    """Channels of the feet's heading-frame xyz in a MoGlow pose (channel 0 is the root height)."""
    return [1 + 3 * (j - 1) + k for j in feet for k in range(3)]


def gait_speed(pose: Tensor, fps: float = 30.0, feet: tuple[int, ...] = FOOT_JOINTS) -> Tensor:
    """Speed (m/s) at which the support foot moves backwards relative to the pelvis, ``(..., T-1)``.

    Args:
        pose: MoGlow poses ``(..., T, 64)`` in metres (heading frame: x forward, z up).
        feet: the candidate support joints (default ankles and toes).
    """
    check_tensor(pose, "pose", "gait_speed", trailing=(64,), min_leading=1, finite=False)
    check_scalar(fps, "fps", "gait_speed", minimum=0.0, include_minimum=False)
    if pose.shape[-2] < 2:
        raise ValueError(f"gait_speed: pose needs T >= 2 frames, got {tuple(pose.shape)}")
    foot = pose[..., _foot_pose_indices(feet)].unflatten(-1, (len(feet), 3))  # (..., T, F, 3)
    lowest = foot[..., :-1, :, 2].argmin(dim=-1, keepdim=True)
    backward = -(foot[..., 1:, :, 0] - foot[..., :-1, :, 0]) * fps
    return backward.gather(-1, lowest)[..., 0]


def control_mismatch(pose: Tensor, control: Tensor, fps: float = 30.0, window: int = 30) -> Tensor:
    """Mean over windows of ``|mean(commanded speed - gait speed)|`` (m/s), per clip ``(...,)``.

    Args:
        pose: MoGlow poses ``(..., T, 64)`` in metres.
        control: the commands of the same frames ``(..., T, 3)`` (m/frame); frame ``t + 1``'s forward
            velocity is the command for the step ``t -> t + 1``.
        window: frames per window (the last incomplete window is dropped).
    """
    check_tensor(control, "control", "control_mismatch", trailing=(3,), min_leading=1, finite=False)
    check_scalar(window, "window", "control_mismatch", kind=numbers.Integral, minimum=1)
    if control.shape[:-1] != pose.shape[:-1]:
        raise ValueError(
            f"control_mismatch: control must be (..., T, 3) with the pose's (..., T), got "
            f"{tuple(control.shape)} and {tuple(pose.shape)}"
        )
    difference = control[..., 1:, 0] * fps - gait_speed(pose, fps)
    n_windows = difference.shape[-1] // window
    if n_windows < 1:
        raise ValueError(f"control_mismatch: needs at least {window + 1} frames, got {pose.shape[-2]}")
    per_window = difference[..., : n_windows * window].unflatten(-1, (n_windows, window)).mean(dim=-1)
    return per_window.abs().mean(dim=-1)


def joint_speed(pose: Tensor, fps: float = 30.0) -> Tensor:
    """Mean speed (m/s) of the root-local joints per frame step ``(..., T-1)`` from MoGlow poses ``(..., T,
    64)``.

    The 21 non-root joints' xyz in the heading frame (channels 1..63); the root height is left out.
    """
    check_tensor(pose, "pose", "joint_speed", min_leading=2, finite=False)
    check_scalar(fps, "fps", "joint_speed", minimum=0.0, include_minimum=False)
    if pose.shape[-1] < 4 or (pose.shape[-1] - 1) % 3:
        raise ValueError(f"joint_speed: pose must be (..., T, 1 + 3 * joints), got {tuple(pose.shape)}")
    joints = pose[..., 1:].unflatten(-1, (-1, 3))
    return (joints[..., 1:, :, :] - joints[..., :-1, :, :]).norm(dim=-1).mean(dim=-1) * fps


def speed_ratio(pose: Tensor, window: int, fps: float = 30.0) -> float:
    """Mean joint speed over the last ``window`` frames divided by that over the first ``window`` frames.

    ``pose`` ``(B, T, 64)`` in metres with ``T >= 2 * window``; speeds are averaged over the batch first.
    """
    check_tensor(pose, "pose", "speed_ratio", ndim=3, finite=False)
    check_scalar(window, "window", "speed_ratio", kind=numbers.Integral, minimum=2)
    if pose.shape[1] < 2 * window:
        raise ValueError(
            f"speed_ratio: pose must be (B, T, 64) with T >= 2 * window, got {tuple(pose.shape)} and "
            f"window={window}"
        )
    speed = joint_speed(pose, fps)
    first = speed[:, : window - 1].mean()
    if float(first) <= 0:
        raise ValueError("speed_ratio: the first window does not move, the ratio is undefined")
    return float(speed[:, -(window - 1) :].mean() / first)


def moving_average(series: Tensor, width: int) -> Tensor:
    """Centred moving average ``(T,)`` of a series ``(T,)`` over ``width`` frames, the end values repeated
    (the chapter's curves of speed over time use one second, ``width = fps + 1``)."""
    check_tensor(series, "series", "moving_average", ndim=1)
    check_scalar(width, "width", "moving_average", kind=numbers.Integral, minimum=1)
    return smoothing.moving_average(series.view(1, -1, 1), width).view(-1)


class ControlTest(NamedTuple):
    """Spliced command sequences ``control`` ``(N, T, 3)`` (m/frame, rad/frame), the seeds that start them,
    and the frame ranges of the pieces (walk, stand, jog, stand) within ``control``."""

    control: Tensor
    seed: MoGlowFeatures
    pieces: tuple[tuple[int, int], ...]


def control_test(
    clips: MoGlowFeatures,
    action: np.ndarray,
    action_names: Sequence[str],
    n: int,
    history: int,
    piece_seconds: float = 3.0,
    blend: int = 15,
    fps: int = 30,
) -> ControlTest:
    """``n`` commands spliced from held-out recorded controls: walk, stand (a wave clip), jog, stand.

    Args:
        clips: raw features of held-out clips ``(M, T, ·)`` (e.g. ``clip_features(test, cfg.data,
            augment=False)`` with ``cfg`` the :class:`~.experiment.ExperimentConfig`).
        action: the action id of each clip ``(M,)``; ``action_names`` maps ids to names.
        n: how many commands (clip ``k * count // n`` of each action for command ``k``).
        history: frames of the seed (taken from the walk clip, right before its piece of control).
        piece_seconds: seconds of each piece; ``blend`` frames of cross-fade at each junction.
    """
    check_scalar(n, "n", "control_test", kind=numbers.Integral, minimum=1)
    check_scalar(history, "history", "control_test", kind=numbers.Integral, minimum=1)
    check_scalar(piece_seconds, "piece_seconds", "control_test", minimum=0.0, include_minimum=False)
    names = [str(a) for a in action_names]
    by_action = {
        name: np.flatnonzero(np.asarray(action) == names.index(name)) for name in ("walk", "jog", "wave")
    }
    if any(len(ids) == 0 for ids in by_action.values()):
        raise ValueError(
            f"control_test: needs walk, jog and wave clips, got counts "
            f"{ {k: len(v) for k, v in by_action.items()} }"
        )
    length = round(piece_seconds * fps)
    first = 1 + history
    if clips.control.shape[1] < first + length:
        raise ValueError(
            f"control_test: clips of {clips.control.shape[1]} frames are too short for {piece_seconds} s "
            f"pieces after {first} frames"
        )
    commands, seeds = [], []
    for k in range(n):
        walk, jog, wave = (int(by_action[a][k * len(by_action[a]) // n]) for a in ("walk", "jog", "wave"))
        pieces = [clips.control[i, first : first + length] for i in (walk, wave, jog, wave)]
        commands.append(splice_controls(pieces, blend))
        seeds.append(walk)
    step = length - blend
    bounds = tuple((i * step, i * step + step) for i in range(4))
    return ControlTest(torch.stack(commands), seed_features(clips, seeds, history), bounds)


class CommandRun(NamedTuple):
    """A model's run of the control test, seed frames left out: the ``mismatch`` per command ``(N,)`` (m/s),
    the legs' ``gait`` speed ``(N, T - 1)`` (m/s), and the generated ``motion`` (seed frames included)."""

    mismatch: Tensor
    gait: Tensor
    motion: GeneratedMotion


def run_control_test(
    model: AutoregressiveModel, scalers: Scalers, commands: ControlTest, temperature: float, seed: int = 0
) -> CommandRun:
    """Generate every command of ``commands`` from its seed frames at ``temperature`` (latents drawn from
    ``seed``) and measure :func:`control_mismatch` and :func:`gait_speed` on the generated frames.

    Raises ``ValueError`` when the generation diverges (:func:`~.sampling.generate_motion`)."""
    motion = generate_motion(
        model, scalers, commands.control, commands.seed, temperature, torch.Generator().manual_seed(seed)
    )
    history = commands.seed.pose.shape[1]
    pose, control = motion.pose[:, history:], motion.control[:, history:]
    return CommandRun(control_mismatch(pose, control), gait_speed(pose), motion)


def long_clips(n_per_mode: int, seconds: float, seed: int) -> MoGlowFeatures:
    """Raw features of held-out walk and jog clips of ``seconds`` (the stability test's, generated once from
    ``seed`` and cached under ``build/data``)."""
    check_scalar(n_per_mode, "n_per_mode", "long_clips", kind=numbers.Integral, minimum=1)
    check_scalar(seconds, "seconds", "long_clips", minimum=0.0, include_minimum=False)
    check_scalar(seed, "seed", "long_clips", kind=numbers.Integral, minimum=0)
    data = load_or_generate(seed, n_per_mode, seconds=seconds, split="test")
    return clip_features(
        data, MoGlowDataConfig(actions=("walk", "jog"), mirror=False, reverse_time=False), augment=False
    )
