"""What chapter 06 measures on generated motion: control adherence and long-horizon stability.

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
``|commanded speed - gait speed|``. So this single number captures both failures the MoGlow paper
describes for models trained without autoregressive dropout.

**Joint-speed ratio** (collapse). The mean speed of the root-local joints over the last seconds of a long
sample divided by that over its first seconds. A model that drifts into a frozen mean pose (the classic
failure of autoregressive motion models) gives a ratio near 0; a healthy one stays near 1.
"""

from __future__ import annotations

import torch
from torch import Tensor

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
    if (
        not isinstance(positions, Tensor)
        or positions.dim() < 3
        or positions.shape[-1] != 3
        or positions.shape[-3] < 2
    ):
        shape = tuple(positions.shape) if isinstance(positions, Tensor) else type(positions).__name__
        raise ValueError(f"support_foot_slide: positions must be (..., T >= 2, J, 3), got {shape}")
    if not bool(torch.isfinite(positions).all()):
        raise ValueError("support_foot_slide: positions contain NaN or inf")
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
    if not isinstance(pose, Tensor) or pose.dim() < 2 or pose.shape[-1] != 64 or pose.shape[-2] < 2:
        shape = tuple(pose.shape) if isinstance(pose, Tensor) else type(pose).__name__
        raise ValueError(f"gait_speed: pose must be (..., T >= 2, 64), got {shape}")
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
    if control.shape[:-1] != pose.shape[:-1] or control.shape[-1] != 3:
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
    if not isinstance(pose, Tensor) or pose.dim() < 2 or pose.shape[-1] < 4 or (pose.shape[-1] - 1) % 3:
        shape = tuple(pose.shape) if isinstance(pose, Tensor) else type(pose).__name__
        raise ValueError(f"joint_speed: pose must be (..., T, 1 + 3 * joints), got {shape}")
    joints = pose[..., 1:].unflatten(-1, (-1, 3))
    return (joints[..., 1:, :, :] - joints[..., :-1, :, :]).norm(dim=-1).mean(dim=-1) * fps


def speed_ratio(pose: Tensor, window: int, fps: float = 30.0) -> float:
    """Mean joint speed over the last ``window`` frames divided by that over the first ``window`` frames.

    ``pose`` ``(B, T, 64)`` in metres with ``T >= 2 * window``; speeds are averaged over the batch first.
    """
    if pose.dim() != 3 or window < 2 or pose.shape[1] < 2 * window:
        raise ValueError(
            f"speed_ratio: pose must be (B, T, 64) with T >= 2 * window, got {tuple(pose.shape)} and "
            f"window={window}"
        )
    speed = joint_speed(pose, fps)
    first = speed[:, : window - 1].mean()
    if float(first) <= 0:
        raise ValueError("speed_ratio: the first window does not move, the ratio is undefined")
    return float(speed[:, -(window - 1) :].mean() / first)
