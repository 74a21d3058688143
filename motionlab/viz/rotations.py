"""Pictures of rotations: slerp and nlerp paths on the sphere, and the chapter-01 widget callback.

A rotation is drawn by where it sends the character's forward axis ``+x`` (a point on the unit
sphere) plus its body frame (x red, y green, z blue). Along an interpolation the forward axis
traces a curve; dots at equal steps of the interpolation weight ``w`` show the speed.
"""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import torch
from matplotlib.figure import Figure

from motionlab.geometry import (
    euler_to_quat,
    interpolation_paths,
    quat_apply,
    quat_geodesic,
    quat_nlerp,
    quat_slerp,
)
from motionlab.validation import check_scalar, check_tensor

_FRAME_COLORS = ("tab:red", "tab:green", "tab:blue")
_PATH_STYLES = {"slerp": dict(color="tab:blue", marker="o"), "nlerp": dict(color="tab:orange", marker="x")}


def _draw_sphere(ax) -> None:
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    ax.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v), color="0.85", linewidth=0.5)


def _draw_frame(ax, q: torch.Tensor, length: float = 1.0, alpha: float = 1.0) -> None:
    axes = quat_apply(q, torch.eye(3, dtype=q.dtype)).numpy()  # rows: images of x, y, z
    for direction, color in zip(axes, _FRAME_COLORS):
        ax.quiver(0, 0, 0, *(length * direction), color=color, alpha=alpha, arrow_length_ratio=0.12)


def plot_interpolation(q0: torch.Tensor, q1: torch.Tensor, w: float, n: int = 21) -> Figure:
    """Compare slerp and nlerp from ``q0`` to ``q1`` (each ``(4,)``), with the frame at weight ``w``.

    Left: the forward axis traced on the unit sphere by both paths (``n`` samples each, at equal steps
    of ``w``; a big dot where each path is at ``w``), the start and end frames faded, the slerp frame
    at ``w`` solid. Right: the angle from ``q0`` against ``w``: a straight line for slerp (constant
    speed), an S-curve for nlerp.
    Returns the figure (created with pyplot, so the inline backend shows it).
    """
    check_scalar(w, "w", "plot_interpolation", minimum=0, maximum=1)
    for name, q in (("q0", q0), ("q1", q1)):
        check_tensor(q, name, "plot_interpolation", ndim=1, trailing=(4,), floating=False)
    q0, q1 = q0.double(), q1.double()
    paths = interpolation_paths(q0, q1, n)
    forward = torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64)

    fig = plt.figure(figsize=(10, 4.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    _draw_sphere(ax)
    at_w = {"slerp": quat_slerp(q0, q1, float(w)), "nlerp": quat_nlerp(q0, q1, float(w))}
    for name in ("slerp", "nlerp"):
        trace = quat_apply(getattr(paths, name), forward).numpy()
        ax.plot(*trace.T, linestyle="-", markersize=4, label=name, **_PATH_STYLES[name])
        ax.scatter(
            *quat_apply(at_w[name], forward).numpy(), s=90, color=_PATH_STYLES[name]["color"], edgecolor="k"
        )
    _draw_frame(ax, q0, length=0.6, alpha=0.35)
    _draw_frame(ax, q1, length=0.6, alpha=0.35)
    _draw_frame(ax, at_w["slerp"])
    ticks = (-1, 0, 1)
    ax.set(xlim=(-1, 1), ylim=(-1, 1), zlim=(-1, 1), xticks=ticks, yticks=ticks, zticks=ticks)
    ax.set(xlabel="x", ylabel="y", zlabel="z")
    ax.set_box_aspect((1, 1, 1))
    ax.set_title(f"forward axis along the paths; frame at w = {float(w):.2f}")
    ax.legend(loc="upper left")

    ax2 = fig.add_subplot(1, 2, 2)
    for name in ("slerp", "nlerp"):
        angle = torch.rad2deg(quat_geodesic(q0, getattr(paths, name))).numpy()
        ax2.plot(paths.w.numpy(), angle, linestyle="-", markersize=4, label=name, **_PATH_STYLES[name])
    ax2.axvline(float(w), color="0.5", linestyle="--")
    ax2.set(
        xlabel="interpolation weight w",
        ylabel="angle from q0 (degrees)",
        title="slerp turns at constant speed",
    )
    ax2.legend()
    fig.tight_layout()
    return fig


def show_interpolation(
    yaw0: float, pitch0: float, roll0: float, yaw1: float, pitch1: float, roll1: float, w: float
) -> Figure:
    """Widget callback: :func:`plot_interpolation` between two orientations given in degrees.

    Each orientation is intrinsic yaw (about z), pitch (new y), roll (new x), Euler order ``"ZYX"``;
    ``w`` is the interpolation weight, from 0 (the first orientation) to 1 (the second).
    """
    angles = torch.tensor([[yaw0, pitch0, roll0], [yaw1, pitch1, roll1]], dtype=torch.float64) * (
        math.pi / 180
    )
    q0, q1 = euler_to_quat(angles, "ZYX")
    return plot_interpolation(q0, q1, w)
