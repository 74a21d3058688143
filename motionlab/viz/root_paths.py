"""Top-down root paths: where each motion goes on the floor (the x-y plane, z up)."""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import matplotlib.pyplot as plt
from matplotlib.axes import Axes

from motionlab.validation import check_scalar
from motionlab.viz.checks import ArrayLike, as_sequence_list, series_colors


def plot_root_paths(
    positions: ArrayLike | Sequence[ArrayLike],
    ax: Axes | None = None,
    *,
    root: int = 0,
    labels: Sequence[str] | None = None,
    colors: Sequence[str] | None = None,
    alpha: float = 0.9,
    title: str | None = None,
) -> Axes:
    """Plot each motion's root path seen from above, with a circle at the start and a cross at the end.

    Args:
        positions: joint positions ``(T, J, 3)``, several as ``(N, T, J, 3)`` or a list of ``(T_i, J, 3)``.
        ax: a 2D axis to draw on; by default a new pyplot figure.
        root: index of the joint whose path is drawn (0, the pelvis, by default).
        labels, colors: one per motion (default colours ``C0, C1, ...``); labels go to a legend.
        alpha: line opacity (lower it for many paths).
        title: optional axis title.

    Returns:
        The axis, with equal x and y scales (metres stay metres in both directions).
    """
    func = "plot_root_paths"
    paths = as_sequence_list(positions, func)
    joints = paths[0].shape[1]
    check_scalar(root, "root (a joint index)", func, kind=numbers.Integral, minimum=0, maximum=joints - 1)
    colors = series_colors(colors, labels, len(paths), func)
    if ax is None:
        _, ax = plt.subplots(figsize=(4.5, 4.5), layout="constrained")
    for i, (path, color) in enumerate(zip(paths, colors)):
        xy = path[:, root, :2]
        ax.plot(
            xy[:, 0],
            xy[:, 1],
            color=color,
            alpha=alpha,
            linewidth=1.5,
            label=None if labels is None else labels[i],
        )
        ax.plot(
            *xy[0], marker="o", color=color, markersize=5, linestyle="none", label="start" if i == 0 else None
        )
        ax.plot(
            *xy[-1], marker="x", color=color, markersize=6, linestyle="none", label="end" if i == 0 else None
        )
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (forward)")
    ax.set_ylabel("y (left)")
    ax.grid(True, linewidth=0.5, alpha=0.5)
    ax.legend(fontsize=8, frameon=False)
    if title:
        ax.set_title(title)
    return ax
