"""The synthetic generator: labels, determinism, physical plausibility, style modes and arguments."""

import numpy as np
import pytest
import torch
from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from motionlab.data import synthetic
from motionlab.data.actions import ACTION_NAMES, MODE_ACTION, MODE_NAMES
from motionlab.data.synthetic import generate, load_or_generate, load_splits
from motionlab.metrics.physical import foot_skating, infer_foot_contacts
from motionlab.skeleton import BODY_MEASUREMENTS, JOINT, forward_kinematics

FPS = 30


@pytest.fixture(scope="module")
def data():
    return generate(seed=0, n_per_mode=4)


def _speeds(positions: np.ndarray) -> np.ndarray:
    return np.linalg.norm(np.diff(positions.astype(np.float64), axis=1), axis=-1) * FPS


def _features(data) -> np.ndarray:
    """Simple per-clip features: mean and spread of the joints in the body's own frame, and root speed.

    The body frame has its origin at the pelvis, ``left`` along the hips (horizontal) and ``up`` = +z.
    """
    x = data.positions.astype(np.float64)
    rel = x - x[:, :, :1]
    left = x[:, :, JOINT["left_hip"]] - x[:, :, JOINT["right_hip"]]
    left[..., 2] = 0
    left /= np.linalg.norm(left, axis=-1, keepdims=True)
    forward = np.stack([left[..., 1], -left[..., 0], np.zeros_like(left[..., 0])], axis=-1)
    local = np.stack(
        [np.einsum("ntjc,ntc->ntj", rel, forward), np.einsum("ntjc,ntc->ntj", rel, left), rel[..., 2]], -1
    )
    local = local[:, :, 1:].reshape(len(x), data.n_frames, -1)
    speed = np.linalg.norm(np.diff(x[:, :, 0, :2], axis=1), axis=-1) * FPS
    return np.concatenate(
        [local.mean(1), local.std(1), speed.mean(1, keepdims=True), x[:, :, 0, 2].std(1)[:, None]], 1
    )


def test_catalogue_and_labels(data):
    assert ACTION_NAMES == ("walk", "jog", "jump", "lift", "wave", "kick")
    assert len(MODE_NAMES) == len(set(MODE_NAMES)) == 12
    assert all(name.startswith(ACTION_NAMES[a] + "_") for name, a in zip(MODE_NAMES, MODE_ACTION))
    assert data.n_clips == 48 and data.n_frames == 120 and int(data.fps) == FPS
    assert list(data.action_names) == list(ACTION_NAMES) and list(data.mode_names) == list(MODE_NAMES)
    np.testing.assert_array_equal(np.bincount(data.mode), [4] * 12)
    np.testing.assert_array_equal(data.action, MODE_ACTION[data.mode])
    np.testing.assert_array_equal(np.bincount(data.body), [24, 24])
    for mode in range(12):
        np.testing.assert_array_equal(np.bincount(data.body[data.mode == mode]), [2, 2])


def test_same_seed_is_bitwise_identical_and_clips_differ(data):
    again = generate(seed=0, n_per_mode=4)
    for key, value in data.arrays().items():
        np.testing.assert_array_equal(value, again.arrays()[key], err_msg=key)
    other = generate(seed=1, n_per_mode=4)
    assert not np.array_equal(other.positions, data.positions)
    flat = data.positions.reshape(data.n_clips, -1)
    assert len(np.unique(flat, axis=0)) == data.n_clips


def test_fewer_clips_per_mode_give_a_subset_and_splits_differ(data):
    small = generate(seed=0, n_per_mode=2)
    first_two = np.concatenate([np.flatnonzero(data.mode == m)[:2] for m in range(12)])
    np.testing.assert_array_equal(small.positions, data.positions[first_two])
    np.testing.assert_array_equal(small.rotations, data.rotations[first_two])
    val = generate(seed=0, n_per_mode=2, split="val")
    assert not np.any(np.all(val.positions.reshape(24, -1) == small.positions.reshape(24, -1), axis=1))


def test_forward_kinematics_of_rotations_reproduces_positions(data):
    positions, _ = forward_kinematics(
        torch.from_numpy(data.rotations),
        torch.from_numpy(data.positions[:, :, 0]),
        torch.from_numpy(data.clip_offsets()[:, None]),
        data.parents,
    )
    np.testing.assert_allclose(positions.numpy(), data.positions, atol=5e-5)
    norms = np.linalg.norm(data.rotations, axis=-1)
    np.testing.assert_allclose(norms, 1.0, atol=1e-6)
    dots = np.sum(data.rotations[:, 1:] * data.rotations[:, :-1], axis=-1)
    assert dots.min() > 0.5  # sign-continuous in time (and no jumps)


def test_rigid_bones_and_nothing_below_the_floor(data):
    x = data.positions
    bones = np.linalg.norm(x[:, :, 1:] - x[:, :, data.parents[1:]], axis=-1)
    reference = np.linalg.norm(data.clip_offsets()[:, None, 1:], axis=-1)
    np.testing.assert_allclose(bones, np.broadcast_to(reference, bones.shape), atol=1e-5)
    assert x[..., 2].min() > -0.01
    feet = [JOINT["left_foot"], JOINT["right_foot"]]
    ball = np.array([BODY_MEASUREMENTS[b].ball_height for b in data.body])
    assert np.all(x[:, :, feet, 2].min(axis=(1, 2)) >= ball - 1e-4)  # the balls of the feet touch, never sink


def test_planted_feet_do_not_slide(data):
    skating = foot_skating(data.positions, data.contacts, fps=FPS)
    assert skating < 1e-3
    for action in ("walk", "jog"):
        chosen = data.action == ACTION_NAMES.index(action)
        assert data.contacts[chosen].mean() > 0.15
        # the generic detector (low and slow) on the balls of the feet, which roll but never slide
        assert (
            foot_skating(data.positions[chosen], fps=FPS, feet=(JOINT["left_foot"], JOINT["right_foot"]))
            < 0.04
        )
    planted = data.contacts[:, :, [0, 1]]
    heights = data.positions[:, :, [JOINT["left_ankle"], JOINT["right_ankle"]], 2]
    ankle = np.array([BODY_MEASUREMENTS[b].ankle_height for b in data.body])[:, None, None]
    np.testing.assert_allclose(
        np.where(planted, heights, ankle + 0 * heights), ankle + 0 * heights, atol=1e-4
    )


def test_motion_is_smooth(data):
    acceleration = np.linalg.norm(np.diff(data.positions.astype(np.float64), 2, axis=1), axis=-1) * FPS**2
    assert acceleration.max() < 250  # m/s^2: no teleports or snaps
    assert np.percentile(acceleration, 99) < 60
    root = acceleration[:, :, 0]
    assert root.max() < 60


def test_events_start_and_end_at_rest(data):
    for action in ("jump", "lift", "kick"):
        chosen = data.positions[data.action == ACTION_NAMES.index(action)]
        speed = _speeds(chosen)
        assert speed[:, :3].max() < 1e-3 and speed[:, -3:].max() < 1e-3, action
        assert speed.max(axis=(1, 2)).min() > 0.5, action  # and something happens in between
        for frame in (0, -1):
            pose = chosen[:, frame]
            assert np.all(pose[:, JOINT["head"], 2] > pose[:, 0, 2] + 0.45)  # upright
            assert np.all(
                pose[:, [JOINT["left_wrist"], JOINT["right_wrist"]], 2] < pose[:, :1, 2]
            )  # arms down
    jumps = data.positions[data.action == ACTION_NAMES.index("jump")]
    apex = np.argmax(jumps[:, :, 0, 2], axis=1) / FPS
    assert apex.std() > 0.15 and apex.min() > 0.5 and apex.max() < 3.5  # at a random time inside the clip


def test_modes_differ_as_documented(data):
    def mean_speed(mode: str) -> np.ndarray:
        x = data.positions[data.mode == MODE_NAMES.index(mode)]
        return np.linalg.norm(x[:, -1, 0, :2] - x[:, 0, 0, :2], axis=-1) / ((data.n_frames - 1) / FPS)

    assert np.all(mean_speed("walk_hunched") < mean_speed("walk_upright").min() + 0.1)
    assert np.all(mean_speed("jog_upright") > mean_speed("walk_upright").max())
    forward, vertical = mean_speed("jump_forward"), mean_speed("jump_vertical")
    assert forward.min() > vertical.max()

    def waving_wrist_height(mode: str, side: str) -> np.ndarray:
        x = data.positions[data.mode == MODE_NAMES.index(mode)]
        return (x[:, :, JOINT[f"{side}_wrist"], 2] - x[:, :, JOINT["head"], 2]).mean(1)

    for mode, up, down in (("wave_left", "left", "right"), ("wave_right", "right", "left")):
        assert np.all(waving_wrist_height(mode, up) > 0) and np.all(waving_wrist_height(mode, down) < -0.5)

    def lowest_pelvis(mode: str) -> np.ndarray:
        return data.positions[data.mode == MODE_NAMES.index(mode), :, 0, 2].min(1)

    assert lowest_pelvis("lift_squat").max() < lowest_pelvis("lift_stoop").min() - 0.15


def test_walks_curve_and_vary_within_a_mode():
    walks = generate(seed=3, n_per_mode=12)
    chosen = walks.positions[walks.mode == MODE_NAMES.index("walk_upright")]
    step = np.diff(chosen[:, :, 0, :2].astype(np.float64), axis=1)
    heading = np.unwrap(np.arctan2(step[..., 1], step[..., 0]), axis=1)
    turn = np.abs(heading[:, -15:].mean(1) - heading[:, :15].mean(1))
    assert turn.max() > 0.4 and np.median(turn) > 0.1  # paths curve, by different amounts
    speed = np.linalg.norm(step, axis=-1).mean(1) * FPS
    assert speed.max() - speed.min() > 0.2 and len(np.unique(np.round(speed, 3))) == len(speed)
    start = chosen[:, 0, 0, :2]
    assert np.linalg.norm(start, axis=-1).max() < 0.6  # start near the origin, in random directions
    first = np.arctan2(step[:, 0, 1], step[:, 0, 0])
    assert np.ptp(first) > 2.0


def test_modes_are_separable_by_a_linear_classifier():
    train = generate(seed=0, n_per_mode=10)
    test = generate(seed=0, n_per_mode=4, split="test")
    classifier = make_pipeline(StandardScaler(), LogisticRegression(max_iter=3000))
    classifier.fit(_features(train), train.mode)
    assert (classifier.predict(_features(test)) == test.mode).mean() >= 0.95


def test_contacts_agree_with_a_height_and_speed_detector(data):
    inferred = infer_foot_contacts(data.positions, fps=FPS, height_threshold=0.02, speed_threshold=0.1)
    ground_truth = data.contacts
    assert (inferred & ground_truth).sum() / ground_truth.sum() > 0.9  # the planted frames are low and still


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"seed": -1, "n_per_mode": 2}, "generate: seed must be at least 0, got -1"),
        ({"seed": 0, "n_per_mode": 0}, "generate: n_per_mode must be at least 1, got 0"),
        ({"seed": 0, "n_per_mode": -3}, "n_per_mode"),
        ({"seed": 0, "n_per_mode": 2, "seconds": 0.0}, "generate: seconds must be at least"),
        ({"seed": 0, "n_per_mode": 2, "seconds": -1.0}, "seconds"),
        ({"seed": 0, "n_per_mode": 2, "seconds": float("nan")}, "generate: seconds must be a finite number"),
        ({"seed": 0, "n_per_mode": 2, "fps": 0}, "fps"),
        ({"seed": 0, "n_per_mode": 2, "fps": 5}, "generate: fps must be at least"),
        (
            {"seed": 0, "n_per_mode": 2, "split": "dev"},
            "generate: split must be one of 'train', 'val', 'test', got 'dev'",
        ),
    ],
)
def test_bad_arguments_raise(kwargs, message):
    with pytest.raises(ValueError, match=message):
        generate(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"seed": 1.5, "n_per_mode": 2}, r"generate: seed must be an integer, got 1.5 \(float\)"),
        ({"seed": 0, "n_per_mode": True}, "generate: n_per_mode must be an integer, got True"),
        ({"seed": 0, "n_per_mode": 2, "fps": 30.0}, "generate: fps must be an integer"),
        ({"seed": 0, "n_per_mode": 2, "seconds": "4"}, "generate: seconds must be a real number"),
    ],
)
def test_wrong_argument_types_raise_type_error(kwargs, message):
    with pytest.raises(TypeError, match=message):
        generate(**kwargs)


def test_short_clips_and_other_frame_rates_still_hold_whole_events():
    short = generate(seed=2, n_per_mode=1, seconds=1.5, fps=24)
    assert short.n_frames == 36 and int(short.fps) == 24
    speed = _speeds(short.positions)
    for action in ("jump", "lift", "kick"):
        chosen = speed[short.action == ACTION_NAMES.index(action)]
        assert chosen[:, 0].max() < 1e-3 and chosen[:, -1].max() < 1e-3


def test_load_or_generate_caches_and_recovers(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    stale = tmp_path / "data" / "synthetic_train_seed5_n1_2s_30fps_000000000000.npz"
    other = tmp_path / "data" / "synthetic_train_seed5_n2_2s_30fps_000000000000.npz"
    stale.parent.mkdir()
    stale.write_bytes(b"old")
    other.write_bytes(b"old")
    first = load_or_generate(seed=5, n_per_mode=1, seconds=2.0)
    path = synthetic.cache_path(seed=5, n_per_mode=1, seconds=2.0)
    assert path.is_file() and path.parent == tmp_path / "data"
    assert not stale.exists() and other.exists()  # an older generator's copy of these arguments is gone
    np.testing.assert_array_equal(
        load_or_generate(seed=5, n_per_mode=1, seconds=2.0).positions, first.positions
    )
    path.write_bytes(b"not an archive")
    np.testing.assert_array_equal(
        load_or_generate(seed=5, n_per_mode=1, seconds=2.0).positions, first.positions
    )
    train, val, test = load_splits(seed=5, n_per_mode=(2, 1, 1), seconds=2.0)
    assert (train.n_clips, val.n_clips, test.n_clips) == (24, 12, 12)
    assert not np.array_equal(val.positions, test.positions)
    with pytest.raises(ValueError, match="one count per split"):
        load_splits(seed=5, n_per_mode=(2, 1))
