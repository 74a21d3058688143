"""The chapter-02 data browser (motionlab.widgets.data_browser): clip selection, measurements, plots,
wiring."""

import matplotlib

matplotlib.use("Agg")

import math  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from motionlab.data.synthetic import generate  # noqa: E402
from motionlab.skeleton import PARENTS  # noqa: E402
from motionlab.widgets import data_browser  # noqa: E402
from motionlab.widgets.data_browser import (  # noqa: E402
    STILL_TOLERANCE,
    browse_clip,
    build_browser,
    mode_choices,
    plot_clip_overview,
    show_clip,
    summarise_clip,
)

FPS = 30.0
LEFT_BALL, RIGHT_BALL = 10, 11


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def walking_clip() -> tuple[np.ndarray, np.ndarray]:
    """A hand-made 61-frame clip: the root moves along +x at 1.2 m/s and the two balls of the feet touch
    down every 20 frames, left at frames 20 and 40 (x = 1.0, 2.2), right at 10, 30, 50 (x = 0.5, 1.6, 2.9)."""
    n_frames = 61
    positions = np.zeros((n_frames, 22, 3))
    positions[:, 0, 0] = 1.2 * np.arange(n_frames) / FPS
    positions[:, 0, 2] = 0.9
    contacts = np.zeros((n_frames, 4), bool)
    for column, joint, plants in (
        (2, LEFT_BALL, [(0, 0.0), (20, 1.0), (40, 2.2)]),
        (3, RIGHT_BALL, [(10, 0.5), (30, 1.6), (50, 2.9)]),
    ):
        for start, x in plants:
            contacts[start : start + 10, column] = True
            positions[start : start + 10, joint, 0] = x
    return positions, contacts


def test_summarise_clip_walk_by_hand():
    positions, contacts = walking_clip()
    summary = summarise_clip(positions, contacts, FPS)
    assert summary.speed == pytest.approx(1.2, abs=1e-12)
    # touch-downs (contact starts after a frame without contact): left 20, 40; right 10, 30, 50 (frame 0 is
    # not one)
    assert summary.stride == pytest.approx((1.2 + 1.1 + 1.3) / 3, abs=1e-12)
    assert summary.step_rate == pytest.approx(2 / (20 / FPS), abs=1e-12)
    assert summary.pelvis_rise == 0.0 and summary.pelvis_drop == 0.0
    assert summary.moving_from == pytest.approx(1 / FPS) and summary.moving_until == pytest.approx(59 / FPS)


def test_summarise_clip_one_off_event_by_hand():
    n_frames = 60
    positions = np.zeros((n_frames, 22, 3))
    positions[:, :, 2] = 1.0
    bump = np.zeros(n_frames)
    bump[15:41] = 0.3 * np.sin(np.linspace(0, math.pi, 28)[1:-1])  # zero outside frames 15..40, peak 0.3
    positions[:, 0, 2] += bump
    positions[:, 5, 0] -= 0.5 * bump  # another joint moves too
    summary = summarise_clip(positions, np.zeros((n_frames, 4), bool), FPS)
    moving = np.flatnonzero(np.abs(bump) > STILL_TOLERANCE)
    assert summary.moving_from == pytest.approx(moving[0] / FPS)
    assert summary.moving_until == pytest.approx(moving[-1] / FPS)
    assert summary.pelvis_rise == pytest.approx(bump.max(), abs=1e-12)
    assert summary.pelvis_drop == 0.0
    assert summary.speed == 0.0 and summary.stride is None and summary.step_rate is None
    assert "stride" not in summary.describe() and "moves 0.50-1.33 s" in summary.describe()


def test_summarise_clip_still_clip_never_moves():
    summary = summarise_clip(np.ones((10, 22, 3)), np.ones((10, 4), bool), FPS)
    assert summary.moving_from is None and summary.moving_until is None and summary.stride is None
    assert summary.describe() == "0.00 m/s, pelvis +0.00/-0.00 m"


@settings(max_examples=25, deadline=None)
@given(radius=st.floats(0.5, 5.0), turn_rate=st.floats(0.05, 1.0), yaw=st.floats(-math.pi, math.pi))
def test_speed_on_a_circle_matches_radius_times_turn_rate(radius, turn_rate, yaw):
    # the root circles at angular speed turn_rate (rad/s); its speed is radius * turn_rate (chords: sinc
    # factor)
    angle = yaw + turn_rate * np.arange(90) / FPS
    positions = np.zeros((90, 22, 3))
    positions[:, 0, 0], positions[:, 0, 1] = radius * np.cos(angle), radius * np.sin(angle)
    summary = summarise_clip(positions, np.zeros((90, 4), bool), FPS)
    chord = 2 * radius * math.sin(turn_rate / FPS / 2) * FPS
    assert summary.speed == pytest.approx(chord, rel=1e-9)
    assert summary.speed == pytest.approx(radius * turn_rate, rel=1e-4)


def test_summarise_clip_rejects_bad_input():
    positions, contacts = walking_clip()
    with pytest.raises(ValueError, match=r"positions must have shape \(T, J, 3\)"):
        summarise_clip(positions[:, :, :2], contacts, FPS)
    bad = positions.copy()
    bad[3, 4, 1] = np.nan
    with pytest.raises(
        ValueError, match=r"summarise_clip: positions contains NaN .* \(first at index \(3, 4, 1\)\)"
    ):
        summarise_clip(bad, contacts, FPS)
    with pytest.raises(ValueError, match="contacts must have shape"):
        summarise_clip(positions, contacts[:, :2], FPS)
    with pytest.raises(TypeError, match="contacts must be booleans"):
        summarise_clip(positions, contacts.astype(float), FPS)
    with pytest.raises(ValueError, match="feet must be distinct joint indices"):
        summarise_clip(positions, contacts, FPS, feet=(7, 8, 10, 22))
    with pytest.raises(ValueError, match="summarise_clip: fps must be greater than 0, got 0.0"):
        summarise_clip(positions, contacts, 0.0)


def test_mode_choices():
    assert mode_choices("walk") == ("upright", "hunched")
    assert mode_choices("kick") == ("front", "side")
    with pytest.raises(ValueError, match="mode_choices: action must be one of 'walk', .*, got 'run'"):
        mode_choices("run")


def test_browse_clip_is_the_first_clip_of_its_mode_and_body_in_a_larger_set():
    reference = generate(seed=3, n_per_mode=4)  # a superset: the same streams, more clips per mode
    mode_id = list(reference.mode_names).index("jump_forward")
    index = np.flatnonzero((reference.mode == mode_id) & (reference.body == 1))[0]
    clip = browse_clip("jump", "forward", "slender", 3)
    np.testing.assert_array_equal(clip.positions, reference.positions[index])
    np.testing.assert_array_equal(clip.contacts, reference.contacts[index])
    assert clip.parents == PARENTS and clip.fps == 30.0
    summary = summarise_clip(reference.positions[index], reference.contacts[index], 30.0)
    assert clip.title == f"jump_forward, slender body, seed 3: {summary.describe()}"


def test_browse_clip_returns_copies_and_walks_have_strides():
    clip = browse_clip("walk", "upright", "broad", 0)
    clip.positions[:] = 0.0
    again = browse_clip("walk", "upright", "broad", 0)
    assert np.abs(again.positions).max() > 0.5
    summary = summarise_clip(again.positions, again.contacts, again.fps)
    assert 1.0 < summary.speed < 2.0 and 1.0 < summary.stride < 2.0 and 1.4 < summary.step_rate < 2.6
    assert "stride" in again.title


def test_browse_clip_names_bad_arguments():
    with pytest.raises(ValueError, match="browse_clip: action must be one of 'walk', .*, got 'swim'"):
        browse_clip("swim", "upright", "broad", 0)
    with pytest.raises(
        ValueError,
        match=r"browse_clip: mode \(a style of 'walk'\) must be one of 'upright', 'hunched', got 'lean'",
    ):
        browse_clip("walk", "lean", "broad", 0)
    with pytest.raises(ValueError, match="browse_clip: body must be one of 'broad', 'slender', got 'tall'"):
        browse_clip("walk", "upright", "tall", 0)
    with pytest.raises(ValueError, match="browse_clip: seed must be at least 0, got -1"):
        browse_clip("walk", "upright", "broad", -1)
    for seed in (1.5, True):
        with pytest.raises(TypeError, match="browse_clip: seed must be an integer"):
            browse_clip("walk", "upright", "broad", seed)


def test_show_clip_draws_filmstrip_and_overview_of_the_clip():
    clip = browse_clip("lift", "squat", "broad", 1)
    strip, overview = show_clip("lift", "squat", "broad", 1, n_keyframes=3)
    assert len(strip.axes) == 3 and all(ax.name == "3d" for ax in strip.axes)
    assert strip.get_suptitle() == clip.title
    path_ax, feet_ax = overview.axes
    np.testing.assert_allclose(path_ax.get_lines()[0].get_xydata(), clip.positions[:, 0, :2], atol=1e-6)
    heights = [line.get_ydata() for line in feet_ax.get_lines()]
    np.testing.assert_allclose(np.stack(heights, axis=1), clip.positions[:, [7, 8, 10, 11], 2], atol=1e-6)
    assert [line.get_label() for line in feet_ax.get_lines()] == [
        "left_ankle",
        "right_ankle",
        "left_foot",
        "right_foot",
    ]


def test_plot_clip_overview_shades_only_planted_frames():
    clip = browse_clip("walk", "hunched", "slender", 0)
    fig = plot_clip_overview(clip)
    shaded = fig.axes[1].collections
    assert len(shaded) == 4
    assert all(len(band.get_paths()) >= 1 for band, column in zip(shaded, clip.contacts.T) if column.any())


@pytest.mark.filterwarnings("ignore:FigureCanvasAgg is non-interactive")
def test_build_browser_offers_the_actions_modes_and_redraws_once_per_change(monkeypatch):
    calls = []
    monkeypatch.setattr(data_browser, "show_clip", lambda *args: calls.append(args))
    browser = build_browser(seed=5, n_keyframes=2)
    (action, mode, seed_box), body = browser.children[0].children, browser.children[1]
    assert calls == [("walk", "upright", "broad", 5, 2)]
    action.value = "jump"
    assert mode.options == ("vertical", "forward")
    assert calls[-1] == ("jump", "vertical", "broad", 5, 2) and len(calls) == 2
    mode.value = "forward"
    body.value = "slender"
    seed_box.value = 7
    assert calls[-1] == ("jump", "forward", "slender", 7, 2) and len(calls) == 5
