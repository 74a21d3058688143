"""Skeleton, body types, forward kinematics and joint impact weights, against hand computations and scipy."""

import math

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from motionlab.data import rig
from motionlab.skeleton import (
    BODY_MEASUREMENTS,
    BODY_TYPES,
    JOINT,
    JOINT_NAMES,
    PARENTS,
    Skeleton,
    average_skeleton,
    body_skeleton,
    forward_kinematics,
    joint_impact_weights,
)


def _quat_wxyz(rotation: Rotation) -> np.ndarray:
    return rotation.as_quat()[..., [3, 0, 1, 2]]


def _scipy_fk(quats: np.ndarray, root: np.ndarray, offsets: np.ndarray, parents) -> np.ndarray:
    """Independent oracle: compose scipy rotations joint by joint for one pose (J, 4)."""
    rotations = [Rotation.from_quat(q[[1, 2, 3, 0]]) for q in quats]
    glob, pos = [rotations[0]], [root]
    for j in range(1, len(parents)):
        p = parents[j]
        glob.append(glob[p] * rotations[j])
        pos.append(pos[p] + glob[p].apply(offsets[j]))
    return np.array(pos)


def test_default_skeleton_is_smpl_ordered():
    assert len(JOINT_NAMES) == 22 and JOINT_NAMES[0] == "pelvis" and JOINT_NAMES[21] == "right_wrist"
    assert PARENTS == (-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19)
    assert JOINT["left_ankle"] == 7 and JOINT["right_foot"] == 11


def test_body_types_have_realistic_different_proportions():
    broad, slender = BODY_MEASUREMENTS
    assert BODY_TYPES == ("broad", "slender")
    assert broad.stature == pytest.approx(1.755, abs=0.01)
    assert slender.stature == pytest.approx(1.619, abs=0.01)
    shoulder = [m.collar_out + m.shoulder_out for m in BODY_MEASUREMENTS]
    assert (
        shoulder[0] / broad.hip_width > shoulder[1] / slender.hip_width + 0.15
    )  # broad shoulders, narrow hips
    leg_ratio = [(m.root_height - m.hip_drop) / m.stature for m in BODY_MEASUREMENTS]
    assert leg_ratio[1] > leg_ratio[0] + 0.01  # the slender body has relatively longer legs
    lengths = [body_skeleton(i).bone_lengths() for i in range(2)]
    assert np.all(lengths[0][1:] >= lengths[1][1:] - 1e-12) and np.any(lengths[0][1:] > lengths[1][1:] + 0.01)


def test_rest_pose_stands_on_the_floor_symmetric_and_upright():
    for body, m in enumerate(BODY_MEASUREMENTS):
        skeleton = body_skeleton(BODY_TYPES[body])
        rest = skeleton.rest_positions() + [0, 0, m.root_height]
        assert rest[[JOINT["left_foot"], JOINT["right_foot"]], 2] == pytest.approx([m.ball_height] * 2)
        assert rest[:, 2].min() == pytest.approx(m.ball_height)
        assert rest[JOINT["head"], 2] + m.head_top == pytest.approx(m.stature)
        mirrored = rest * [1, -1, 1]
        partner = [n.replace("left", "#").replace("right", "left").replace("#", "right") for n in JOINT_NAMES]
        swap = [JOINT_NAMES.index(n) for n in partner]
        np.testing.assert_allclose(mirrored[swap], rest, atol=1e-12)
        assert rest[JOINT["left_foot"], 0] > rest[JOINT["left_ankle"], 0]  # feet point along +x
        assert rest[JOINT["left_hip"], 1] > 0  # left is +y


def test_skeleton_validation_and_helpers():
    chain = Skeleton(("a", "b", "c"), (-1, 0, 1), np.array([[0, 0, 0], [1.0, 0, 0], [0, 2.0, 0]]))
    assert chain.n_joints == 3 and chain.children(0) == (1,)
    np.testing.assert_allclose(chain.bone_lengths(), [0, 1, 2])
    np.testing.assert_allclose(chain.rest_positions(), [[0, 0, 0], [1, 0, 0], [1, 2, 0]])
    with pytest.raises(ValueError, match="earlier joint"):
        Skeleton(("a", "b", "c"), (-1, 2, 0), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="offsets must have shape"):
        Skeleton(("a", "b"), (-1, 0), np.zeros((3, 3)))
    with pytest.raises(
        ValueError, match=r"Skeleton: offsets contains NaN or infinite values \(first at index \(1, 0\)\)"
    ):
        Skeleton(("a", "b"), (-1, 0), np.array([[0, 0, 0], [np.nan, 0, 0]]))
    with pytest.raises(ValueError, match="unique"):
        Skeleton(("a", "a"), (-1, 0), np.zeros((2, 3)))
    with pytest.raises(
        ValueError, match=r"body_skeleton: body \(a body type name\) must be one of .*, got 'tall'"
    ):
        body_skeleton("tall")
    with pytest.raises(
        ValueError, match=r"body_skeleton: body \(an index or a name\) must be in \[0, 1\], got 2"
    ):
        body_skeleton(2)
    with pytest.raises(
        TypeError, match=r"body_skeleton: body \(an index or a name\) must be an integer, got 1.0"
    ):
        body_skeleton(1.0)


def test_forward_kinematics_hand_computed_chain():
    # root at (1, 2, 3) turned 90 degrees about z; joint 1 one metre ahead (+x) of the root, bent 90 degrees
    # about its y axis; joint 2 one metre above joint 1 in joint 1's frame.
    offsets = torch.tensor([[0.0, 0, 0], [1.0, 0, 0], [0.0, 0, 1.0]], dtype=torch.float64)
    s = math.sqrt(0.5)
    rotations = torch.tensor([[s, 0, 0, s], [s, 0, s, 0], [1.0, 0, 0, 0]], dtype=torch.float64)
    positions, global_rotations = forward_kinematics(
        rotations, torch.tensor([1.0, 2, 3], dtype=torch.float64), offsets, [-1, 0, 1]
    )
    # joint 1: root + Rz(90)(1, 0, 0) = (1, 3, 3); joint 2: + Rz(90) Ry(90) (0, 0, 1) = + Rz(90) (1, 0, 0) =
    # (0, 1, 0)
    np.testing.assert_allclose(positions.numpy(), [[1, 2, 3], [1, 3, 3], [1, 4, 3]], atol=1e-12)
    expected = _quat_wxyz(Rotation.from_euler("ZY", [90, 90], degrees=True))
    assert abs(abs(np.dot(global_rotations[2].numpy(), expected)) - 1) < 1e-12


def test_forward_kinematics_matches_scipy_and_numpy_rig():
    rng = np.random.default_rng(0)
    skeleton = body_skeleton(0)
    quats = _quat_wxyz(Rotation.random(3 * 22, random_state=1)).reshape(3, 22, 4)
    roots = rng.normal(size=(3, 3))
    positions, global_rotations = forward_kinematics(
        torch.from_numpy(quats), torch.from_numpy(roots), skeleton.offsets, PARENTS
    )
    for i in range(3):
        expected = _scipy_fk(quats[i], roots[i], skeleton.offsets, PARENTS)
        np.testing.assert_allclose(positions[i].numpy(), expected, atol=1e-12)
    matrices = Rotation.from_quat(quats.reshape(-1, 4)[:, [1, 2, 3, 0]]).as_matrix().reshape(3, 22, 3, 3)
    np_positions, np_global = rig.forward_kinematics(matrices, roots, skeleton.offsets, PARENTS)
    np.testing.assert_allclose(np_positions, positions.numpy(), atol=1e-12)
    torch_global = Rotation.from_quat(global_rotations.numpy().reshape(-1, 4)[:, [1, 2, 3, 0]]).as_matrix()
    np.testing.assert_allclose(np_global.reshape(-1, 3, 3), torch_global, atol=1e-12)


def test_forward_kinematics_batching_broadcasting_and_gradients():
    skeleton = body_skeleton(1)
    quats = torch.from_numpy(_quat_wxyz(Rotation.random(2 * 5 * 22, random_state=2)).reshape(2, 5, 22, 4))
    roots = torch.zeros(2, 5, 3, dtype=torch.float64)
    shared, _ = forward_kinematics(quats, roots, skeleton.offsets, PARENTS)
    per_clip_offsets = torch.from_numpy(np.broadcast_to(skeleton.offsets, (2, 1, 22, 3)).copy())
    per_clip, _ = forward_kinematics(quats, roots, per_clip_offsets, PARENTS)
    torch.testing.assert_close(shared, per_clip)
    scaled, _ = forward_kinematics(3.0 * quats, roots, skeleton.offsets, torch.tensor(PARENTS))
    torch.testing.assert_close(scaled, shared)  # any non-zero quaternion is normalised first
    chain_offsets = torch.tensor([[0.0, 0, 0], [0.3, 0, 0], [0, 0.2, 0.1]], dtype=torch.float64)
    torch.autograd.gradcheck(
        lambda q: forward_kinematics(q, torch.zeros(4, 3, dtype=torch.float64), chain_offsets, [-1, 0, 1])[0],
        quats[0, :4, :3].clone().requires_grad_(),
    )


def test_forward_kinematics_rejects_bad_input():
    q = torch.zeros(4, 3, 4)
    q[..., 0] = 1
    root, offsets = torch.zeros(4, 3), torch.zeros(3, 3)
    with pytest.raises(ValueError, match=r"forward_kinematics: rotations must have shape \(\.\.\., \*, 4\)"):
        forward_kinematics(q[..., :3], root, offsets, [-1, 0, 1])
    with pytest.raises(TypeError, match="forward_kinematics: rotations must be a torch.Tensor, got ndarray"):
        forward_kinematics(q.numpy(), root, offsets, [-1, 0, 1])
    with pytest.raises(TypeError, match="forward_kinematics: rotations must have a floating-point dtype"):
        forward_kinematics(q.long(), root, offsets, [-1, 0, 1])
    with pytest.raises(ValueError, match="root_positions must have shape"):
        forward_kinematics(q, torch.zeros(5, 3), offsets, [-1, 0, 1])
    with pytest.raises(ValueError, match="offsets must have shape"):
        forward_kinematics(q, root, torch.zeros(4, 3), [-1, 0, 1])
    with pytest.raises(ValueError, match="do not broadcast"):
        forward_kinematics(q, root, torch.zeros(2, 3, 3), [-1, 0, 1])
    with pytest.raises(ValueError, match="earlier joint"):
        forward_kinematics(q, root, offsets, [-1, 2, 0])
    with pytest.raises(ValueError, match="parents has 2 entries"):
        forward_kinematics(q, root, offsets, [-1, 0])
    bad = q.clone()
    bad[1, 2, 1] = float("nan")
    with pytest.raises(
        ValueError, match=r"forward_kinematics: rotations contains NaN .* \(first at index \(1, 2, 1\)\)"
    ):
        forward_kinematics(bad, root, offsets, [-1, 0, 1])
    with pytest.raises(ValueError):
        forward_kinematics(torch.zeros(4, 3, 4), root, offsets, [-1, 0, 1])  # zero quaternions


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_forward_kinematics_keeps_bones_rigid(seed):
    rng = np.random.default_rng(seed)
    skeleton = body_skeleton(int(rng.integers(2)))
    quats = torch.from_numpy(rng.normal(size=(22, 4)))
    positions, _ = forward_kinematics(quats, torch.from_numpy(rng.normal(size=3)), skeleton.offsets, PARENTS)
    bones = np.linalg.norm(positions[1:].numpy() - positions.numpy()[list(PARENTS[1:])], axis=-1)
    np.testing.assert_allclose(bones, skeleton.bone_lengths()[1:], atol=1e-12)


def test_joint_impact_weights_hand_computed():
    # root -> a (1 m) -> b (2 m); root -> c (0.5 m). Longest paths: root 3, a 2, b 0, c 0; floor 0.1 * 3.
    skeleton = Skeleton(
        ("root", "a", "b", "c"), (-1, 0, 1, 0), np.array([[0, 0, 0], [0, 0, 1.0], [2.0, 0, 0], [0, 0.5, 0]])
    )
    raw = np.array([3.0, 2.0, 0.3, 0.3])
    np.testing.assert_allclose(joint_impact_weights(skeleton), raw / raw.mean())
    np.testing.assert_allclose(joint_impact_weights(skeleton, leaf_floor=0.0), np.array([3, 2, 0, 0]) / 1.25)
    with pytest.raises(ValueError, match=r"joint_impact_weights: leaf_floor must be in \[0, 1\], got 1.5"):
        joint_impact_weights(skeleton, leaf_floor=1.5)


def test_joint_impact_weights_default_skeleton():
    weights = joint_impact_weights()
    average = average_skeleton()
    np.testing.assert_allclose(
        average.offsets, (BODY_MEASUREMENTS[0].offsets() + BODY_MEASUREMENTS[1].offsets()) / 2
    )
    assert weights.shape == (22,) and weights.mean() == pytest.approx(1.0) and weights.min() > 0
    assert weights.argmax() == JOINT["pelvis"]
    leaves = [JOINT[n] for n in ("left_foot", "right_foot", "head", "left_wrist", "right_wrist")]
    np.testing.assert_allclose(weights[leaves], weights.min())
    for name in ("hip", "knee", "shoulder", "elbow"):
        assert weights[JOINT[f"left_{name}"]] == pytest.approx(weights[JOINT[f"right_{name}"]])
    assert weights[JOINT["left_hip"]] > weights[JOINT["left_knee"]] > weights[JOINT["left_ankle"]]
    # hand computation of the longest paths on the average skeleton
    bone = dict(zip(JOINT_NAMES, average.bone_lengths()))
    leg = bone["left_knee"] + bone["left_ankle"] + bone["left_foot"]
    arm = bone["left_collar"] + bone["left_shoulder"] + bone["left_elbow"] + bone["left_wrist"]
    spine = bone["spine1"] + bone["spine2"] + bone["spine3"]
    root = max(bone["left_hip"] + leg, spine + arm, spine + bone["neck"] + bone["head"])
    assert weights[0] / weights[JOINT["left_hip"]] == pytest.approx(root / leg)
    shank_and_foot = bone["left_ankle"] + bone["left_foot"]
    assert weights[JOINT["spine3"]] / weights[JOINT["left_knee"]] == pytest.approx(arm / shank_and_foot)
