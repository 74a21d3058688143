"""Chapter 08's widgets: sample a discovered mode, slide between two modes, send several styles to one end
point.

Each callback is a plain function of a trained :class:`~motionlab.models.odmo.sampling.ODMOSampler` and the
widget values that returns a matplotlib ``Figure``; the ``*_widget`` builders only wire ipywidgets to them.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import partial

import ipywidgets as widgets
import numpy as np
from matplotlib.figure import Figure

from motionlab.models.odmo.sampling import ODMOSampler, Samples, mode_interpolation, styles_to_end_point
from motionlab.viz import GENERATED_COLOR, filmstrip, plot_root_paths
from motionlab.widgets.controls import action_dropdown, wire


def _check_mode(sampler: ODMOSampler, action: int, mode: int) -> None:
    n_modes = sampler.modes.classes[sampler.modes.check_action(action)].n_modes
    if not 0 <= mode < n_modes:
        raise ValueError(f"action {action} has discovered modes 0..{n_modes - 1}, got {mode}")


def _clip_strip(clip: Samples, parents: Sequence[int], fps: int, title: str) -> Figure:
    """Six keyframes of the first of ``clip``'s generated motions."""
    return filmstrip(
        clip.positions[0].numpy(), parents, n_frames=6, fps=fps, color=GENERATED_COLOR, title=title
    )


def mode_sample_figure(
    sampler: ODMOSampler, parents: Sequence[int], action: int, mode: int, seed: int, fps: int = 30
) -> Figure:
    """Filmstrip of one clip drawn from discovered ``mode`` of ``action`` (seeded)."""
    _check_mode(sampler, action, mode)
    clip = sampler.sample(action, 1, np.random.default_rng(seed), mode=mode)
    return _clip_strip(clip, parents, fps, f"action {action}, discovered mode {mode}, seed {seed}")


def interpolation_figure(
    sampler: ODMOSampler,
    parents: Sequence[int],
    action: int,
    mode_a: int,
    mode_b: int,
    weight: float,
    fps: int = 30,
) -> Figure:
    """Filmstrip of the clip whose code lies ``weight`` of the way from mode ``mode_a``'s centre to
    ``mode_b``'s."""
    _check_mode(sampler, action, mode_a)
    _check_mode(sampler, action, mode_b)
    if not 0.0 <= weight <= 1.0:
        raise ValueError(f"interpolation_figure: weight must lie in [0, 1], got {weight}")
    clip = mode_interpolation(sampler, action, mode_a, mode_b, np.array([weight]))
    return _clip_strip(
        clip,
        parents,
        fps,
        f"action {action}: {1 - weight:.2f} x mode {mode_a} + {weight:.2f} x mode {mode_b}",
    )


def end_point_figure(
    sampler: ODMOSampler, action: int, x: float, y: float, seed: int, per_mode: int = 2
) -> Figure:
    """Top-down root paths of ``per_mode`` clips of every discovered mode of ``action``, all sent to ``(x,
    y)`` metres from the start (the character starts at the origin facing +x); the target is the black
    star."""
    clips = styles_to_end_point(sampler, action, np.array([x, y, 0.0]), np.random.default_rng(seed), per_mode)
    fig = Figure(figsize=(5, 4), layout="constrained")
    ax = fig.add_subplot()
    labels = [f"mode {m}" for m in clips.mode]
    colors = [f"C{m % 10}" for m in clips.mode]
    plot_root_paths(
        clips.positions.numpy(),
        ax,
        labels=labels,
        colors=colors,
        title=f"action {action} to ({x:.1f}, {y:.1f}) m",
    )
    ax.plot([x], [y], marker="*", color="black", markersize=14, linestyle="none")
    handles, names = ax.get_legend_handles_labels()
    unique = dict(zip(names, handles))
    ax.legend(unique.values(), unique.keys(), fontsize=8)
    return fig


def _mode_slider(sampler: ODMOSampler, action: int, description: str, value: int = 0) -> widgets.IntSlider:
    n_modes = sampler.modes.classes[action].n_modes
    return widgets.IntSlider(
        value=min(value, n_modes - 1),
        min=0,
        max=n_modes - 1,
        description=description,
        continuous_update=False,
    )


def _follow_action(action: widgets.Dropdown, sampler: ODMOSampler, *sliders: widgets.IntSlider) -> None:
    """Keep each mode slider's range to the chosen action's discovered modes."""

    def update(change: dict) -> None:
        for slider in sliders:
            slider.max = sampler.modes.classes[change["new"]].n_modes - 1

    action.observe(update, names="value")


def mode_sampler_widget(
    sampler: ODMOSampler, parents: Sequence[int], action_names: Sequence[str]
) -> widgets.VBox:
    """Pick an action and one of its discovered modes, and draw a clip from it."""
    action = action_dropdown(action_names)
    mode = _mode_slider(sampler, 0, "mode")
    seed = widgets.IntSlider(value=0, min=0, max=20, description="seed", continuous_update=False)
    _follow_action(action, sampler, mode)
    out = widgets.Output()
    wire(out, partial(mode_sample_figure, sampler, parents), {"action": action, "mode": mode, "seed": seed})
    return widgets.VBox([widgets.HBox([action, mode, seed]), out])


def interpolation_widget(
    sampler: ODMOSampler, parents: Sequence[int], action_names: Sequence[str]
) -> widgets.VBox:
    """Slide a code between the centres of two discovered modes of one action."""
    action = action_dropdown(action_names)
    mode_a = _mode_slider(sampler, 0, "from mode", 0)
    mode_b = _mode_slider(sampler, 0, "to mode", 1)
    weight = widgets.FloatSlider(
        value=0.5, min=0.0, max=1.0, step=0.1, description="weight", continuous_update=False
    )
    _follow_action(action, sampler, mode_a, mode_b)
    out = widgets.Output()
    wire(
        out,
        partial(interpolation_figure, sampler, parents),
        {"action": action, "mode_a": mode_a, "mode_b": mode_b, "weight": weight},
    )
    return widgets.VBox([widgets.HBox([action, mode_a, mode_b, weight]), out])


def end_point_widget(sampler: ODMOSampler, action_names: Sequence[str]) -> widgets.VBox:
    """Set an end point and watch clips of every discovered mode of an action walk to it."""
    action = action_dropdown(action_names)
    x = widgets.FloatSlider(
        value=4.0, min=-2.0, max=12.0, step=0.5, description="x (m)", continuous_update=False
    )
    y = widgets.FloatSlider(
        value=1.0, min=-4.0, max=4.0, step=0.5, description="y (m)", continuous_update=False
    )
    seed = widgets.IntSlider(value=0, min=0, max=20, description="seed", continuous_update=False)
    out = widgets.Output()
    wire(out, partial(end_point_figure, sampler), {"action": action, "x": x, "y": y, "seed": seed})
    return widgets.VBox([widgets.HBox([action, x, y, seed]), out])
