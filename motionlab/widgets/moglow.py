"""Chapter 06's widget: steer a MoGlow character with speed, turn and temperature sliders.

:func:`steer` is the plain function behind it (unit-tested). A constant command would lack the small
rhythmic sway and turning of the pelvis that every recorded control signal carries, so the sliders
retarget a recorded one instead: the clip of the library whose mean speed is closest to the requested
speed (a standing clip below :data:`STAND_SPEED`) is looped, its forward velocity scaled to the requested
speed and the requested turning rate added to its yaw rate. :func:`show_steering` draws the result.

The same widget steers chapter 06's synthetic character and chapter 10's real CMU one: a :class:`Character`
says what differs (frame rate, skeleton, which joints are the toes and the feet).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import matplotlib.pyplot as plt
import torch
from matplotlib.figure import Figure
from torch import Tensor

from motionlab.models.moglow.data import MoGlowFeatures, Scalers
from motionlab.models.moglow.evaluate import FOOT_JOINTS, support_foot_slide
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

#: Below this speed (m/s) the character is asked to stand: a standing clip's control is used unscaled.
STAND_SPEED = 0.3


@dataclass(frozen=True)
class Character:
    """What the widget needs to know of a skeleton and its data.

    Attributes:
        fps: frames per second of the model's data.
        parents: parent index of each joint (for the keyframes).
        toes: the left and right toe joints (their trails are drawn).
        feet: the candidate support joints of the foot-slide measure.
    """

    fps: float = 30.0
    parents: tuple[int, ...] = tuple(PARENTS)
    toes: tuple[int, int] = (10, 11)
    feet: tuple[int, ...] = FOOT_JOINTS


#: Chapter 06's synthetic character (the course's 22-joint skeleton at 30 fps).
SYNTHETIC = Character()


def steering_control(
    library: MoGlowFeatures, speed: float, turn: float, frames: int, fps: float = SYNTHETIC.fps
) -> tuple[Tensor, int]:
    """A control ``(frames, 3)`` for ``speed`` (m/s) and ``turn`` (degrees/s), and the library clip it came
    from (controls are per frame at ``fps``).

    ``library`` holds recorded clips in physical units ``(N, T, ·)``; frame 0 of each (no control) is skipped.
    """
    check_scalar(speed, "speed", "steering_control", minimum=0.0)
    check_scalar(turn, "turn", "steering_control")
    check_scalar(frames, "frames", "steering_control", kind=numbers.Integral, minimum=1)
    check_scalar(fps, "fps", "steering_control", minimum=0.0, include_minimum=False)
    recorded = library.control[:, 1:]
    mean_speed = recorded[..., 0].mean(dim=1) * fps
    if speed < STAND_SPEED:
        index = int(mean_speed.abs().argmin())
        control = recorded[index].clone()
    else:
        moving = mean_speed > STAND_SPEED
        forward = torch.where(moving, (mean_speed - speed).abs(), torch.full_like(mean_speed, math.inf))
        index = int(forward.argmin())
        control = recorded[index].clone()
        control[:, 0] *= speed / float(mean_speed[index])
    control[:, 2] += turn * math.pi / 180.0 / fps
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
    fps: float = SYNTHETIC.fps,
) -> GeneratedMotion:
    """Generate ``seconds`` of motion for ``speed`` (m/s), ``turn`` (degrees/s, positive to the left) and
    ``temperature``, seeded with the first frames of the library clip the control came from.

    ``sample_seed`` seeds the latents: the same values give the same motion; ``fps`` is the data's frame rate.
    """
    check_scalar(seconds, "seconds", "steer", minimum=0.0, include_minimum=False)
    control, index = steering_control(library, speed, turn, round(seconds * fps), fps)
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
    character: Character = SYNTHETIC,
) -> Figure:
    """Widget callback: :func:`steer`, then the path from above with the toes' trails, and six keyframes of
    ``character`` (chapter 06's synthetic one by default)."""
    motion = steer(model, scalers, library, speed, turn, temperature, fps=character.fps)
    positions = motion.positions[0].numpy()
    fig, ax = plt.subplots(figsize=(4.5, 4.0))
    plot_root_paths(
        positions[None],
        ax,
        labels=["pelvis"],
        title=f"{speed:.1f} m/s, {turn:.0f} deg/s, temperature {temperature:.2f}",
    )
    left, right = character.toes
    for joint, color, label in ((left, "tab:blue", "left toe"), (right, "tab:red", "right toe")):
        ax.plot(positions[:, joint, 0], positions[:, joint, 1], color=color, lw=0.8, alpha=0.7, label=label)
    ax.legend(fontsize=8)
    slide = float(support_foot_slide(motion.positions[0], character.fps, character.feet))
    ax.set_xlabel(f"support-foot slide {slide:.2f} m/s")
    plt.show()
    return filmstrip(positions, list(character.parents), n_frames=6, fps=character.fps, color="tab:orange")
