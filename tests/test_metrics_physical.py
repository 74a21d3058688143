"""Foot skating and bone-length error on motions built with known foot speeds and rigid bones."""

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation

from motionlab.metrics import FOOT_JOINTS, bone_length_error, bone_lengths, foot_skating, infer_foot_contacts

PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19]
FPS = 30.0


def standing(frames: int) -> np.ndarray:
    """A still pose ``(T, 22, 3)``: feet on the floor (ankles 8 cm up), everything else higher."""
    pose = np.zeros((frames, 22, 3))
    pose[..., 2] = 1.0
    pose[:, [7, 8], 2] = 0.08
    pose[:, [10, 11], 2] = 0.02
    return pose


def test_given_contacts_measure_the_planted_speed():
    motion = standing(31)
    motion[:, 7, 0] = 0.3 * np.arange(31) / FPS  # left ankle slides at 0.3 m/s, other feet still
    contacts = np.ones((31, 4), dtype=bool)
    assert foot_skating(motion, contacts, fps=FPS) == pytest.approx(0.3 / 4)


def test_only_intervals_with_contact_at_both_ends_count():
    motion = standing(5)
    motion[:, 10, 1] = [0.0, 0.1, 0.3, 0.6, 1.0]  # interval speeds 3, 6, 9, 12 m/s at 30 fps
    contacts = np.zeros((5, 4), dtype=bool)
    contacts[[0, 1, 2], 2] = True  # left foot (joint 10, third entry of FOOT_JOINTS) planted on frames 0-2
    assert FOOT_JOINTS[2] == 10
    assert foot_skating(motion, contacts, fps=FPS) == pytest.approx((3.0 + 6.0) / 2)


def test_vertical_motion_is_not_skating():
    motion = standing(10)
    motion[:, 8, 2] += np.linspace(0.0, 0.01, 10)
    assert foot_skating(motion, np.ones((10, 4)), fps=FPS) == 0.0


def walking_foot(frames: int = 60) -> np.ndarray:
    """Joint 10 alternates a planted phase (z = 0.02, sliding at 0.1 m/s) and a swing (z = 0.2, 2 m/s)."""
    motion = standing(frames)
    speed = np.where((np.arange(frames) // 15) % 2 == 0, 0.1, 2.0)
    motion[:, 10, 0] = np.concatenate([[0.0], np.cumsum(speed[:-1]) / FPS])
    motion[:, 10, 2] = np.where(speed == 0.1, 0.02, 0.2)
    return motion


def test_inferred_contacts_find_the_planted_phase():
    motion = walking_foot()
    contacts = infer_foot_contacts(motion, fps=FPS)
    assert contacts.shape == (60, 4)
    planted = (np.arange(60) // 15) % 2 == 0
    assert not contacts[~planted, 2].any()
    assert contacts[planted, 2].sum() >= planted.sum() - 4  # at most the phase-boundary frames are lost
    assert contacts[:, [0, 1, 3]].all()  # the still feet are always in contact


def test_inferred_skating_equals_the_planted_slide():
    motion = walking_foot()
    # Feet 7, 8 and 11 stand still (speed 0); foot 10 slides at 0.1 m/s while planted.
    contacts = infer_foot_contacts(motion, fps=FPS)
    both = contacts[1:] & contacts[:-1]
    expected = 0.1 * both[:, 2].sum() / both.sum()
    assert foot_skating(motion, fps=FPS) == pytest.approx(expected, rel=1e-9)
    assert foot_skating(motion, fps=FPS, feet=[10]) == pytest.approx(0.1, rel=1e-9)


def test_heights_are_relative_to_each_foot_lowest_point():
    raised = walking_foot() + np.array([0.0, 0.0, 0.5])  # the whole clip half a metre up
    assert foot_skating(raised, fps=FPS, feet=[10]) == pytest.approx(0.1, rel=1e-9)


def test_batches_pool_all_planted_intervals():
    motion = walking_foot()
    batch = np.stack([motion, motion])
    assert foot_skating(torch.from_numpy(batch), fps=FPS) == pytest.approx(
        foot_skating(motion, fps=FPS), rel=1e-12
    )


def test_speed_scales_with_the_frame_rate():
    motion = standing(20)
    motion[:, 11, 0] = 0.01 * np.arange(20)
    contacts = np.ones((20, 4))
    assert foot_skating(motion, contacts, fps=60.0) == pytest.approx(
        2 * foot_skating(motion, contacts, fps=30.0)
    )


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"contacts": np.zeros((10, 4))}, "foot_skating: no foot is in contact on two consecutive frames"),
        ({"contacts": np.ones((10, 3))}, r"foot_skating: contacts must have shape \(10, 4\)"),
        ({"contacts": np.full((10, 4), 0.5)}, "foot_skating: contacts must be booleans or 0/1"),
        ({"feet": [7, 30]}, r"foot_skating: feet must be distinct joint indices in \[0, 22\)"),
        ({"fps": 0.0}, "foot_skating: fps must be greater than 0, got 0.0"),
        ({"height_threshold": -0.1}, "foot_skating: height_threshold must be greater than 0, got -0.1"),
        ({"speed_threshold": np.nan}, "foot_skating: speed_threshold must be a finite number, got nan"),
    ],
)
def test_foot_skating_bad_inputs(kwargs, match):
    with pytest.raises(ValueError, match=match):
        foot_skating(standing(10), **kwargs)


def test_foot_skating_of_feet_never_planted_is_nan_when_asked():
    never = np.zeros((10, 4))
    assert np.isnan(foot_skating(standing(10), never, never_planted="nan"))
    assert foot_skating(standing(10), np.ones((10, 4)), never_planted="nan") == 0.0  # defined: unchanged
    with pytest.raises(ValueError, match="foot_skating: never_planted must be 'raise' or 'nan', got 'zero'"):
        foot_skating(standing(10), never, never_planted="zero")


def test_foot_skating_needs_two_frames_and_xyz():
    with pytest.raises(ValueError, match="foot_skating: positions needs at least 2 frames"):
        foot_skating(standing(1))
    with pytest.raises(ValueError, match="foot_skating: positions must end in 3 coordinates"):
        foot_skating(np.zeros((5, 22, 2)))


def rigid_motion(offsets: np.ndarray, frames: int, seed: int) -> np.ndarray:
    """Positions ``(T, J, 3)``: every bone keeps its length, each joint turned by its own random rotation."""
    joints = len(PARENTS)
    rotations = Rotation.random(frames * joints, random_state=seed).as_matrix().reshape(frames, joints, 3, 3)
    positions = np.zeros((frames, len(PARENTS), 3))
    for joint, parent in enumerate(PARENTS):
        if parent >= 0:
            positions[:, joint] = positions[:, parent] + rotations[:, joint] @ offsets[joint]
    return positions


def test_rigid_bones_have_zero_error_and_scaled_bones_a_known_one():
    offsets = np.random.default_rng(0).normal(scale=0.2, size=(22, 3))
    lengths = np.linalg.norm(offsets, axis=1)
    motion = rigid_motion(offsets, 8, seed=1)
    assert bone_length_error(motion, PARENTS, offsets) == pytest.approx(0.0, abs=1e-12)
    assert bone_length_error(motion, PARENTS, lengths) == pytest.approx(0.0, abs=1e-12)
    stretched = rigid_motion(offsets * 1.1, 8, seed=2)
    assert bone_length_error(stretched, PARENTS, offsets) == pytest.approx(
        0.1 * lengths[1:].mean(), rel=1e-10
    )


def test_bone_length_error_hand_value():
    positions = np.array([[[0.0, 0.0, 0.0], [1.2, 0.0, 0.0], [1.2, 0.0, 0.5]]])
    # bones 1.2 and 0.5 against 1.0 and 1.0: errors 0.2 and 0.5
    assert bone_length_error(positions, [-1, 0, 1], [0.0, 1.0, 1.0]) == pytest.approx(0.35)
    np.testing.assert_allclose(bone_lengths(positions, [-1, 0, 1]), [[1.2, 0.5]])


@pytest.mark.parametrize(
    "parents, reference, match",
    [
        ([-1, 0], [0.0, 1.0, 1.0], "parents must be 3 integers"),
        ([-1, 0, 5], [0.0, 1.0, 1.0], "parents must lie in"),
        ([0, 0, 1], [0.0, 1.0, 1.0], "parents must lie in"),
        ([-1, 0, 1], [1.0, 1.0], r"reference_offsets_or_lengths must be offsets \(3, 3\) or lengths \(3,\)"),
    ],
)
def test_bone_length_error_bad_inputs(parents, reference, match):
    with pytest.raises(ValueError, match=match):
        bone_length_error(np.zeros((2, 3, 3)), parents, reference)


def test_non_integer_parents_are_a_type_error():
    with pytest.raises(
        TypeError, match="bone_lengths: parents must be 3 integers .one per joint., got dtype float64"
    ):
        bone_lengths(np.zeros((2, 3, 3)), [-1.0, 0.0, 1.0])
