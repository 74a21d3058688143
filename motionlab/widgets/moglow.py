"""Chapter 06's widget: steer a MoGlow character with speed, turn and temperature sliders.

:func:`steer` is the plain function behind it (unit-tested). A constant command would lack the small
rhythmic sway and turning of the pelvis that every recorded control signal carries, so the sliders
retarget a recorded one instead: the clip of the library whose mean speed is closest to the requested
speed (a standing clip below :data:`STAND_SPEED`) is looped, its forward velocity scaled to the requested
speed and the requested turning rate added to its yaw rate. :func:`show_steering` draws the result.
"""

from __future__ import annotations

import math
import numbers

import matplotlib.pyplot as plt
import torch
from matplotlib.figure import Figure
from torch import Tensor

from motionlab.models.moglow.data import MoGlowFeatures, Scalers
from motionlab.models.moglow.evaluate import support_foot_slide
from motionlab.models.moglow.sampling import (
    AutoregressiveModel,
    GeneratedMotion,
    generate_motion,
    seed_features,
    splice_controls,
)
from motionlab.skeleton import PARENTS
from motionlab.validation import check_scalar
from motionlab.viz import filmstrip, plot_root_paths

FPS = 30

#: Below this speed (m/s) the character is asked to stand: a standing clip's control is used unscaled.
STAND_SPEED = 0.3


def steering_control(library: MoGlowFeatures, speed: float, turn: float, frames: int) -> tuple[Tensor, int]:
    """A control ``(frames, 3)`` for ``speed`` (m/s) and ``turn`` (degrees/s), and the library clip it came
    from.

    ``library`` holds recorded clips in physical units ``(N, T, ·)``; frame 0 of each (no control) is skipped.
    """
    check_scalar(speed, "speed", "steering_control", minimum=0.0)
    check_scalar(turn, "turn", "steering_control")
    check_scalar(frames, "frames", "steering_control", kind=numbers.Integral, minimum=1)
    recorded = library.control[:, 1:]
    mean_speed = recorded[..., 0].mean(dim=1) * FPS
    if speed < STAND_SPEED:
        index = int(mean_speed.abs().argmin())
        control = recorded[index].clone()
    else:
        moving = mean_speed > STAND_SPEED
        forward = torch.where(moving, (mean_speed - speed).abs(), torch.full_like(mean_speed, math.inf))
        index = int(forward.argmin())
        control = recorded[index].clone()
        control[:, 0] *= speed / float(mean_speed[index])
    control[:, 2] += turn * math.pi / 180.0 / FPS
    blend = min(15, control.shape[0] // 3)
    pieces = [control] * max(1, math.ceil(frames / (control.shape[0] - blend)) + 1)
    return splice_controls(pieces, blend)[:frames], index


def steer(
    model: AutoregressiveModel,
    scalers: Scalers,
    library: MoGlowFeatures,
    speed: float,
    turn: float,
    temperature: float,
    seconds: float = 4.0,
    sample_seed: int = 0,
) -> GeneratedMotion:
    """Generate ``seconds`` of motion for ``speed`` (m/s), ``turn`` (degrees/s, positive to the left) and
    ``temperature``, seeded with the first frames of the library clip the control came from.

    ``sample_seed`` seeds the latents: the same values give the same motion.
    """
    check_scalar(seconds, "seconds", "steer", minimum=0.0, include_minimum=False)
    control, index = steering_control(library, speed, turn, round(seconds * FPS))
    seed = seed_features(library, [index], model.cfg.history)
    return generate_motion(
        model, scalers, control[None], seed, temperature, torch.Generator().manual_seed(sample_seed)
    )


def show_steering(
    model: AutoregressiveModel,
    scalers: Scalers,
    library: MoGlowFeatures,
    speed: float,
    turn: float,
    temperature: float,
) -> Figure:
    """Widget callback: :func:`steer`, then the path from above with the toes' trails, and six keyframes."""
    motion = steer(model, scalers, library, speed, turn, temperature)
    positions = motion.positions[0].numpy()
    fig, ax = plt.subplots(figsize=(4.5, 4.0))
    plot_root_paths(
        positions[None],
        ax,
        labels=["pelvis"],
        title=f"{speed:.1f} m/s, {turn:.0f} deg/s, temperature {temperature:.2f}",
    )
    for joint, color, label in ((10, "tab:blue", "left toe"), (11, "tab:red", "right toe")):
        ax.plot(positions[:, joint, 0], positions[:, joint, 1], color=color, lw=0.8, alpha=0.7, label=label)
    ax.legend(fontsize=8)
    ax.set_xlabel(f"support-foot slide {float(support_foot_slide(motion.positions[0])):.2f} m/s")
    plt.show()
    return filmstrip(positions, PARENTS, n_frames=6, fps=FPS, color="tab:orange")
