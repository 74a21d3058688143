"""Stick figures on 3D axes: :func:`plot_pose` and :func:`filmstrip`, plus the scene helpers they share.

A stick figure is two cheap artists: one ``Line3D`` through every bone (consecutive bones separated by
NaN, which breaks the line) and one ``Line3D`` of joint markers. Moving a figure to the next pose is two
``set_data_3d`` calls, which keeps animations fast (:mod:`motionlab.viz.animation`).

The scene is the motionlab world frame: z up, a floor grid at ``z = min(0, lowest point)``, equal
scales on all three axes (the box keeps the data's proportions), axis panes hidden.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass, replace

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d import Axes3D
from mpl_toolkits.mplot3d.art3d import Line3D

from motionlab.validation import check_scalar
from motionlab.viz.checks import ArrayLike, as_parents, as_pose, as_sequence

#: Colours of the Motion Cell paper's comparison figure: real motion blue, generated motion orange.
REAL_COLOR = "tab:blue"
GENERATED_COLOR = "tab:orange"


@dataclass(frozen=True)
class Scene:
    """The box a set of poses is shown in: x-y centre, floor height and extent along x, y and z.

    Plots use the same scale on all three axes, so the box keeps the proportions of the motion (a walk
    gives a long, low box) instead of squeezing it into a cube.
    """

    centre: np.ndarray  # (2,) x-y centre
    floor: float  # z of the floor, the bottom of the box
    extent: np.ndarray  # (3,) sizes along x, y, z

    @staticmethod
    def _box(low: np.ndarray, high: np.ndarray, margin: float, min_fraction: float) -> Scene:
        low = low.astype(np.float64)
        low[2] = min(0.0, float(low[2]))
        extent = high - low
        largest = float(extent.max()) if extent.max() > 0 else 1.0
        extent = np.maximum(extent, min_fraction * largest) + np.array([2, 2, 1]) * margin * largest
        return Scene(centre=(low[:2] + high[:2]) / 2, floor=float(low[2]), extent=extent)

    @staticmethod
    def around(points: np.ndarray, margin: float = 0.05, min_fraction: float = 0.3) -> Scene:
        """The box around ``points`` ``(..., 3)`` with the floor at ``min(0, lowest z)``.

        Each side grows by ``margin`` of the largest extent, and no extent is less than ``min_fraction``
        of the largest, so a figure walking straight still stands on a floor of some width.
        """
        flat = points.reshape(-1, 3)
        return Scene._box(flat.min(axis=0), flat.max(axis=0), margin, min_fraction)

    @staticmethod
    def following(
        points: np.ndarray, centres: np.ndarray, margin: float = 0.05, min_fraction: float = 0.3
    ) -> Scene:
        """A box that moves with the motion: centred on ``centres[t]`` ``(T, 2)`` at frame t, just large
        enough to hold every frame's ``points[t]`` ``(T, K, 3)``. Returned centred on ``centres[0]``."""
        reach = np.abs(points[..., :2] - centres[:, None]).reshape(-1, 2).max(axis=0)
        heights = points[..., 2]
        low = np.array([-reach[0], -reach[1], heights.min()])
        high = np.array([reach[0], reach[1], heights.max()])
        return Scene._box(low, high, margin, min_fraction).moved(centres[0])

    @property
    def lower(self) -> np.ndarray:
        """``(3,)`` lowest corner of the box."""
        return np.array([*(self.centre - self.extent[:2] / 2), self.floor])

    @property
    def upper(self) -> np.ndarray:
        """``(3,)`` highest corner of the box."""
        return self.lower + self.extent

    def moved(self, centre: np.ndarray) -> Scene:
        """The same box with its x-y centre at ``centre``."""
        return replace(self, centre=np.asarray(centre, dtype=np.float64)[:2])

    def with_extent(self, extent: np.ndarray) -> Scene:
        """The same centre and floor with another extent (to show several scenes at one scale)."""
        return replace(self, extent=np.asarray(extent, dtype=np.float64))


def common_extent(scenes: Sequence[Scene]) -> np.ndarray:
    """``(3,)`` the largest extent along each axis: a box size that fits every scene."""
    return np.max([s.extent for s in scenes], axis=0)


def _grid_spacing(size: float) -> float:
    """A round spacing (1, 2 or 5 times a power of ten) giving about eight grid cells across ``size``."""
    raw = size / 8
    power = 10.0 ** np.floor(np.log10(raw))
    return float(power * min(m for m in (1, 2, 5, 10) if m * power >= raw))


@dataclass
class FloorGrid:
    """A floor grid drawn as one ``Line3D`` (segments separated by NaN), world-fixed lines every ``step``."""

    line: Line3D
    step: float

    def show(self, scene: Scene) -> None:
        """Draw the grid lines that fall inside ``scene``'s floor rectangle."""
        low, high = scene.lower, scene.upper
        xs = np.arange(np.ceil(low[0] / self.step), np.floor(high[0] / self.step) + 1) * self.step
        ys = np.arange(np.ceil(low[1] / self.step), np.floor(high[1] / self.step) + 1) * self.step
        gx = [[x, x, np.nan] for x in xs] + [[low[0], high[0], np.nan] for _ in ys]
        gy = [[low[1], high[1], np.nan] for _ in xs] + [[y, y, np.nan] for y in ys]
        self.line.set_data_3d(np.ravel(gx), np.ravel(gy), np.full(3 * (len(xs) + len(ys)), scene.floor))


def setup_axes(ax: Axes3D, scene: Scene, elev: float = 15.0, azim: float = -60.0) -> FloorGrid:
    """Equal scales on x, y, z for boxes of ``scene``'s extent, a floor grid and a clean look for ``ax``.

    Returns the grid; :func:`show_scene` moves the view (and the grid) to another box of the same extent.
    """
    ax.set_box_aspect(tuple(scene.extent), zoom=1.1)
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()
    (line,) = ax.plot([], [], [], color="0.8", linewidth=0.6, zorder=0)
    grid = FloorGrid(line=line, step=_grid_spacing(float(scene.extent[:2].max())))
    show_scene(ax, grid, scene)
    return grid


def show_scene(ax: Axes3D, grid: FloorGrid, scene: Scene) -> None:
    """Set ``ax``'s limits to ``scene``'s box and redraw the floor grid there."""
    low, high = scene.lower, scene.upper
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_zlim(low[2], high[2])
    grid.show(scene)


@dataclass
class StickFigure:
    """The artists of one drawn skeleton; :meth:`set_pose` moves them to a new pose ``(J, 3)``."""

    bones: Line3D
    joints: Line3D
    bone_index: np.ndarray  # indices into the pose with a NaN row appended: parent, child, NaN, ...

    def set_pose(self, pose: np.ndarray) -> None:
        padded = np.vstack([pose, np.full((1, 3), np.nan)])
        path = padded[self.bone_index]
        self.bones.set_data_3d(path[:, 0], path[:, 1], path[:, 2])
        self.joints.set_data_3d(pose[:, 0], pose[:, 1], pose[:, 2])


def _bone_index(parents: np.ndarray) -> np.ndarray:
    nan_row = len(parents)
    return np.array([i for j, p in enumerate(parents) if p >= 0 for i in (p, j, nan_row)], dtype=np.int64)


def draw_stick_figure(
    ax: Axes3D,
    pose: np.ndarray,
    parents: np.ndarray,
    color: str,
    linewidth: float = 2.0,
    marker_size: float = 2.5,
    label: str | None = None,
    alpha: float = 1.0,
) -> StickFigure:
    """Draw a checked pose ``(J, 3)`` with checked ``parents`` on ``ax`` (no scene setup)."""
    (bones,) = ax.plot(
        [], [], [], color=color, linewidth=linewidth, solid_capstyle="round", label=label, alpha=alpha
    )
    (joints,) = ax.plot(
        [], [], [], linestyle="none", marker="o", markersize=marker_size, color=color, alpha=alpha
    )
    figure = StickFigure(bones=bones, joints=joints, bone_index=_bone_index(parents))
    figure.set_pose(pose)
    return figure


def plot_pose(
    ax: Axes3D,
    pos: ArrayLike,
    parents: Sequence[int] | ArrayLike,
    color: str = REAL_COLOR,
    *,
    scene: Scene | None = None,
    label: str | None = None,
    elev: float = 15.0,
    azim: float = -60.0,
) -> StickFigure:
    """Draw one pose as a stick figure on a 3D axis, with equal aspect and a floor grid.

    Args:
        ax: a 3D axis (``fig.add_subplot(projection="3d")``).
        pos: joint positions ``(J, 3)``, z up.
        parents: ``(J,)`` parent index of each joint, ``-1`` for the root.
        color: any matplotlib colour.
        scene: the box to show; by default the one around this pose. To overlay several poses on one
            axis, pass the same scene (for example ``Scene.around`` of all of them) to every call.
        label: legend label of the figure.
        elev, azim: camera angles in degrees.

    Returns:
        The :class:`StickFigure` (its artists; ``set_pose`` redraws it in another pose).
    """
    pose = as_pose(pos, "pos", "plot_pose")
    parent_index = as_parents(parents, pose.shape[0], "plot_pose")
    if not isinstance(ax, Axes3D):
        raise TypeError(f"plot_pose: ax must be a 3D axis (projection='3d'), got {type(ax).__name__}")
    setup_axes(ax, Scene.around(pose) if scene is None else scene, elev=elev, azim=azim)
    return draw_stick_figure(ax, pose, parent_index, color, label=label)


def keyframe_indices(num_frames: int, n_frames: int) -> np.ndarray:
    """``n_frames`` frame indices spread evenly from the first to the last of ``num_frames`` frames."""
    check_scalar(n_frames, "n_frames", "keyframe_indices", kind=numbers.Integral, minimum=1)
    return np.unique(np.round(np.linspace(0, num_frames - 1, min(n_frames, num_frames))).astype(np.int64))


def filmstrip(
    pos: ArrayLike,
    parents: Sequence[int] | ArrayLike,
    n_frames: int = 6,
    *,
    fps: float | None = None,
    color: str = REAL_COLOR,
    panel_size: float = 2.0,
    elev: float = 15.0,
    azim: float = -60.0,
    title: str | None = None,
) -> Figure:
    """Keyframes of a motion side by side in one figure.

    Args:
        pos: joint positions ``(T, J, 3)``.
        parents: ``(J,)`` parent indices.
        n_frames: how many keyframes, spread evenly over the clip (fewer if the clip is shorter).
        fps: frames per second; when given, panels are titled with the time, otherwise the frame.
        color: figure colour; panel_size: inches per panel; elev, azim: camera angles.
        title: optional figure title.

    Every panel shows a box of the same size (fitting the largest pose) centred on that pose's root, so
    poses compare at one scale. Returns the pyplot ``Figure`` (one row of 3D axes).
    """
    motion = as_sequence(pos, "pos", "filmstrip")
    parent_index = as_parents(parents, motion.shape[1], "filmstrip")
    frames = keyframe_indices(motion.shape[0], n_frames)
    roots = motion[frames, 0, :2]
    scene = Scene.following(motion[frames], roots)
    fig = plt.figure(figsize=(panel_size * len(frames), panel_size * 1.1))
    for k, t in enumerate(frames):
        ax = fig.add_subplot(1, len(frames), k + 1, projection="3d")
        plot_pose(ax, motion[t], parent_index, color, scene=scene.moved(roots[k]), elev=elev, azim=azim)
        ax.set_title(f"t = {t / fps:.2f} s" if fps else f"frame {t}", fontsize=9)
    if title:
        fig.suptitle(title, y=0.99)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.8 if title else 0.9, wspace=0)
    return fig
