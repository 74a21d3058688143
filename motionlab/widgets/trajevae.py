"""Chapter 07 widget: tick which joints' trajectories are given, pick the number of samples and the
temperature, optionally bend a given trajectory, and watch the completions.

The callback :func:`complete_window` is a plain function (unit-tested); :func:`completion_widget` wires it to
ipywidgets and animates the result with :func:`motionlab.viz.animate`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import ipywidgets as widgets
import torch
from IPython.display import display
from torch import Tensor

from motionlab.models.trajevae.data import completion_task
from motionlab.models.trajevae.evaluate import Completer
from motionlab.models.trajevae.masks import PAPER_ORDER, channel_mask, joint_mask
from motionlab.skeleton import JOINT, PARENTS
from motionlab.validation import check_tensor
from motionlab.viz import animate

#: Joints offered as tick boxes: the paper's four end effectors, the head and the pelvis.
CONTROL_JOINTS: tuple[str, ...] = PAPER_ORDER + ("head", "pelvis")


class Completion(NamedTuple):
    """What the widget shows: ``samples`` ``(K, T, J, 3)``, the requested ``trajectories`` ``(T - 1, J, 3)``
    (zeros for joints to complete) and the ``mask`` ``(J,)`` of given joints."""

    samples: Tensor
    trajectories: Tensor
    mask: Tensor


def left_direction(pose: Tensor) -> Tensor:
    """The character's left in the floor plane ``(3,)`` (unit, z = 0): from the right hip to the left hip of
    ``pose`` ``(J * 3,)``."""
    check_tensor(pose, "pose", "left_direction", ndim=1)
    joints = pose.reshape(-1, 3)
    across = joints[JOINT["left_hip"]] - joints[JOINT["right_hip"]]
    across = torch.cat([across[:2], across.new_zeros(1)])
    norm = across.norm()
    if float(norm) < 1e-6:
        raise ValueError("left_direction: the hips coincide, so the pose has no left")
    return across / norm


def bend_trajectory(trajectories: Tensor, joint: str, amount: float, left: Tensor) -> Tensor:
    """Bend one joint's trajectory sideways: frame ``t`` of ``F`` moves by ``amount * (t / F)²`` metres along
    ``left``.

    Args:
        trajectories: ``(F, J * 3)``; joint: the joint's name; amount: metres at the last frame (negative
            bends to the right); left: the direction ``(3,)``, e.g. :func:`left_direction` of the initial
            pose.

    Returns:
        A new ``(F, J * 3)`` tensor; only the joint's three channels change.
    """
    check_tensor(trajectories, "trajectories", "bend_trajectory", ndim=2)
    if joint not in JOINT:
        raise ValueError(f"bend_trajectory: unknown joint {joint!r}")
    n_frames = trajectories.shape[0]
    ramp = (torch.arange(1, n_frames + 1, dtype=trajectories.dtype) / n_frames) ** 2
    bent = trajectories.clone()
    index = 3 * JOINT[joint]
    bent[:, index : index + 3] += float(amount) * ramp[:, None] * left.to(trajectories.dtype)
    return bent


def complete_window(
    model: Completer,
    window: Tensor,
    given: Sequence[str],
    n_samples: int,
    temperature: float,
    bend_joint: str | None = None,
    bend: float = 0.0,
    seed: int = 0,
) -> Completion:
    """The widget's callback: complete one window ``(T, J * 3)`` from its initial pose and the ``given``
    joints.

    ``bend_joint`` (one of ``given``) has its trajectory bent sideways by ``bend`` metres (see
    :func:`bend_trajectory`) before the model sees it. ``seed`` fixes the samples.
    """
    check_tensor(window, "window", "complete_window", ndim=2)
    mask = joint_mask(given, window.shape[-1] // 3)
    initial_pose, trajectories = completion_task(window[None], mask)
    if bend_joint is not None and bend != 0.0:
        if bend_joint not in given:
            raise ValueError(
                f"complete_window: can only bend a given joint; {bend_joint!r} is not in {list(given)}"
            )
        trajectories = bend_trajectory(trajectories[0], bend_joint, bend, left_direction(initial_pose[0]))[
            None
        ]
    future = model.sample(
        initial_pose, trajectories, n_samples, temperature, torch.Generator().manual_seed(seed)
    )[0]
    samples = torch.cat([initial_pose.expand(n_samples, 1, -1), future], dim=1)
    trajectories = trajectories[0] * channel_mask(mask).to(trajectories.dtype)
    return Completion(samples.unflatten(-1, (-1, 3)), trajectories.unflatten(-1, (-1, 3)), mask)


def completion_widget(model: Completer, windows: Tensor, fps: float, step: int = 2) -> widgets.VBox:
    """Controls plus an animation of the completions of ``windows`` ``(N, T, J * 3)`` (rendered once on
    creation)."""
    window_index = widgets.IntSlider(
        0, 0, windows.shape[0] - 1, description="test window", continuous_update=False
    )
    ticks = {
        name: widgets.Checkbox(value=name in PAPER_ORDER[:2], description=name, indent=False)
        for name in CONTROL_JOINTS
    }
    n_samples = widgets.IntSlider(4, 1, 10, description="samples", continuous_update=False)
    temperature = widgets.FloatSlider(
        1.0, min=0.0, max=2.0, step=0.1, description="temperature", continuous_update=False
    )
    bend_joint = widgets.Dropdown(
        options=["(none)"] + list(CONTROL_JOINTS), value="(none)", description="bend"
    )
    bend = widgets.FloatSlider(
        0.0, min=-1.0, max=1.0, step=0.1, description="bend (m)", continuous_update=False
    )
    output = widgets.Output()

    def show(*_) -> None:
        given = [name for name, box in ticks.items() if box.value]
        chosen = None if bend_joint.value == "(none)" or bend_joint.value not in given else bend_joint.value
        result = complete_window(
            model, windows[window_index.value], given, n_samples.value, temperature.value, chosen, bend.value
        )
        output.clear_output(wait=True)
        with output:
            display(
                animate(
                    result.samples,
                    PARENTS,
                    fps,
                    step=step,
                    title=f"{n_samples.value} completions, given: {', '.join(given) or 'nothing'}",
                )
            )

    for control in (window_index, n_samples, temperature, bend_joint, bend, *ticks.values()):
        control.observe(show, names="value")
    show()
    boxes = widgets.HBox(list(ticks.values()))
    return widgets.VBox(
        [
            window_index,
            boxes,
            widgets.HBox([n_samples, temperature]),
            widgets.HBox([bend_joint, bend]),
            output,
        ]
    )
