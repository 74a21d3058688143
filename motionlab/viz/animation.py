"""Animated stick figures as self-contained HTML: :func:`animate` and :func:`compare_animation`.

Animations are rendered with ``FuncAnimation.to_jshtml()``: every frame is a small PNG embedded in
an HTML player, so they play in Jupyter and in the exported course pages without ffmpeg. To keep
that fast (a 4-second clip of 22 joints in well under 3 s) each figure is two ``Line3D`` artists whose
data is replaced per frame (the camera, when it follows the figure, only changes axis limits), the
figure is small at a low dpi, and ``step``
skips frames when a long clip needs it.

The figure is a bare ``matplotlib.figure.Figure`` (not registered with pyplot), so it never shows up
as a stray static image in a notebook and is freed as soon as the HTML is made.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from IPython.display import HTML
from matplotlib.animation import FuncAnimation
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d import Axes3D

from motionlab.validation import check_choice, check_scalar
from motionlab.viz.checks import ArrayLike, as_parents, as_sequence_list, series_colors
from motionlab.viz.stick_figure import (
    GENERATED_COLOR,
    REAL_COLOR,
    FloorGrid,
    Scene,
    StickFigure,
    common_extent,
    draw_stick_figure,
    setup_axes,
    show_scene,
)

LAYOUTS = ("overlay", "side")


def animation_frames(num_frames: int, step: int) -> list[int]:
    """The frame indices an animation of ``num_frames`` frames shows with ``step``: 0, step, 2·step, ..."""
    check_scalar(step, "step", "animation_frames", kind=numbers.Integral, minimum=1)
    return list(range(0, num_frames, int(step)))


@dataclass
class _Panel:
    """One 3D axis of an animation: its figures, their (padded) positions and, when following, its path."""

    ax: Axes3D
    grid: FloorGrid
    scene: Scene
    figures: list[StickFigure]
    sequences: list[np.ndarray]  # (T, J, 3) each, padded to the animation's length
    centres: np.ndarray | None  # (T, 2) box centres when the camera follows, else None

    def show_frame(self, t: int) -> None:
        if self.centres is not None:
            show_scene(self.ax, self.grid, self.scene.moved(self.centres[t]))
        for figure, sequence in zip(self.figures, self.sequences):
            figure.set_pose(sequence[t])


def build_animation(
    motions: ArrayLike | Sequence[ArrayLike],
    parents: Sequence[int] | ArrayLike,
    fps: float = 30.0,
    *,
    step: int = 1,
    layout: str = "overlay",
    follow: bool = True,
    colors: Sequence[str] | None = None,
    labels: Sequence[str] | None = None,
    panel_size: float = 3.0,
    dpi: int = 60,
    elev: float = 15.0,
    azim: float = -60.0,
    title: str | None = None,
) -> FuncAnimation:
    """The ``FuncAnimation`` behind :func:`animate` (same arguments); useful to save to a file."""
    func = "animate"
    sequences = as_sequence_list(motions, func)
    parent_index = as_parents(parents, sequences[0].shape[1], func)
    check_choice(layout, "layout", func, LAYOUTS)
    fps = float(check_scalar(fps, "fps", func, minimum=0, include_minimum=False))
    count = len(sequences)
    colors = series_colors(colors, labels, count, func)
    length = max(len(s) for s in sequences)
    frames = animation_frames(length, step)
    padded = [np.concatenate([s, np.repeat(s[-1:], length - len(s), axis=0)]) for s in sequences]

    groups = [list(range(count))] if layout == "overlay" else [[i] for i in range(count)]
    fig = Figure(figsize=(panel_size * len(groups), panel_size), dpi=dpi)
    headings = bool(title) + (labels is not None and layout == "side")  # lines of text above the axes
    fig.subplots_adjust(left=0, right=1, bottom=0, top=1 - 0.09 * headings, wspace=0)
    points = [np.concatenate([padded[i] for i in group], axis=1) for group in groups]  # (T, K, 3) per panel
    centres = [np.mean([padded[i][:, 0, :2] for i in group], axis=0) for group in groups] if follow else None
    scenes = (
        [Scene.following(p, c) for p, c in zip(points, centres)]
        if follow
        else [Scene.around(p) for p in points]
    )
    extent = common_extent(scenes)  # every panel at one scale
    panels = []
    for k, (group, scene) in enumerate(zip(groups, scenes)):
        ax = fig.add_subplot(1, len(groups), k + 1, projection="3d")
        scene = scene.with_extent(extent)
        grid = setup_axes(ax, scene, elev=elev, azim=azim)
        figures = [
            draw_stick_figure(
                ax, padded[i][0], parent_index, colors[i], label=None if labels is None else labels[i]
            )
            for i in group
        ]
        if labels is not None and layout == "side":
            ax.set_title(labels[group[0]], fontsize=9)
        panels.append(
            _Panel(
                ax, grid, scene, figures, [padded[i] for i in group], None if centres is None else centres[k]
            )
        )
    if layout == "overlay" and labels is not None:
        panels[0].ax.legend(loc="upper left", fontsize=8, frameon=False)
    clock = fig.text(0.02, 0.02, "", fontsize=8, color="0.3")
    if title:
        fig.suptitle(title, fontsize=9)

    def update(t: int) -> list:
        for panel in panels:
            panel.show_frame(t)
        clock.set_text(f"t = {t / fps:.2f} s")
        return []

    return FuncAnimation(fig, update, frames=frames, interval=1000.0 * step / fps, blit=False)


def animate(
    motions: ArrayLike | Sequence[ArrayLike],
    parents: Sequence[int] | ArrayLike,
    fps: float = 30.0,
    *,
    step: int = 1,
    layout: str = "overlay",
    follow: bool = True,
    colors: Sequence[str] | None = None,
    labels: Sequence[str] | None = None,
    panel_size: float = 3.0,
    dpi: int = 60,
    elev: float = 15.0,
    azim: float = -60.0,
    title: str | None = None,
) -> HTML:
    """An HTML player (``FuncAnimation.to_jshtml``) of one or several stick-figure motions.

    Args:
        motions: joint positions ``(T, J, 3)``, several as ``(N, T, J, 3)`` or a list of ``(T_i, J, 3)``
            (shorter ones hold their last pose), z up.
        parents: ``(J,)`` parent indices, ``-1`` for the root.
        fps: frame rate of the positions.
        step: show every ``step``-th frame (the player still runs in real time).
        layout: ``"overlay"`` draws all motions in one scene; ``"side"`` gives each its own panel, all
            panels at the same scale.
        follow: the camera travels with the root (the mean root when overlaid) in a box just large
            enough for the figure, and the floor grid slides by; ``False`` shows the whole path in a
            fixed box (figures get small when they travel far).
        colors, labels: one per motion (default colours ``C0, C1, ...``; labels go to a legend or
            panel titles).
        panel_size: inches per panel; dpi: pixels per inch of the frames; elev, azim: camera angles.
        title: optional title.

    Returns:
        ``IPython.display.HTML`` with ``ceil(T / step)`` embedded frames (T the longest motion).
    """
    anim = build_animation(
        motions,
        parents,
        fps,
        step=step,
        layout=layout,
        follow=follow,
        colors=colors,
        labels=labels,
        panel_size=panel_size,
        dpi=dpi,
        elev=elev,
        azim=azim,
        title=title,
    )
    html = anim.to_jshtml(fps=fps / step, default_mode="loop")
    return HTML(html)


def compare_animation(
    real: ArrayLike,
    generated: ArrayLike,
    parents: Sequence[int] | ArrayLike,
    fps: float = 30.0,
    *,
    layout: str = "side",
    follow: bool = True,
    step: int = 1,
    labels: Sequence[str] = ("real", "generated"),
) -> HTML:
    """Real motion (blue) next to generated motion (orange), as in the Motion Cell paper's figures.

    ``real`` and ``generated`` are ``(T, J, 3)`` positions of one skeleton; ``layout="overlay"`` puts
    both figures in one scene instead. Other arguments as in :func:`animate`.
    """
    return animate(
        [real, generated],
        parents,
        fps,
        step=step,
        layout=layout,
        follow=follow,
        colors=(REAL_COLOR, GENERATED_COLOR),
        labels=labels,
    )
