"""The chapter-02 data browser: pick an action, a style mode, a body type and a seed, and see that clip.

The pieces are plain functions, tested without a browser:

- :func:`browse_clip` generates one synthetic clip (a :class:`BrowsedClip`: positions, contacts,
  skeleton, frame rate and a title with its measurements);
- :func:`summarise_clip` measures a clip (speed, stride, step rate, pelvis rise and drop, when it
  moves): the numbers in the title, and the ones chapter 02 plots for whole modes;
- :func:`plot_clip_overview` draws the root path from above and the foot heights with their contacts;
- :func:`show_clip` is the widget callback: a filmstrip and the overview of one clip.

:func:`build_browser` wires :func:`show_clip` to dropdowns and a seed box (ipywidgets).

The browser draws from ``generate(seed, n_per_mode=2)``: one clip of each body type per mode. Because a
smaller data set is a subset of a larger one with the same seed, the clip of seed ``s`` is also the
first clip of that mode and body in every ``generate(s, n_per_mode=N)``.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import clear_output
from matplotlib.figure import Figure

from motionlab.data.actions import ACTION_NAMES, CATALOGUE
from motionlab.data.store import MotionSet
from motionlab.data.synthetic import generate
from motionlab.metrics.physical import FOOT_JOINTS
from motionlab.skeleton import BODY_TYPES, JOINT_NAMES
from motionlab.validation import as_float_array, check_choice, check_scalar
from motionlab.viz import filmstrip, plot_root_paths

#: A pose counts as moving when some joint is more than this far (metres) from the reference pose.
STILL_TOLERANCE = 0.01


def mode_choices(action: str) -> tuple[str, ...]:
    """The style modes of ``action`` (e.g. ``("upright", "hunched")`` for ``"walk"``), in mode-id order."""
    check_choice(action, "action", "mode_choices", ACTION_NAMES)
    return CATALOGUE[ACTION_NAMES.index(action)].modes


class BrowsedClip(NamedTuple):
    """One clip of the synthetic data set, ready to draw.

    Attributes:
        positions: ``(T, 22, 3)`` float32 global joint positions, metres, z up.
        contacts: ``(T, 4)`` bool ground-truth contacts of the joints :data:`FOOT_JOINTS` (left ankle,
            right ankle, left foot, right foot).
        parents: the 22 parent indices.
        fps: frames per second.
        title: mode, body, seed and the clip's measurements (:meth:`ClipSummary.describe`).
    """

    positions: np.ndarray
    contacts: np.ndarray
    parents: tuple[int, ...]
    fps: float
    title: str


@dataclass(frozen=True)
class ClipSummary:
    """Measurements of one clip (see :func:`summarise_clip`). ``None`` where a clip has nothing to measure.

    Attributes:
        speed: mean horizontal speed of the root (path length over duration), m/s.
        stride: mean distance between successive touch-downs of the same foot joint, m (``None`` when no
            foot joint touches down twice, e.g. in a jump).
        step_rate: steps per second, twice the inverse of the mean time between successive touch-downs
            of the same foot joint (``None`` with ``stride``).
        pelvis_rise, pelvis_drop: highest rise and deepest drop of the pelvis relative to frame 0, m (>= 0).
        moving_from: first time (s) at which the pose differs from frame 0 by more than
            :data:`STILL_TOLERANCE` (``None`` for a clip that never moves).
        moving_until: last time (s) at which the pose differs from the last frame by more than
            :data:`STILL_TOLERANCE` (``None`` likewise). For one-off events (jump, lift, kick) these are the
            start and end of the event; periodic motion moves from the second frame to the second last.
    """

    speed: float
    stride: float | None
    step_rate: float | None
    pelvis_rise: float
    pelvis_drop: float
    moving_from: float | None
    moving_until: float | None

    def describe(self) -> str:
        """The measurements as a short phrase, e.g. ``"1.31 m/s, stride 1.45 m, 1.8 steps/s, pelvis
        +0.02/-0.03 m"``."""
        parts = [f"{self.speed:.2f} m/s"]
        if self.stride is not None and self.step_rate is not None:
            parts += [f"stride {self.stride:.2f} m", f"{self.step_rate:.1f} steps/s"]
        parts.append(f"pelvis +{self.pelvis_rise:.2f}/-{self.pelvis_drop:.2f} m")
        if self.moving_from is not None and self.moving_until is not None:
            parts.append(f"moves {self.moving_from:.2f}-{self.moving_until:.2f} s")
        return ", ".join(parts)


def _check_clip(
    positions: np.ndarray, contacts: np.ndarray, fps: float, feet: Sequence[int]
) -> tuple[np.ndarray, np.ndarray, float, list[int]]:
    func = "summarise_clip"
    positions = as_float_array(positions, "positions", func, allow_empty=True)
    contacts = np.asarray(contacts)
    if positions.ndim != 3 or positions.shape[-1] != 3 or positions.shape[0] < 2:
        raise ValueError(f"{func}: positions must have shape (T, J, 3) with T >= 2, got {positions.shape}")
    feet = [int(j) for j in feet]
    if not feet or min(feet) < 0 or max(feet) >= positions.shape[1] or len(set(feet)) != len(feet):
        raise ValueError(
            f"{func}: feet must be distinct joint indices in [0, {positions.shape[1]}), got {feet}"
        )
    if contacts.shape != (positions.shape[0], len(feet)):
        raise ValueError(
            f"{func}: contacts must have shape (T, F) = {(positions.shape[0], len(feet))} "
            f"(frames x feet), got {contacts.shape}"
        )
    if contacts.dtype != bool:
        raise TypeError(f"{func}: contacts must be booleans, got dtype {contacts.dtype}")
    fps = float(check_scalar(fps, "fps", func, minimum=0, include_minimum=False))
    return positions, contacts, fps, feet


def _first_moving(displacement: np.ndarray) -> int | None:
    """Index of the first entry of ``displacement`` ``(T,)`` above :data:`STILL_TOLERANCE`, or ``None``."""
    moving = np.flatnonzero(displacement > STILL_TOLERANCE)
    return int(moving[0]) if moving.size else None


def summarise_clip(
    positions: np.ndarray, contacts: np.ndarray, fps: float, feet: Sequence[int] = FOOT_JOINTS
) -> ClipSummary:
    """Measure one clip: speed, stride, step rate, pelvis rise and drop, and when it moves.

    Args:
        positions: ``(T, J, 3)`` global joint positions, metres, z up; joint 0 is the root (pelvis).
        contacts: ``(T, F)`` bool, whether joint ``feet[f]`` is planted on frame ``t``.
        fps: frames per second.
        feet: the ``F`` joints the contact columns belong to (default: the 22-joint skeleton's ankles and
            feet, the column order of the synthetic data's ``contacts``).

    A touch-down of a foot joint is a frame where its contact starts (it was not planted on the frame
    before); the stride is the horizontal distance between successive touch-downs of the same joint.
    Returns a :class:`ClipSummary`.
    """
    positions, contacts, fps, feet = _check_clip(positions, contacts, fps, feet)
    n_frames = positions.shape[0]
    root = positions[:, 0]
    path_length = np.linalg.norm(np.diff(root[:, :2], axis=0), axis=-1).sum()
    strides, intervals = [], []
    for column, joint in enumerate(feet):
        planted = contacts[:, column]
        touchdowns = np.flatnonzero(planted[1:] & ~planted[:-1]) + 1
        strides.append(np.linalg.norm(np.diff(positions[touchdowns, joint, :2], axis=0), axis=-1))
        intervals.append(np.diff(touchdowns) / fps)
    strides, intervals = np.concatenate(strides), np.concatenate(intervals)
    from_first = np.linalg.norm(positions - positions[0], axis=-1).max(axis=-1)
    from_last = np.linalg.norm(positions - positions[-1], axis=-1).max(axis=-1)
    start, end = _first_moving(from_first), _first_moving(from_last[::-1])
    return ClipSummary(
        speed=float(path_length * fps / (n_frames - 1)),
        stride=float(strides.mean()) if strides.size else None,
        step_rate=float(2.0 / intervals.mean()) if intervals.size else None,
        pelvis_rise=float(max(root[:, 2].max() - root[0, 2], 0.0)),
        pelvis_drop=float(max(root[0, 2] - root[:, 2].min(), 0.0)),
        moving_from=None if start is None else start / fps,
        moving_until=None if end is None else (n_frames - 1 - end) / fps,
    )


@lru_cache(maxsize=8)
def _clip_set(seed: int) -> MotionSet:
    """``generate(seed, n_per_mode=2)``: one clip per mode and body type (cached: the widget asks
    repeatedly)."""
    return generate(seed=seed, n_per_mode=len(BODY_TYPES))


def browse_clip(action: str, mode: str, body: str, seed: int) -> BrowsedClip:
    """The synthetic clip of ``action`` in style ``mode`` for body type ``body``, generated with ``seed``.

    Args:
        action: one of :data:`~motionlab.data.actions.ACTION_NAMES` (``"walk"``, ``"jog"``, ...).
        mode: one of the action's styles, :func:`mode_choices` (``"upright"``, ``"hunched"``, ...).
        body: one of :data:`~motionlab.skeleton.BODY_TYPES` (``"broad"``, ``"slender"``).
        seed: non-negative integer seed of the generator.
    Returns:
        A :class:`BrowsedClip` (copies; changing them does not change later calls).
    Raises:
        ValueError: naming the argument that is not one of the choices (or a negative seed).
        TypeError: a seed that is not an integer.
    """
    check_choice(action, "action", "browse_clip", ACTION_NAMES)
    check_choice(mode, f"mode (a style of {action!r})", "browse_clip", mode_choices(action))
    check_choice(body, "body", "browse_clip", BODY_TYPES)
    check_scalar(seed, "seed", "browse_clip", kind=numbers.Integral, minimum=0)
    data = _clip_set(int(seed))
    mode_name = f"{action}_{mode}"
    mode_id = list(data.mode_names).index(mode_name)
    (index,) = np.flatnonzero((data.mode == mode_id) & (data.body == BODY_TYPES.index(body)))
    fps = float(data.fps)
    positions, contacts = data.positions[index].copy(), data.contacts[index].copy()
    summary = summarise_clip(positions, contacts, fps)
    title = f"{mode_name}, {body} body, seed {seed}: {summary.describe()}"
    return BrowsedClip(positions, contacts, tuple(int(p) for p in data.parents), fps, title)


def plot_clip_overview(clip: BrowsedClip) -> Figure:
    """Two panels: the root path seen from above, and the heights of the foot joints over time.

    In the right panel, the band under a foot joint's height curve is shaded on the frames where the
    joint is planted (the ground-truth contacts). Returns the pyplot figure.
    """
    fig, (path_ax, feet_ax) = plt.subplots(1, 2, figsize=(10, 3.2), width_ratios=(1, 2), layout="constrained")
    plot_root_paths(clip.positions, ax=path_ax, title="root path (from above)")
    time = np.arange(clip.positions.shape[0]) / clip.fps
    for column, joint in enumerate(FOOT_JOINTS):
        height = clip.positions[:, joint, 2]
        (line,) = feet_ax.plot(time, height, linewidth=1.2, label=JOINT_NAMES[joint])
        feet_ax.fill_between(
            time, 0, height, where=clip.contacts[:, column], color=line.get_color(), alpha=0.25, linewidth=0
        )
    feet_ax.set(xlabel="time (s)", ylabel="height (m)", title="foot joints; shaded while planted")
    feet_ax.legend(fontsize=8, ncols=2, frameon=False)
    return fig


def show_clip(action: str, mode: str, body: str, seed: int, n_keyframes: int = 4) -> tuple[Figure, Figure]:
    """Widget callback: a filmstrip of ``n_keyframes`` poses and :func:`plot_clip_overview` of one clip.

    Arguments as in :func:`browse_clip`. Returns both pyplot figures (the inline backend shows them).
    """
    clip = browse_clip(action, mode, body, seed)
    strip = filmstrip(clip.positions, clip.parents, n_keyframes, fps=clip.fps, title=clip.title)
    return strip, plot_clip_overview(clip)


def build_browser(seed: int = 0, n_keyframes: int = 4) -> widgets.VBox:
    """The data browser: dropdowns for action and mode, buttons for the body, a seed box, and the plots.

    Changing the action offers that action's modes; every change redraws :func:`show_clip` once. The
    first clip (walk, upright, broad, ``seed``) is drawn when the browser is built.
    """
    action = widgets.Dropdown(options=ACTION_NAMES, description="action")
    mode = widgets.Dropdown(options=mode_choices(action.value), description="mode")
    body = widgets.ToggleButtons(options=BODY_TYPES, description="body")
    seed_box = widgets.BoundedIntText(value=seed, min=0, max=2**31 - 1, description="seed")
    output = widgets.Output()

    def redraw(_change: object = None) -> None:
        with output:
            clear_output(wait=True)
            show_clip(action.value, mode.value, body.value, seed_box.value, n_keyframes)
            plt.show()

    def change_action(change: dict) -> None:
        mode.unobserve(redraw, "value")  # new options reset the mode: draw once, below
        mode.options = mode_choices(change["new"])
        mode.observe(redraw, "value")
        redraw()

    action.observe(change_action, "value")
    for control in (mode, body, seed_box):
        control.observe(redraw, "value")
    redraw()
    return widgets.VBox([widgets.HBox([action, mode, seed_box]), body, output])
