"""Headless checks of the plotting functions: return types, frame counts, geometry of what is drawn,
and shape validation. Speed is measured by ``motionlab.bench.viz``, not here."""

from __future__ import annotations

import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import torch  # noqa: E402
from IPython.display import HTML  # noqa: E402
from matplotlib.animation import FuncAnimation  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from motionlab import skeleton  # noqa: E402
from motionlab.viz import (  # noqa: E402
    GENERATED_COLOR,
    REAL_COLOR,
    Scene,
    StickFigure,
    animate,
    build_animation,
    compare_animation,
    filmstrip,
    plot_pose,
    plot_root_paths,
)
from motionlab.viz.animation import animation_frames  # noqa: E402
from motionlab.viz.stick_figure import keyframe_indices  # noqa: E402

PARENTS = list(skeleton.PARENTS)


def walk(frames: int = 12, seed: int = 0) -> np.ndarray:
    """``(T, 22, 3)``: the rest skeleton with a little noise, its root moving along +x at 1 m/s (30 fps)."""
    rest = skeleton.body_skeleton(0).rest_positions() + [0.0, 0.0, 0.95]
    rng = np.random.default_rng(seed)
    shift = np.stack([np.arange(frames) / 30, np.zeros(frames), np.zeros(frames)], axis=1)
    return rest[None] + shift[:, None] + 0.01 * rng.standard_normal((frames, 22, 3))


def embedded_frames(html: HTML) -> int:
    return len(re.findall(r'frames\[\d+\] = "data:image/png;base64,', html.data))


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def test_plot_pose_draws_every_bone_with_equal_scales() -> None:
    pose = walk(1)[0]
    ax = plt.figure().add_subplot(projection="3d")
    figure = plot_pose(ax, torch.from_numpy(pose), PARENTS, color="tab:green", label="pose")
    assert isinstance(figure, StickFigure)
    x, y, z = figure.bones.get_data_3d()
    assert len(x) == 3 * 21 and np.isnan(x[2::3]).all()  # parent, child, break for each bone
    for k, j in enumerate(j for j, p in enumerate(PARENTS) if p >= 0):
        np.testing.assert_allclose([x[3 * k + 1], y[3 * k + 1], z[3 * k + 1]], pose[j])
        np.testing.assert_allclose([x[3 * k], y[3 * k], z[3 * k]], pose[PARENTS[j]])
    ranges = np.array([np.ptp(ax.get_xlim()), np.ptp(ax.get_ylim()), np.ptp(ax.get_zlim())])
    box = np.asarray(ax.get_box_aspect())
    np.testing.assert_allclose(box / box.max(), ranges / ranges.max(), rtol=1e-9)  # same scale on x, y, z
    assert ax.get_zlim()[0] == min(0.0, pose[:, 2].min())  # the floor
    figure.set_pose(pose + 1.0)
    np.testing.assert_allclose(figure.joints.get_data_3d()[0], pose[:, 0] + 1.0)


def test_plot_pose_validates_its_input() -> None:
    ax3d = plt.figure().add_subplot(projection="3d")
    with pytest.raises(ValueError, match=r"plot_pose: pos must have shape \(J, 3\).*got \(12, 22, 3\)"):
        plot_pose(ax3d, walk(), PARENTS)
    with pytest.raises(ValueError, match="parents has 21 entries but the positions have 22 joints"):
        plot_pose(ax3d, walk(1)[0], PARENTS[:-1])
    with pytest.raises(ValueError, match=r"parents\[3\] must be -1 or the index of another joint"):
        plot_pose(ax3d, walk(1)[0], PARENTS[:3] + [3] + PARENTS[4:])
    with pytest.raises(
        ValueError, match=r"plot_pose: pos contains NaN or infinite values \(first at index \(0, 0\)\)"
    ):
        plot_pose(ax3d, np.full((22, 3), np.nan), PARENTS)
    with pytest.raises(TypeError, match="plot_pose: ax must be a 3D axis"):
        plot_pose(plt.figure().add_subplot(), walk(1)[0], PARENTS)
    with pytest.raises(TypeError, match=r"plot_pose: parents\[2\] must be an integer, got 0.5 \(float\)"):
        plot_pose(ax3d, walk(1)[0], PARENTS[:2] + [0.5] + PARENTS[3:])
    with pytest.raises(TypeError, match="plot_pose: pos must hold real numbers, got dtype <U1"):
        plot_pose(ax3d, np.full((22, 3), "a"), PARENTS)


def test_scene_keeps_proportions_and_floor() -> None:
    points = np.array([[0.0, 0.0, 0.5], [4.0, 0.2, 1.8]])
    scene = Scene.around(points, margin=0.0, min_fraction=0.3)
    assert scene.floor == 0.0
    np.testing.assert_allclose(scene.extent, [4.0, 1.2, 1.8])  # y widened to 30% of the largest
    np.testing.assert_allclose(scene.lower, [0.0, -0.5, 0.0])
    moved = scene.moved(np.array([10.0, 20.0]))
    np.testing.assert_allclose(moved.lower[:2], [8.0, 19.4])
    below = Scene.around(np.array([[0.0, 0.0, -1.0], [1.0, 1.0, 1.0]]))
    assert below.floor == -1.0


def test_filmstrip_panels_and_titles() -> None:
    fig = filmstrip(walk(30), PARENTS, n_frames=4, fps=30, title="walk")
    assert isinstance(fig, Figure)
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == ["t = 0.00 s", "t = 0.33 s", "t = 0.63 s", "t = 0.97 s"]
    assert filmstrip(walk(3), PARENTS, n_frames=6).axes[-1].get_title() == "frame 2"  # short clip: 3 panels
    np.testing.assert_array_equal(keyframe_indices(30, 4), [0, 10, 19, 29])
    with pytest.raises(ValueError, match="keyframe_indices: n_frames must be at least 1, got 0"):
        filmstrip(walk(3), PARENTS, n_frames=0)
    with pytest.raises(ValueError, match=r"filmstrip: pos must have shape \(T, J, 3\)"):
        filmstrip(np.zeros((3, 22, 2)), PARENTS)


def test_animate_returns_html_with_one_frame_per_step() -> None:
    figures_before = plt.get_fignums()
    html = animate(walk(10), PARENTS, fps=30)
    assert isinstance(html, HTML) and embedded_frames(html) == 10
    assert embedded_frames(animate(walk(10), PARENTS, fps=30, step=3)) == 4  # frames 0, 3, 6, 9
    assert plt.get_fignums() == figures_before  # no pyplot figure left behind
    assert animation_frames(10, 3) == [0, 3, 6, 9]


def test_animate_several_motions_overlaid_and_side_by_side() -> None:
    batch = np.stack([walk(8, seed=s) for s in range(3)])  # (N, T, J, 3)
    assert embedded_frames(animate(batch, PARENTS, layout="side", labels=["a", "b", "c"])) == 8
    uneven = [walk(8), walk(5)]  # the shorter one holds its last pose
    anim = build_animation(
        uneven, PARENTS, layout="overlay", colors=["red", "blue"], labels=["long", "short"]
    )
    assert isinstance(anim, FuncAnimation)
    anim._func(7)
    lines = [line for line in anim._fig.axes[0].lines if line.get_marker() == "o"]
    np.testing.assert_allclose(lines[1].get_data_3d()[0], uneven[1][4][:, 0])
    assert anim.to_jshtml().count("frames[") >= 8
    sides = build_animation(uneven, PARENTS, layout="side")
    assert len(sides._fig.axes) == 2
    extents = [np.ptp(ax.get_xlim()) for ax in sides._fig.axes]
    assert extents[0] == pytest.approx(extents[1])  # side panels share one scale
    sides.to_jshtml()


def test_camera_follows_the_root_or_shows_the_whole_path() -> None:
    motion = walk(30) + np.linspace(0, 5, 30)[:, None, None] * [1.0, 0.0, 0.0]  # travels ~6 m along +x
    following = build_animation(motion, PARENTS, follow=True)
    ax = following._fig.axes[0]
    widths = []
    for t in (0, 29):
        following._func(t)
        assert np.mean(ax.get_xlim()) == pytest.approx(motion[t, 0, 0])
        assert np.mean(ax.get_ylim()) == pytest.approx(motion[t, 0, 1])
        widths.append(np.ptp(ax.get_xlim()))
        grid = next(line for line in ax.lines if line.get_color() == "0.8")
        gx, gy, gz = (np.asarray(v) for v in grid.get_data_3d())
        assert np.nanmin(gx) >= ax.get_xlim()[0] - 1e-9 and np.nanmax(gx) <= ax.get_xlim()[1] + 1e-9
        assert np.allclose(gz, ax.get_zlim()[0])  # the grid lies on the floor
    assert widths[0] == pytest.approx(widths[1]) and widths[0] < 3.0  # a box the size of the figure
    following.to_jshtml()
    fixed = build_animation(motion, PARENTS, follow=False)
    xlim = fixed._fig.axes[0].get_xlim()
    assert xlim[0] <= motion[..., 0].min() and xlim[1] >= motion[..., 0].max()
    fixed.to_jshtml()


def test_compare_animation_is_blue_and_orange() -> None:
    real, generated = walk(6), walk(6, seed=1)
    html = compare_animation(real, generated, PARENTS, fps=30)
    assert isinstance(html, HTML) and embedded_frames(html) == 6
    assert (REAL_COLOR, GENERATED_COLOR) == ("tab:blue", "tab:orange")


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"motions": np.zeros((5, 22)), "parents": PARENTS}, r"motion 0 must have shape \(T, J, 3\)"),
        ({"motions": np.zeros((2, 2, 5, 22, 3)), "parents": PARENTS}, r"got shape \(2, 2, 5, 22, 3\)"),
        (
            {"motions": [walk(4), walk(4)[:, :21]], "parents": PARENTS},
            r"motion 1 must have shape \(T, 22, 3\)",
        ),
        ({"motions": [], "parents": PARENTS}, "no motions"),
        ({"motions": walk(4), "parents": PARENTS[:5]}, "parents has 5 entries"),
        (
            {"motions": walk(4), "parents": PARENTS, "step": 0},
            "animation_frames: step must be at least 1, got 0",
        ),
        ({"motions": walk(4), "parents": PARENTS, "layout": "grid"}, "layout must be one of"),
        ({"motions": walk(4), "parents": PARENTS, "fps": 0}, "animate: fps must be greater than 0, got 0"),
        ({"motions": [walk(4), walk(4)], "parents": PARENTS, "colors": ["red"]}, "1 colors for 2 motions"),
    ],
)
def test_animate_validates_its_input(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        animate(**kwargs)


def test_plot_root_paths_marks_start_and_end() -> None:
    paths = np.stack([walk(20, seed=s) + [0.0, s, 0.0] for s in range(3)])
    ax = plot_root_paths(torch.from_numpy(paths), labels=["a", "b", "c"], title="roots")
    assert len(ax.lines) == 9  # path, start, end per motion
    for k in range(3):
        path, start, end = ax.lines[3 * k : 3 * k + 3]
        np.testing.assert_allclose(np.stack(path.get_data(), axis=1), paths[k, :, 0, :2])
        np.testing.assert_allclose(np.ravel(start.get_data()), paths[k, 0, 0, :2])
        np.testing.assert_allclose(np.ravel(end.get_data()), paths[k, -1, 0, :2])
        assert start.get_marker() == "o" and end.get_marker() == "x"
    assert ax.get_aspect() == 1.0
    own_axis = plt.figure().add_subplot()
    assert plot_root_paths([walk(5), walk(9)], ax=own_axis, root=2) is own_axis
    np.testing.assert_allclose(np.ravel(own_axis.lines[1].get_data()), walk(5)[0, 2, :2])
    with pytest.raises(
        ValueError, match=r"plot_root_paths: root \(a joint index\) must be in \[0, 21\], got 22"
    ):
        plot_root_paths(walk(5), root=22)
    with pytest.raises(ValueError, match="2 labels for 1 motions"):
        plot_root_paths(walk(5), labels=["a", "b"])
