"""The CMU MoCap loader: its three sources, the course frame, facing, ODMO's protocol, refusals, checksums,
and the compact copy against the original."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from motionlab.data import cmu_mocap as cm
from motionlab.data.bvh import CMU_SCALE
from motionlab.skeleton import Skeleton

ORIGINAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real" / "cmu_mocap_a2m.npz"
needs_original = pytest.mark.skipif(
    not ORIGINAL.is_file(), reason=f"the original archive is not at {ORIGINAL}"
)


@pytest.fixture(scope="module")
def clips() -> cm.MocapClips:
    return cm.load_cmu_mocap()


def _write_folder(
    folder: Path, clips: dict[str, np.ndarray], rows: list[str], subfolder: bool = True
) -> Path:
    """An Action2Motion-style download: ``pose_clip.csv`` and one ``.npy`` per clip (CMU units, y up)."""
    npy_dir = folder / "mocap_3djoints" if subfolder else folder
    npy_dir.mkdir(parents=True, exist_ok=True)
    for name, positions in clips.items():
        np.save(npy_dir / f"{name}.npy", positions)
    (folder / "pose_clip.csv").write_text("\n".join(["motion,action_type", *rows]) + "\n")
    return folder


def _clip(n_frames: int, seed: int = 0, n_joints: int = cm.N_JOINTS) -> np.ndarray:
    """A random clip in CMU units, y up, around a standing height."""
    generator = np.random.default_rng(seed)
    return (generator.normal(size=(n_frames, n_joints, 3)) + [0.0, 16.0, 0.0]).astype(np.float32)


def _write_original(path: Path, clips: list[np.ndarray], action: list[int]) -> Path:
    lengths = np.array([len(c) for c in clips], dtype=np.int64)
    np.savez(
        path,
        positions=np.concatenate(clips),
        clip_start=np.cumsum(lengths) - lengths,
        clip_length=lengths,
        clip_id=np.array([f"{i + 1:02d}_01" for i in range(len(clips))]),
        action=np.array(action, dtype=np.int64),
        action_names=np.array(cm.ACTION_NAMES),
        kinematic_chain=np.array([str(list(c)) for c in cm.KINEMATIC_CHAIN]),
    )
    return path


# ----------------------------------------------------------------------------------------------------
# loading


def test_compact_copy_loads_every_clip(clips: cm.MocapClips) -> None:
    assert clips.n_clips == 1088
    assert clips.class_counts() == {
        "Walk": 474,
        "Wash": 118,
        "Run": 109,
        "Jump": 108,
        "Animal Behavior": 101,
        "Dance": 77,
        "Step": 68,
        "Climb": 33,
    }
    assert clips.lengths.sum() == 204079 and clips.lengths.min() == 3 and clips.lengths.max() == 2295
    assert all(p.dtype == np.float32 and p.shape[1:] == (20, 3) for p in clips.positions)
    assert clips.clip_id[0] == "02_01" and clips.fps == cm.FPS
    assert clips.parents == cm.PARENTS == (-1, 0, 1, 2, 1, 4, 5, 6, 1, 8, 9, 10, 0, 12, 13, 14, 0, 16, 17, 18)


def test_compact_copy_is_small_enough() -> None:
    assert (cm.DATA_DIR / cm.COMPACT_FILE).stat().st_size < 20e6


@needs_original
def test_compact_copy_matches_the_original_within_half_a_step(clips: cm.MocapClips) -> None:
    original = cm.load_cmu_mocap(ORIGINAL)
    assert original.clip_id == clips.clip_id and original.action_names == clips.action_names
    np.testing.assert_array_equal(original.action, clips.action)
    np.testing.assert_array_equal(original.lengths, clips.lengths)
    error = max(float(np.abs(a - b).max()) for a, b in zip(original.positions, clips.positions))
    assert error <= cm.QUANTUM / 2 + 1e-6  # the data card states 0.1 mm
    record = json.loads((cm.DATA_DIR / cm.CHECKSUM_FILE).read_text())
    assert record["quantum_m"] == cm.QUANTUM and record["max_abs_error_m"] <= cm.QUANTUM / 2 + 1e-12


@needs_original
def test_original_is_converted_to_metres_and_z_up() -> None:
    raw = np.load(ORIGINAL)
    first = raw["positions"][: raw["clip_length"][0]].astype(np.float64)
    loaded = cm.load_cmu_mocap(ORIGINAL).positions[0]
    expected = np.stack([first[..., 0], -first[..., 2], first[..., 1]], axis=-1) * CMU_SCALE
    np.testing.assert_allclose(loaded, expected, atol=1e-6)


def test_y_up_to_z_up_is_a_rotation_taking_y_to_z() -> None:
    assert np.isclose(np.linalg.det(cm.Y_UP_TO_Z_UP), 1.0)
    np.testing.assert_allclose(cm.y_up_to_z_up(np.array([0.0, 1.0, 0.0])), [0.0, 0.0, 1.0])


def test_course_frame_has_people_standing_upright_in_metres(clips: cm.MocapClips) -> None:
    walk = clips.subset(clips.action == clips.action_names.index("Walk"))
    frames = np.concatenate(walk.positions)
    joint = cm.JOINT
    head, pelvis = frames[:, joint["head"], 2], frames[:, joint["pelvis"], 2]
    toes = np.minimum(frames[:, joint["left_toe"], 2], frames[:, joint["right_toe"], 2])
    assert np.mean(head > pelvis) > 0.99 and np.mean(pelvis > toes) > 0.99
    assert 0.8 < np.median(pelvis - toes) < 1.1  # a pelvis about 0.9 m above the feet
    assert 1.3 < np.median(head - toes) < 1.8


# ----------------------------------------------------------------------------------------------------
# conversions


def test_heading_yaw_reads_a_known_turn(clips: cm.MocapClips) -> None:
    faced = cm.face_x(clips.positions[0])
    for yaw in (0.3, -2.0, 3.0):
        cos, sin = np.cos(yaw), np.sin(yaw)
        turned = faced[0] @ np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]]).T
        assert np.isclose(cm.heading_yaw(turned), yaw, atol=1e-9)


def test_face_x_turns_a_walk_to_face_and_travel_along_x(clips: cm.MocapClips) -> None:
    walk = clips.positions[0]  # 02_01, a straight walk
    faced = cm.face_x(walk)
    assert abs(cm.heading_yaw(faced[0])) < 1e-9
    np.testing.assert_allclose(faced[0, 0], walk[0, 0], atol=1e-6)  # turned about the first root's vertical
    np.testing.assert_allclose(faced[..., 2], walk[..., 2], atol=1e-6)
    left, right = faced[0, cm.JOINT["left_hip"]], faced[0, cm.JOINT["right_hip"]]
    assert left[1] > right[1]  # left is +y
    travel = faced[-1, 0, :2] - faced[0, 0, :2]
    assert travel[0] > 0.9 * np.linalg.norm(travel) > 1.0  # metres forward, along +x
    bones = np.linalg.norm(walk[:, 1:] - walk[:, list(cm.PARENTS[1:])], axis=-1)
    turned = np.linalg.norm(faced[:, 1:] - faced[:, list(cm.PARENTS[1:])], axis=-1)
    np.testing.assert_allclose(turned, bones, atol=1e-5)


def test_most_walks_move_forward_so_left_and_right_are_right(clips: cm.MocapClips) -> None:
    walk = clips.subset(clips.action == 0).map(cm.face_x)
    travel = np.array([p[-1, 0, :2] - p[0, 0, :2] for p in walk.positions])
    moving = np.linalg.norm(travel, axis=-1) > 0.3
    forward = travel[moving, 0] / np.linalg.norm(travel[moving], axis=-1)
    assert np.mean(forward > 0.5) > 0.75


def test_origin_and_root_relative(clips: cm.MocapClips) -> None:
    clip = clips.positions[5]
    moved = cm.first_root_at_origin(clip)
    np.testing.assert_array_equal(moved[0, 0], 0.0)
    np.testing.assert_allclose(moved - clip, np.broadcast_to(-clip[0, 0], clip.shape), atol=1e-6)
    local = cm.root_relative(clip)
    np.testing.assert_array_equal(local[:, 0], 0.0)
    np.testing.assert_allclose(local[:, 3] - local[:, 1], clip[:, 3] - clip[:, 1], atol=1e-6)


def test_skeleton_and_parents_draw(clips: cm.MocapClips) -> None:
    skeleton = clips.subset(np.arange(20)).skeleton()
    assert isinstance(skeleton, Skeleton) and skeleton.names == cm.JOINT_NAMES
    lengths = skeleton.bone_lengths()
    assert 0.03 < lengths[1:].min() and lengths.max() < 0.5
    rest = skeleton.rest_positions()
    assert rest[cm.JOINT["head"], 2] > 0 > rest[cm.JOINT["left_ankle"], 2]
    assert rest[cm.JOINT["left_shoulder"], 1] > 0 > rest[cm.JOINT["right_shoulder"], 1]
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from motionlab.viz import filmstrip

    filmstrip(clips.positions[0], clips.parents)
    plt.close("all")


# ----------------------------------------------------------------------------------------------------
# ODMO's protocol


def test_odmo_clips_drop_wash(clips: cm.MocapClips) -> None:
    bench = cm.odmo_clips(clips)
    assert bench.n_clips == 970 and len(bench.action_names) == 7 and "Wash" not in bench.action_names
    assert bench.class_counts()["Walk"] == 474 and bench.class_counts()["Climb"] == 33
    assert np.array_equal(np.unique(bench.action), np.arange(7))


def test_random_windows_crop_pad_and_start_at_the_origin(clips: cm.MocapClips) -> None:
    bench = cm.odmo_clips(clips)
    windows = cm.random_windows(bench, 100, rng=3)
    assert windows.positions.shape == (970, 100, 20, 3) and windows.positions.dtype == np.float32
    np.testing.assert_array_equal(windows.positions[:, 0, 0], 0.0)
    lengths = bench.lengths
    np.testing.assert_array_equal(windows.n_real, np.minimum(lengths, 100))
    assert np.all(windows.start + windows.n_real <= lengths)
    short = int(np.nonzero(lengths < 100)[0][0])
    n = lengths[short]
    padded = windows.positions[short]
    np.testing.assert_array_equal(padded[n:], np.broadcast_to(padded[n - 1], padded[n:].shape))
    expected = bench.positions[short] - bench.positions[short][0, 0]
    np.testing.assert_allclose(padded[:n], expected, atol=1e-6)
    long = int(np.nonzero(lengths > 300)[0][0])
    start = windows.start[long]
    piece = bench.positions[long][start : start + 100]
    np.testing.assert_allclose(windows.positions[long], piece - piece[0, 0], atol=1e-6)
    again = cm.random_windows(bench, 100, rng=3)
    np.testing.assert_array_equal(again.start, windows.start)
    assert not np.array_equal(cm.random_windows(bench, 100, rng=4).start, windows.start)


def test_stratified_indices_keep_class_shares() -> None:
    action = np.repeat(np.arange(3), [50, 30, 20])
    picked = cm.stratified_indices(action, 10, rng=0)
    np.testing.assert_array_equal(np.bincount(action[picked]), [5, 3, 2])
    assert len(set(picked.tolist())) == 10
    many = cm.stratified_indices(action, 250, rng=0)
    np.testing.assert_array_equal(np.bincount(action[many]), [125, 75, 50])
    assert set(np.bincount(many, minlength=100).tolist()) == {2, 3}  # every clip before any clip again
    odd = cm.stratified_indices(np.repeat(np.arange(3), [2, 1, 1]), 3, rng=1)
    assert len(odd) == 3


# ----------------------------------------------------------------------------------------------------
# the .npy folder layout


@pytest.mark.parametrize("subfolder", [True, False])
def test_npy_folder_layout(tmp_path: Path, subfolder: bool) -> None:
    raw = {"01_01": _clip(5, 0), "02_03": _clip(7, 1)}
    folder = _write_folder(tmp_path / "mocap", raw, ["01_01,0", ",", "02_03,dance"], subfolder)
    loaded = cm.load_cmu_mocap(folder)
    assert loaded.clip_id == ("01_01", "02_03") and loaded.action.tolist() == [0, 5]
    assert loaded.action_names == cm.ACTION_NAMES
    np.testing.assert_allclose(
        loaded.positions[1], cm.y_up_to_z_up(raw["02_03"].astype(np.float64) * CMU_SCALE), atol=1e-6
    )
    same = cm.load_cmu_mocap(folder / "pose_clip.csv")
    np.testing.assert_array_equal(same.positions[0], loaded.positions[0])


def test_write_compact_round_trip_and_determinism(tmp_path: Path) -> None:
    source = _write_original(tmp_path / "original.npz", [_clip(6, 0), _clip(4, 1)], [2, 7])
    first = cm.write_compact(source, tmp_path / "a")
    second = cm.write_compact(source, tmp_path / "b")
    assert first == second and first["max_abs_error_m"] <= cm.QUANTUM / 2 + 1e-12
    compact, original = cm.load_cmu_mocap(tmp_path / "a"), cm.load_cmu_mocap(source)
    assert compact.clip_id == original.clip_id and compact.action.tolist() == [2, 7]
    for a, b in zip(compact.positions, original.positions):
        assert np.abs(a - b).max() <= cm.QUANTUM / 2 + 1e-6
    assert cm.main(["--source", str(source), "--out", str(tmp_path / "c")]) == 0
    assert cm.main(["--source", str(tmp_path / "missing.npz"), "--out", str(tmp_path / "d")]) == 2


# ----------------------------------------------------------------------------------------------------
# refusals


@pytest.mark.parametrize(
    ("clip", "label", "message"),
    [
        (_clip(1), "0", r"clip 09_09: too short \(1 frames, at least 2\)"),
        (_clip(4, n_joints=22), "0", r"clip 09_09: positions must have shape \(T, 20, 3\), got \(4, 22, 3\)"),
        (_clip(4), "8", "clip 09_09: unknown label 8"),
        (_clip(4), "Swim", "clip 09_09: unknown label 'Swim'"),
    ],
)
def test_refuses_a_clip_it_cannot_use(tmp_path: Path, clip: np.ndarray, label: str, message: str) -> None:
    folder = _write_folder(tmp_path, {"01_01": _clip(4), "09_09": clip}, ["01_01,0", f"09_09,{label}"])
    with pytest.raises(ValueError, match=message):
        cm.load_cmu_mocap(folder)


def test_refuses_nan_naming_clip_and_place(tmp_path: Path) -> None:
    bad = _clip(4)
    bad[2, 7, 1] = np.nan
    source = _write_original(tmp_path / "original.npz", [_clip(3), bad], [0, 1])
    with pytest.raises(
        ValueError, match=r"clip 02_01: NaN or infinite position at \(frame, joint, axis\) \(2, 7, 1\)"
    ):
        cm.load_cmu_mocap(source)


def test_min_frames_is_a_knob(tmp_path: Path) -> None:
    folder = _write_folder(tmp_path, {"01_01": _clip(3)}, ["01_01,2"])
    assert cm.load_cmu_mocap(folder, cm.LoadConfig(min_frames=3)).n_clips == 1
    with pytest.raises(ValueError, match="clip 01_01: too short"):
        cm.load_cmu_mocap(folder, cm.LoadConfig(min_frames=4))
    with pytest.raises(ValueError, match="min_frames must be at least 1"):
        cm.LoadConfig(min_frames=0)
    with pytest.raises(TypeError, match="config must be a LoadConfig"):
        cm.load_cmu_mocap(folder, {"min_frames": 3})


def test_malformed_files_get_clear_messages(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="no such file or folder"):
        cm.load_cmu_mocap(tmp_path / "nothing.npz")
    text = tmp_path / "text.npz"
    text.write_text("not an archive")
    with pytest.raises(ValueError, match="is not a readable .npz archive"):
        cm.load_cmu_mocap(text)
    partial = tmp_path / "partial.npz"
    np.savez(partial, positions=np.zeros((3, 20, 3), np.float32))
    with pytest.raises(ValueError, match=r"missing arrays \['clip_start'"):
        cm.load_cmu_mocap(partial)
    with pytest.raises(ValueError, match="holds neither"):
        cm.load_cmu_mocap(tmp_path)
    (tmp_path / "pose_clip.csv").write_text("name,label\n01_01,0\n")
    with pytest.raises(ValueError, match="needs the columns 'motion' and 'action_type'"):
        cm.load_cmu_mocap(tmp_path)
    (tmp_path / "pose_clip.csv").write_text("motion,action_type\n01_01,0\n")
    with pytest.raises(ValueError, match="clip 01_01: no file"):
        cm.load_cmu_mocap(tmp_path)
    (tmp_path / "01_01.npy").write_bytes(b"garbage")
    with pytest.raises(ValueError, match=r"clip 01_01: .*01_01.npy is not a readable .npy array"):
        cm.load_cmu_mocap(tmp_path)


def test_checksum_mismatch_is_refused(tmp_path: Path) -> None:
    shutil.copy(cm.DATA_DIR / cm.COMPACT_FILE, tmp_path / cm.COMPACT_FILE)
    record = json.loads((cm.DATA_DIR / cm.CHECKSUM_FILE).read_text())
    record["sha256"]["positions_delta"] = "0" * 64
    (tmp_path / cm.CHECKSUM_FILE).write_text(json.dumps(record))
    with pytest.raises(ValueError, match="array 'positions_delta' does not match its SHA-256"):
        cm.load_cmu_mocap(tmp_path)
    assert cm.load_cmu_mocap(tmp_path, cm.LoadConfig(verify=False)).n_clips == 1088
    (tmp_path / cm.CHECKSUM_FILE).unlink()
    with pytest.raises(ValueError, match="cannot read the checksums"):
        cm.load_cmu_mocap(tmp_path)


def test_argument_checks(clips: cm.MocapClips) -> None:
    with pytest.raises(ValueError, match="names \\(an action to drop\\) must be one of"):
        clips.without_actions(["Swim"])
    with pytest.raises(ValueError, match="a mask must have shape"):
        clips.subset(np.ones(3, dtype=bool))
    with pytest.raises(ValueError, match="length must be at least 1"):
        cm.random_windows(clips, 0)
    with pytest.raises(TypeError, match="rng must be"):
        cm.random_windows(clips, 10, rng="seed")
    with pytest.raises(ValueError, match=r"must have shape \(\.\.\., 20, 3\)"):
        cm.face_x(np.zeros((4, 22, 3)))
    with pytest.raises(ValueError, match="no horizontal direction"):
        cm.heading_yaw(np.zeros((20, 3)))


# ----------------------------------------------------------------------------------------------------
# mirror map, floor levelling, splits


def test_mirror_map_swaps_sides_and_is_an_involution() -> None:
    mirror = np.array(cm.MIRROR)
    assert (mirror[mirror] == np.arange(cm.N_JOINTS)).all()
    for name, index in cm.JOINT.items():
        partner = cm.JOINT_NAMES[mirror[index]]
        if name.startswith("left_"):
            assert partner == "right_" + name[5:]
        elif name.startswith("right_"):
            assert partner == "left_" + name[6:]
        else:
            assert partner == name
    assert np.array(cm.PARENTS)[mirror][1:].tolist() == mirror[np.array(cm.PARENTS)[1:]].tolist()


def test_level_floor_puts_the_low_quantile_of_the_lowest_joint_at_zero() -> None:
    clip = _clip(40).astype(np.float64) * 0.05 + [0.0, 0.0, 0.7]
    levelled = cm.level_floor(clip, quantile=0.1)
    assert np.quantile(levelled[..., 2].min(-1), 0.1) == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(levelled[..., :2], clip[..., :2])
    np.testing.assert_allclose(np.diff(levelled[..., 2], axis=0), np.diff(clip[..., 2], axis=0))
    with pytest.raises(ValueError, match="quantile"):
        cm.level_floor(clip, quantile=1.5)


def test_split_is_stratified_disjoint_and_seeded(clips: cm.MocapClips) -> None:
    bench = cm.odmo_clips(clips)
    train, test = cm.split_clips(bench, 0.2, rng=3)
    assert train.n_clips + test.n_clips == bench.n_clips
    assert not {id(p) for p in train.positions} & {id(p) for p in test.positions}  # shared arrays, no copies
    for name, count in bench.class_counts().items():
        assert test.class_counts()[name] == min(max(round(0.2 * count), 1), count - 1)
    again = cm.split_clips(bench, 0.2, rng=3)[1]
    assert again.clip_id == test.clip_id


def test_split_refuses_a_class_with_one_clip(clips: cm.MocapClips) -> None:
    lonely = clips.subset(
        np.concatenate([np.flatnonzero(clips.action == 0)[:3], np.flatnonzero(clips.action == 2)[:1]])
    )
    with pytest.raises(ValueError, match="Run has 1 clip"):
        cm.split_clips(lonely)
