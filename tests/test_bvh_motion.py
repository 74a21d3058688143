"""The ``Motion`` container: validation, forward kinematics, slicing, resampling, reordering, scaling."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation, Slerp

from motionlab.data.bvh import load_bvh
from motionlab.data.motion import Motion

CMU_FILE = Path(__file__).parent / "data" / "cmu_12_01_walk.bvh"


def chain(frames: int = 3, dtype: torch.dtype = torch.float64) -> Motion:
    """Root -> a -> b, each 1 unit along +x of its parent, identity rotations, root at (0, 0, 1)."""
    rotations = torch.zeros(frames, 3, 4, dtype=dtype)
    rotations[..., 0] = 1
    return Motion(
        joint_names=("root", "a", "b"),
        parents=(-1, 0, 1),
        offsets=[[0, 0, 0], [1, 0, 0], [1, 0, 0]],
        rotations=rotations,
        root_positions=torch.tensor([[0, 0, 1.0]] * frames, dtype=dtype),
        fps=30,
    )


def test_forward_kinematics_by_hand() -> None:
    motion = chain(1)
    quarter_z = torch.tensor([np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)], dtype=torch.float64)
    rotations = motion.rotations.clone()
    rotations[0, 0] = quarter_z  # root turns 90° left: its +x becomes +y
    rotations[0, 1] = quarter_z  # a turns another 90°: b lies along -x from a
    turned = replace(motion, rotations=rotations)
    expected = torch.tensor([[[0, 0, 1], [0, 1, 1], [-1, 1, 1]]], dtype=torch.float64)
    torch.testing.assert_close(turned.global_positions(), expected, rtol=0, atol=1e-12)


def test_moving_joints_use_their_translations() -> None:
    motion = chain(2)
    moving = motion.local_translations().clone()
    moving[1, 2] = torch.tensor([0.0, 0.0, 2.0], dtype=torch.float64)  # b lifts 2 up in frame 1
    lifted = replace(motion, joint_translations=moving)
    torch.testing.assert_close(
        lifted.global_positions()[1, 2], torch.tensor([1.0, 0, 3], dtype=torch.float64)
    )
    torch.testing.assert_close(
        lifted.global_positions()[0, 2], torch.tensor([2.0, 0, 1], dtype=torch.float64)
    )


@pytest.mark.parametrize(
    "change, message",
    [
        ({"joint_names": ("root", "a")}, r"parents: expected 2 entries"),
        ({"joint_names": ("root", "a", "a")}, "appears more than once"),
        ({"joint_names": ("root", "left arm", "b")}, r"joint_names\[1\]"),
        ({"parents": (0, 0, 1)}, r"parents\[0\]: joint 0 must be the root"),
        ({"parents": (-1, 2, 0)}, r"parents\[1\]: must be the index of an earlier joint"),
        ({"offsets": np.zeros((3, 2))}, r"offsets: expected shape \(3, 3\)"),
        (
            {"offsets": [[0, 0, 0], [1, 0, np.nan], [1, 0, 0]]},
            r"Motion: offsets contains NaN or infinite values \(first at index \(1, 2\)\)",
        ),
        ({"rotations": torch.ones(3, 3, 4)}, "frame 0, joint 0 .* is not a unit quaternion"),
        ({"rotations": torch.zeros(0, 3, 4)}, "at least one frame"),
        ({"rotations": torch.ones(3, 4)}, r"rotations: expected shape \(T, 3, 4\)"),
        ({"root_positions": torch.zeros(2, 3)}, r"root_positions: expected shape \(3, 3\)"),
        ({"fps": 0}, "Motion: fps must be greater than 0, got 0"),
        ({"fps": float("nan")}, "Motion: fps must be a finite number, got nan"),
        ({"channels": [("Xrotation",), ("Xrotation", "Xrotation"), ()]}, "listed twice"),
        ({"channels": [("Wrotation",), (), ()]}, "unknown channel"),
        ({"channels": [()]}, "expected 3 entries"),
        ({"end_sites": [(5, (0, 1, 0))]}, r"end_sites\[0\]"),
        ({"end_sites": [(0, (0, 1))]}, r"end_sites\[0\]"),
        (
            {"joint_translations": torch.zeros(3, 3, 3, dtype=torch.float64)},
            "row 0 .* must equal root_positions",
        ),
        (
            {"joint_translations": torch.zeros(3, 3, dtype=torch.float64)},
            r"joint_translations: expected shape",
        ),
    ],
)
def test_validation_names_the_problem(change: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        replace(chain(), **change)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"root_positions": [["a", "b", "c"]] * 3}, "Motion.root_positions: not a numeric array"),
        ({"parents": (-1, 0.0, 1)}, r"Motion: parents\[1\] must be an integer, got 0.0 \(float\)"),
        ({"joint_names": ("root", 7, "b")}, r"Motion.joint_names\[1\]: 7 is not a string"),
        ({"fps": True}, "Motion: fps must be a real number, got True"),
    ],
)
def test_wrong_types_raise_type_error(change: dict, message: str) -> None:
    with pytest.raises(TypeError, match=message):
        replace(chain(), **change)


def test_quaternions_are_renormalised_and_dtypes_follow_rotations() -> None:
    motion = chain(dtype=torch.float32)
    nearly = motion.rotations * 1.0005
    fixed = replace(motion, rotations=nearly)
    torch.testing.assert_close(fixed.rotations.norm(dim=-1), torch.ones(3, 3))
    assert fixed.offsets.dtype == fixed.root_positions.dtype == torch.float32
    assert "3 joints, 3 frames at 30 fps" in repr(fixed)


def test_slicing_keeps_frames_and_divides_fps() -> None:
    motion = load_bvh(CMU_FILE)
    walk = motion[1:]
    assert walk.num_frames == 523 and walk.fps == 120.0
    torch.testing.assert_close(walk.rotations, motion.rotations[1:])
    every_other = motion[::2]
    assert every_other.num_frames == 262 and every_other.fps == 60.0
    with pytest.raises(ValueError, match="selects no frames"):
        motion[600:]
    with pytest.raises(ValueError, match="step"):
        motion[::0]
    with pytest.raises(TypeError, match="sliced by frames"):
        motion[3]


def test_resample_mocap_to_30_fps_hits_every_fourth_frame() -> None:
    walk = load_bvh(CMU_FILE)[1:]
    slow = walk.resample(30)
    assert slow.fps == 30.0 and slow.num_frames == 131  # 522 / 4 + 1
    torch.testing.assert_close(slow.global_positions(), walk.global_positions()[::4], rtol=0, atol=1e-9)


def test_resample_interpolates_between_frames() -> None:
    motion = chain(2)
    rotations = motion.rotations.clone()
    rotations[1, 1] = torch.from_numpy(Rotation.from_euler("z", 40, degrees=True).as_quat(scalar_first=True))
    roots = torch.tensor([[0, 0, 1.0], [2, 0, 1.0]], dtype=torch.float64)
    two = replace(motion, rotations=rotations, root_positions=roots, fps=1)
    fine = two.resample(4)
    assert fine.num_frames == 5
    torch.testing.assert_close(
        fine.root_positions[:, 0], torch.tensor([0, 0.5, 1, 1.5, 2], dtype=torch.float64)
    )
    slerp = Slerp([0, 1], Rotation.from_quat(rotations[:, 1].numpy(), scalar_first=True))
    expected = slerp([0, 0.25, 0.5, 0.75, 1])
    got = Rotation.from_quat(fine.rotations[:, 1].numpy(), scalar_first=True)
    errors = np.rad2deg((got.inv() * expected).magnitude())
    assert errors[[0, 2, 4]].max() < 1e-9 and errors.max() < 0.2  # nlerp: exact at the ends and middle
    flipped = rotations.clone()
    flipped[1] = -flipped[1]  # the same rotations with the other sign
    torch.testing.assert_close(
        replace(two, rotations=flipped).resample(4).global_positions(), fine.global_positions()
    )
    up = replace(motion, fps=10).resample(30)
    assert up.num_frames == 4  # (2 - 1) frames of 0.1 s = 3 frames of 1/30 s, plus the first
    with pytest.raises(ValueError, match="Motion.resample: fps must be greater than 0, got -1"):
        motion.resample(-1)


def test_reorder_permutes_everything() -> None:
    motion = load_bvh(CMU_FILE)[:5]
    names = list(motion.joint_names)
    order = [0] + list(range(6, 11)) + list(range(1, 6)) + list(range(11, 31))  # right leg before left
    shuffled = motion.reorder([names[i] for i in order])
    torch.testing.assert_close(shuffled.global_positions(), motion.global_positions()[:, order])
    assert shuffled.parents[1] == 0 and shuffled.parents[6] == 0
    assert shuffled.channels == tuple(motion.channels[i] for i in order)
    assert sorted(j for j, _ in shuffled.end_sites) == sorted(order.index(j) for j, _ in motion.end_sites)
    with pytest.raises(ValueError, match="permutation"):
        motion.reorder(names[:-1])
    with pytest.raises(ValueError, match=r"parents\["):
        motion.reorder(names[1:2] + names[:1] + names[2:])  # a child before its parent


def test_scaled() -> None:
    motion = load_bvh(CMU_FILE)[:3]
    torch.testing.assert_close(motion.scaled(0.5).global_positions(), 0.5 * motion.global_positions())
    with pytest.raises(ValueError, match="Motion.scaled: factor must be greater than 0, got 0"):
        motion.scaled(0)
