"""Visualisation timings: seconds to render a 4-second clip (120 frames at 30 fps, 22 joints) to an
HTML player with ``FuncAnimation.to_jshtml``, alone and as a real-vs-generated side-by-side pair.

The clip is a stick figure swinging its legs and arms while walking along +x (a sine gait built
with forward kinematics), so the timing includes drawing a moving figure on a floor grid.
"""

from __future__ import annotations

import math

import torch

from motionlab import config, skeleton
from motionlab.bench._timing import best_seconds
from motionlab.geometry import axis_angle_to_quat
from motionlab.viz import animate, compare_animation

REPEATS = 3
FPS = 30
FRAMES = 4 * FPS


def sine_gait(frames: int = FRAMES, fps: int = FPS, phase: float = 0.0) -> torch.Tensor:
    """``(frames, 22, 3)`` joint positions: hips and shoulders swinging at 1 Hz, walking 1.2 m/s along +x."""
    t = torch.arange(frames, dtype=torch.float64) / fps
    swing = 0.5 * torch.sin(2 * math.pi * t + phase)
    axis_angles = torch.zeros(frames, 22, 3, dtype=torch.float64)
    joint = skeleton.JOINT
    for side, sign in (("left", 1.0), ("right", -1.0)):
        axis_angles[:, joint[f"{side}_hip"], 1] = sign * swing  # legs swing about the y (left) axis
        axis_angles[:, joint[f"{side}_knee"], 1] = 0.4 * (1 + sign * torch.cos(2 * math.pi * t + phase))
        axis_angles[:, joint[f"{side}_shoulder"], 1] = -sign * swing
    root = torch.stack([1.2 * t, torch.zeros_like(t), torch.full_like(t, 0.95)], dim=-1)
    offsets = torch.tensor(skeleton.average_skeleton().offsets)
    return skeleton.forward_kinematics(axis_angle_to_quat(axis_angles), root, offsets, skeleton.PARENTS)[0]


def render_timings() -> dict:
    config.set_threads()
    real, generated = sine_gait(), sine_gait(phase=1.0)
    return {
        "animate_4s_clip_seconds": best_seconds(lambda: animate(real, skeleton.PARENTS, fps=FPS), REPEATS),
        "compare_animation_4s_clip_seconds": best_seconds(
            lambda: compare_animation(real, generated, skeleton.PARENTS, fps=FPS), REPEATS
        ),
        "frames": FRAMES,
    }
