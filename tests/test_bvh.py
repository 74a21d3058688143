"""BVH reading and writing against an independent oracle: a minimal BVH reader written here with
scipy's ``Rotation.from_euler`` (intrinsic upper-case orders, degrees), on the real CMU clip and on
hand-written files that mix rotation orders, move non-root joints, use CRLF, tabs and scientific
notation."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation

from motionlab import skeleton
from motionlab.data.bvh import CMU_SCALE, FILE_TO_WORLD, load_bvh, parse_bvh, save_bvh
from motionlab.data.motion import Motion

CMU_FILE = Path(__file__).parent / "data" / "cmu_12_01_walk.bvh"


# ------------------------------------------------------------------------------------ the oracle


def oracle_positions(text: str) -> tuple[list[str], np.ndarray]:
    """Joint names and world positions ``(T, J, 3)`` of a well-formed BVH text, computed independently.

    One statement per line; ``{``/``}`` on their own lines. FK in the file frame with scipy, then the
    documented axis map (x, y, z)_file -> (z, x, y)_world.
    """
    lines = [line.split() for line in text.splitlines()]
    joints: list[dict] = []
    stack: list[int | None] = []
    pending: int | None = None
    row = 0
    for row, words in enumerate(lines):  # noqa: B007 (row is read after the loop)
        if not words:
            continue
        key = words[0]
        if key in ("ROOT", "JOINT"):
            joints.append({"name": words[1], "parent": stack[-1] if stack else -1})
            pending = len(joints) - 1
        elif key == "End":
            pending = None
        elif key == "{":
            stack.append(pending)
        elif key == "}":
            stack.pop()
        elif key == "OFFSET" and stack[-1] is not None:
            joints[stack[-1]]["offset"] = np.array([float(v) for v in words[1:4]])
        elif key == "CHANNELS":
            joints[stack[-1]]["channels"] = words[2:]
        elif key == "MOTION":
            break
    frames_start = (
        next(
            i
            for i in range(row, len(lines))
            if lines[i] and lines[i][0].lower().startswith("frame") and "time" in " ".join(lines[i]).lower()
        )
        + 1
    )
    data = np.array([[float(v) for v in words] for words in lines[frames_start:] if words])

    num_frames = len(data)
    rot_global: list[Rotation] = []
    pos_global: list[np.ndarray] = []
    column = 0
    for joint in joints:
        translation = np.tile(joint["offset"], (num_frames, 1))
        axes, angles = "", []
        for channel in joint["channels"]:
            if channel.endswith("position"):
                translation[:, "XYZ".index(channel[0])] = data[:, column]
            else:
                axes += channel[0]
                angles.append(data[:, column])
            column += 1
        local = (
            Rotation.from_euler(axes, np.stack(angles, axis=1), degrees=True)
            if axes
            else Rotation.identity(num_frames)
        )
        if joint["parent"] < 0:
            rot_global.append(local)
            pos_global.append(translation)
        else:
            parent_rot = rot_global[joint["parent"]]
            rot_global.append(parent_rot * local)
            pos_global.append(pos_global[joint["parent"]] + parent_rot.apply(translation))
    positions = np.stack(pos_global, axis=1)
    return [j["name"] for j in joints], positions[..., [2, 0, 1]]


# ------------------------------------------------------------------------------ hand-written files

MIXED_HIERARCHY = """HIERARCHY
ROOT Hips
{
\tOFFSET 0.5 1.5e1 -2
\tCHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation
\tJOINT Spine
\t{
\t\tOFFSET 0 10 0
\t\tCHANNELS 3 Xrotation Yrotation Zrotation
\t\tJOINT Head
\t\t{
\t\t\tOFFSET 0 8 1
\t\t\tCHANNELS 6 Zrotation Xposition Yposition Zposition Xrotation Yrotation
\t\t\tEnd Site
\t\t\t{
\t\t\t\tOFFSET 0 3 0
\t\t\t}
\t\t}
\t\tJOINT LeftArm
\t\t{
\t\t\tOFFSET 5 6 0
\t\t\tCHANNELS 3 Yrotation Zrotation Xrotation
\t\t\tEnd Site
\t\t\t{
\t\t\t\tOFFSET 7 0 0
\t\t\t}
\t\t}
\t}
\tJOINT LeftLeg
\t{
\t\tOFFSET 3 -2 0
\t\tCHANNELS 2 Zrotation Xrotation
\t\tJOINT LeftFoot
\t\t{
\t\t\tOFFSET 0 -9 0
\t\t\tCHANNELS 1 Yrotation
\t\t\tEnd Site
\t\t\t{
\t\t\t\tOFFSET 0 0 2
\t\t\t}
\t\t}
\t}
\tJOINT RightLeg
\t{
\t\tOFFSET -3 -2 0
\t\tCHANNELS 0
\t\tJOINT RightFoot
\t\t{
\t\t\tOFFSET 0 -9 0
\t\t\tCHANNELS 3 Zrotation Yrotation Xrotation
\t\t\tEnd Site
\t\t\t{
\t\t\t\tOFFSET 0 0 2
\t\t\t}
\t\t}
\t}
}
MOTION
"""
MIXED_CHANNELS = 6 + 3 + 6 + 3 + 2 + 1 + 0 + 3
MIXED_NAMES = ["Hips", "Spine", "Head", "LeftArm", "LeftLeg", "LeftFoot", "RightLeg", "RightFoot"]


def mixed_file(
    seed: int = 0,
    frames: int = 12,
    newline: str = "\n",
    frame_time: str = "Frame Time: 0.0333333",
    sci: bool = False,
    trailing: str = "",
) -> str:
    """The mixed hierarchy with random frames (angles up to ±175°, including 2-channel X beyond 90°)."""
    rng = np.random.default_rng(seed)
    data = rng.uniform(-175, 175, size=(frames, MIXED_CHANNELS))
    fmt = "{:.6e}" if sci else "{:.6f}"
    rows = [" ".join(fmt.format(v) for v in row) for row in data]
    text = MIXED_HIERARCHY + f"Frames: {frames}\n{frame_time}\n" + "\n".join(rows) + "\n" + trailing
    return text.replace("\n", newline)


@pytest.fixture(scope="module")
def cmu() -> Motion:
    return load_bvh(CMU_FILE)


# ------------------------------------------------------------------------------------ the CMU clip


def test_cmu_structure(cmu: Motion) -> None:
    assert cmu.num_joints == 31 and cmu.num_frames == 524 and cmu.fps == 120.0
    assert cmu.joint_names[:3] == ("Hips", "LHipJoint", "LeftUpLeg")
    assert cmu.parents[:6] == (-1, 0, 1, 2, 3, 4)
    assert cmu.channels[0] == ("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation")
    assert all(c == ("Zrotation", "Yrotation", "Xrotation") for c in cmu.channels[1:])
    assert len(cmu.end_sites) == 7 and cmu.joint_translations is None  # toes, head, fingers, thumbs
    assert cmu.rotations.shape == (524, 31, 4) and cmu.rotations.dtype == torch.float64
    # File OFFSET of LeftUpLeg is (2.10660, -1.59283, 1.11709); world = (z, x, y)_file.
    left_up_leg = cmu.joint_names.index("LeftUpLeg")
    np.testing.assert_allclose(cmu.offsets[left_up_leg].numpy(), [1.11709, 2.10660, -1.59283])
    # First frame's root translation (0.0265, 16.2134, -25.4911) in world axes.
    np.testing.assert_allclose(cmu.root_positions[0].numpy(), [-25.4911, 0.0265, 16.2134])


def test_cmu_positions_match_oracle(cmu: Motion) -> None:
    names, expected = oracle_positions(CMU_FILE.read_text())
    assert names == list(cmu.joint_names)
    np.testing.assert_allclose(cmu.global_positions().numpy(), expected, atol=1e-9)


def test_cmu_local_rotations_match_scipy_euler(cmu: Motion) -> None:
    """Each local rotation is from_euler("ZYX", file angles, degrees) conjugated by the axis map."""
    text_rows = [line.split() for line in CMU_FILE.read_text().splitlines()]
    data = np.array([[float(v) for v in row] for row in text_rows[187:] if row])
    perm = np.zeros((3, 3))
    perm[[0, 1, 2], [2, 0, 1]] = 1  # world = perm @ file
    for j in (0, 2, 3, 17):
        column = 3 + 3 * j
        file_rot = Rotation.from_euler("ZYX", data[:, column : column + 3], degrees=True).as_matrix()
        expected = perm @ file_rot @ perm.T
        got = Rotation.from_quat(cmu.rotations[:, j].numpy(), scalar_first=True).as_matrix()
        np.testing.assert_allclose(got, expected, atol=1e-12)


def test_file_to_world_rotation_is_the_documented_axis_map() -> None:
    rotation = Rotation.from_quat(FILE_TO_WORLD, scalar_first=True)
    np.testing.assert_allclose(rotation.apply(np.eye(3)), [[0, 1, 0], [0, 0, 1], [1, 0, 0]], atol=1e-15)
    assert np.isclose(np.linalg.det(rotation.as_matrix()), 1.0)


def test_cmu_in_metres_walks_forward_on_the_floor(cmu: Motion) -> None:
    positions = cmu.scaled(CMU_SCALE)[1:].global_positions().numpy()  # frame 0 is the added T-pose
    toes = [cmu.joint_names.index(n) for n in ("LeftToeBase", "RightToeBase")]
    head = cmu.joint_names.index("Head")
    assert -0.02 < positions[:, toes, 2].min() < 0.05  # the feet touch the floor (z up)
    assert 1.2 < positions[:, head, 2].mean() < 1.8  # the head joint of a standing adult
    assert 0.8 < positions[:, 0, 2].mean() < 1.0  # hips
    travel = positions[-1, 0] - positions[0, 0]
    assert 3.0 < travel[0] < 4.5 and abs(travel[1]) < 0.3  # walks ~3.8 m along +x, straight
    assert np.isclose(CMU_SCALE, 0.056444, atol=1e-6)


def test_scale_multiplies_every_length(cmu: Motion) -> None:
    scaled = load_bvh(CMU_FILE, scale=2.0)
    torch.testing.assert_close(scaled.global_positions(), 2.0 * cmu.global_positions())
    assert scaled.end_sites[0][1] == tuple(2.0 * v for v in cmu.end_sites[0][1])


def test_cmu_round_trip(cmu: Motion, tmp_path: Path) -> None:
    for motion in (cmu, cmu.scaled(CMU_SCALE)):
        save_bvh(motion, tmp_path / "out.bvh")
        again = load_bvh(tmp_path / "out.bvh")
        assert again.joint_names == motion.joint_names and again.channels == motion.channels
        assert again.fps == motion.fps
        expected = motion.global_positions()
        torch.testing.assert_close(
            again.global_positions(), expected, rtol=0, atol=1e-4 * expected.abs().max()
        )
        # Another reader (the oracle) sees the same motion in the written file.
        _, oracle = oracle_positions((tmp_path / "out.bvh").read_text())
        np.testing.assert_allclose(oracle, expected.numpy(), atol=1e-4 * expected.abs().max().item())


# ------------------------------------------------------------------------------ hand-written files


@pytest.mark.parametrize("newline", ["\n", "\r\n", "\r"])
@pytest.mark.parametrize("sci", [False, True])
def test_mixed_orders_and_moving_joints_match_oracle(newline: str, sci: bool) -> None:
    text = mixed_file(seed=1, newline=newline, sci=sci, trailing=newline * 2 + "  \t" + newline)
    motion = parse_bvh(text.encode())
    names, expected = oracle_positions(text.replace("\r\n", "\n").replace("\r", "\n"))
    assert list(motion.joint_names) == names == MIXED_NAMES
    assert motion.parents == (-1, 0, 1, 1, 0, 4, 0, 6)
    assert motion.joint_translations is not None  # Head has position channels
    np.testing.assert_allclose(motion.global_positions().numpy(), expected, atol=1e-9)


@pytest.mark.parametrize("order", ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"])
def test_every_rotation_order_is_intrinsic_euler(order: str) -> None:
    rng = np.random.default_rng(3)
    angles = rng.uniform(-180, 180, size=(5, 3))
    channels = " ".join(f"{a}rotation" for a in order)
    rows = "\n".join(" ".join(f"{v:.10f}" for v in row) for row in angles)
    text = (
        f"HIERARCHY\nROOT A\n{{\nOFFSET 0 0 0\nCHANNELS 3 {channels}\nEnd Site\n{{\nOFFSET 0 1 0\n}}\n}}\n"
        f"MOTION\nFrames: 5\nFrame Time: 0.1\n{rows}\n"
    )
    motion = parse_bvh(text.encode())
    file_quat = motion.rotations[:, 0].numpy()[:, [0, 2, 3, 1]]  # world -> file axes, w first
    expected = Rotation.from_euler(order, angles, degrees=True)
    got = Rotation.from_quat(file_quat, scalar_first=True)
    assert (got.inv() * expected).magnitude().max() < 1e-9


def test_byte_order_mark_and_latin1_names() -> None:
    text = mixed_file(newline="\r\n").replace("LeftArm", "Bra\u00e7oEsquerdo")
    assert parse_bvh(b"\xef\xbb\xbf" + text.encode("utf-8")).joint_names[3] == "Bra\u00e7oEsquerdo"
    assert parse_bvh(text.encode("latin-1")).joint_names[3] == "Bra\u00e7oEsquerdo"


def test_indentation_and_keyword_variants() -> None:
    text = (
        "  HIERARCHY  \nROOT   My Root {\n OFFSET\t1 2 3\nCHANNELS 3 xposition YPOSITION Zposition\n"
        "JOINT Child\n{ OFFSET 0 1 0 CHANNELS 1 Zrotation\nend site { OFFSET 0 1 0 } }\n}\n\n"
        "MOTION\n\nFrames:\t2\n\nFrame Time :  .04\n1 2 3 10\n4 5 6 20\n\n\n"
    )
    motion = parse_bvh(text.encode())
    assert motion.joint_names == ("My_Root", "Child") and motion.fps == 25.0
    np.testing.assert_allclose(motion.root_positions.numpy(), [[3, 1, 2], [6, 4, 5]])


@pytest.mark.parametrize(
    "line, fps",
    [
        ("Frame Time: 0.0333333", 30.0),
        ("Frame Time:0.0333333", 30.0),
        ("Frame Time :\t0.0333333", 30.0),
        ("Frame  Time: 3.33333e-2", 30.0),
        ("FRAME TIME: .0083333", 120.0),
        ("FrameTime: 0.0333", 30.0),
        ("Frame Time: 0.04", 25.0),
        ("Frame Time: 0.021345", 1 / 0.021345),
    ],
)
def test_frame_time_variants(line: str, fps: float) -> None:
    motion = parse_bvh(mixed_file(frame_time=line).encode())
    assert motion.fps == pytest.approx(fps, rel=1e-12)


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
def test_mixed_file_round_trip(newline: str, tmp_path: Path) -> None:
    motion = parse_bvh(mixed_file(seed=2, newline=newline).encode())
    save_bvh(motion, tmp_path / "mixed.bvh")
    again = load_bvh(tmp_path / "mixed.bvh")
    assert again.channels == motion.channels and again.end_sites == motion.end_sites
    expected = motion.global_positions()
    torch.testing.assert_close(again.global_positions(), expected, rtol=0, atol=1e-4 * expected.abs().max())
    _, oracle = oracle_positions((tmp_path / "mixed.bvh").read_text())
    np.testing.assert_allclose(oracle, expected.numpy(), atol=1e-4 * expected.abs().max().item())


# ------------------------------------------------------------------------- synthetic (SMPL) motion


def smpl_motion(seed: int = 0, frames: int = 20, dtype: torch.dtype = torch.float64) -> Motion:
    """22 SMPL-order joints, z up, metres, random local rotations and a root walking along +x."""
    rng = np.random.default_rng(seed)
    body = skeleton.body_skeleton(0)
    rotations = Rotation.random(frames * 22, rng=rng).as_quat(scalar_first=True).reshape(frames, 22, 4)
    root = np.stack(
        [np.linspace(0, 2, frames), 0.1 * np.sin(np.linspace(0, 3, frames)), np.full(frames, 0.95)], axis=1
    )
    return Motion(
        joint_names=skeleton.JOINT_NAMES,
        parents=skeleton.PARENTS,
        offsets=body.offsets,
        rotations=torch.from_numpy(rotations).to(dtype),
        root_positions=torch.from_numpy(root),
        fps=30,
    )


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
def test_synthetic_smpl_motion_round_trip(dtype: torch.dtype, tmp_path: Path) -> None:
    motion = smpl_motion(dtype=dtype)
    save_bvh(motion, tmp_path / "smpl.bvh")
    text = (tmp_path / "smpl.bvh").read_text()
    assert text.count("End Site") == 5  # feet, head, wrists
    assert "CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation" in text
    assert text.count("CHANNELS 3 Zrotation Yrotation Xrotation") == 21
    again = load_bvh(tmp_path / "smpl.bvh")
    assert again.fps == 30.0 and set(again.joint_names) == set(motion.joint_names)
    assert again.joint_names[:5] == (
        "pelvis",
        "left_hip",
        "left_knee",
        "left_ankle",
        "left_foot",
    )  # depth-first
    restored = again.reorder(motion.joint_names)
    assert restored.parents == motion.parents
    expected = motion.global_positions().to(torch.float64)
    torch.testing.assert_close(
        restored.global_positions(), expected, rtol=0, atol=1e-4 * expected.abs().max()
    )
    _, oracle = oracle_positions(text)
    names = [again.joint_names.index(n) for n in motion.joint_names]
    np.testing.assert_allclose(oracle[:, names], expected.numpy(), atol=1e-5)


def test_written_file_is_y_up_and_faces_z(tmp_path: Path) -> None:
    rest = smpl_motion(frames=1)
    rest = Motion(
        joint_names=rest.joint_names,
        parents=rest.parents,
        offsets=rest.offsets,
        rotations=torch.tensor([[[1.0, 0, 0, 0]] * 22], dtype=torch.float64),
        root_positions=torch.tensor([[0, 0, 0.95]], dtype=torch.float64),
        fps=30,
    )
    save_bvh(rest, tmp_path / "rest.bvh")
    names, world = oracle_positions((tmp_path / "rest.bvh").read_text())
    file_positions = dict(zip(names, world[0][:, [1, 2, 0]]))  # back to file axes
    assert max(file_positions, key=lambda n: file_positions[n][1]) == "head"  # y is up in the file
    assert file_positions["left_foot"][2] > file_positions["left_ankle"][2]  # toes point along +z
    assert file_positions["left_hip"][0] > 0  # the left side is +x


def test_rotation_order_argument_and_validation(tmp_path: Path) -> None:
    motion = smpl_motion(frames=4)
    save_bvh(motion, tmp_path / "xyz.bvh", rotation_order="XYZ")
    again = load_bvh(tmp_path / "xyz.bvh")
    assert again.channels[1] == ("Xrotation", "Yrotation", "Zrotation")
    torch.testing.assert_close(
        again.reorder(motion.joint_names).global_positions(), motion.global_positions(), rtol=0, atol=1e-5
    )
    with pytest.raises(
        ValueError, match="save_bvh: rotation_order must be a permutation of 'XYZ', got 'XYX'"
    ):
        save_bvh(motion, tmp_path / "bad.bvh", rotation_order="XYX")
    with pytest.raises(TypeError, match="save_bvh: rotation_order must be a string, got list"):
        save_bvh(motion, tmp_path / "bad.bvh", rotation_order=["X", "Y", "Z"])


def test_writer_refuses_what_the_channels_cannot_express(tmp_path: Path) -> None:
    motion = parse_bvh(mixed_file().encode())
    channels = list(motion.channels)
    channels[5] = ("Xrotation",)  # LeftFoot rotates about y in the file
    bad = replace(motion, channels=channels)
    with pytest.raises(ValueError, match="LeftFoot.*cannot express"):
        save_bvh(bad, tmp_path / "bad.bvh")
    channels = list(motion.channels)
    channels[2] = ("Zrotation", "Xrotation", "Yrotation")  # Head moves but would lose its positions
    with pytest.raises(ValueError, match="Head.*moves along file axis"):
        save_bvh(replace(motion, channels=channels), tmp_path / "bad.bvh")
