"""Chapter 04's widget: pick an action, a body type, a length and a seed, and watch new Motion Cell samples.

The callback :func:`sample_motions` is a plain function (tested without a browser); :func:`motion_cell_widget`
wires it to ipywidgets and shows several samples side by side, so the variety of one setting is visible.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import ipywidgets as widgets
import torch
from torch import Tensor

from motionlab.validation import check_scalar
from motionlab.viz import animate


def sample_motions(
    model: torch.nn.Module, action: int, body: int, n_frames: int, seed: int, n_samples: int = 3
) -> Tensor:
    """Joint positions ``(n_samples, n_frames, 22, 3)`` of new samples of one action and body type.

    Args:
        model: a trained generator with ``generate(action, body, n_frames, generator)`` and a ``codec``.
        action, body: the control attributes (class indices).
        n_frames: frames per sample (any length, also longer than the training windows).
        seed: seeds the sampling; the same seed gives the same motions.
        n_samples: how many samples to draw side by side.
    """
    check_scalar(n_samples, "n_samples", "sample_motions", kind=numbers.Integral, minimum=1)
    check_scalar(seed, "seed", "sample_motions", kind=numbers.Integral, minimum=0)
    actions = torch.full((n_samples,), int(action), dtype=torch.int64)
    bodies = torch.full((n_samples,), int(body), dtype=torch.int64)
    with torch.no_grad():
        poses = model.generate(actions, bodies, n_frames, torch.Generator().manual_seed(seed))
        return model.codec.positions(poses, bodies)


def motion_cell_widget(
    model: torch.nn.Module,
    action_names: Sequence[str],
    body_names: Sequence[str],
    fps: int = 30,
    step: int = 3,
    max_frames: int = 300,
) -> widgets.VBox:
    """Controls (action, body type, length, seed, number of samples) and a player of the samples.

    The player is rendered once for the initial values when the widget is built (so it shows something
    without interaction), and again whenever "sample" is pressed. ``step`` shows every ``step``-th frame.
    """
    action = widgets.Dropdown(
        options=[(name, i) for i, name in enumerate(action_names)], value=0, description="action"
    )
    body = widgets.Dropdown(
        options=[(name, i) for i, name in enumerate(body_names)], value=0, description="body"
    )
    length = widgets.IntSlider(value=90, min=30, max=max_frames, step=30, description="frames")
    seed = widgets.BoundedIntText(value=0, min=0, max=2**31 - 1, description="seed")
    count = widgets.IntSlider(value=3, min=1, max=4, description="samples")
    button = widgets.Button(description="sample", button_style="primary")
    output = widgets.Output()

    def show(_: object = None) -> None:
        positions = sample_motions(model, action.value, body.value, length.value, seed.value, count.value)
        player = animate(
            list(positions),
            model.codec.parents,
            fps=fps,
            step=step,
            layout="side",
            labels=[f"seed {seed.value}, sample {i + 1}" for i in range(count.value)],
        )
        output.outputs = ()
        output.append_display_data(player)

    button.on_click(show)
    show()
    return widgets.VBox([widgets.HBox([action, body, length]), widgets.HBox([seed, count, button]), output])
