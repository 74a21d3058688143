"""Tests of motionlab.data.augment: mirroring and yaw rotation.

Oracles: scipy's Rotation (reflected rotation matrices, turned positions), forward kinematics, and the
representations' features (which mirroring and turning must change in known ways only).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation
from test_representations import make_clips

from motionlab.data.augment import (
    DEFAULT_MIRROR,
    mirror_permutation,
    mirror_positions,
    mirror_rotations,
    random_mirror,
    random_yaw,
    rotate_yaw,
)
from motionlab.data.representations import (
    ROOT_FEATURES,
    heading_yaw,
    representation,
    to_moglow,
    to_motion_cell,
)
from motionlab.skeleton import JOINT, JOINT_NAMES, PARENTS, body_skeleton, forward_kinematics

REFLECT = np.diag([1.0, -1.0, 1.0])


@pytest.fixture(scope="module")
def clips():
    return make_clips(n_clips=4, n_frames=30, seed=7)


def test_default_mirror_swaps_left_and_right_joints():
    expected = list(range(22))
    for left, right in [(1, 2), (4, 5), (7, 8), (10, 11), (13, 14), (16, 17), (18, 19), (20, 21)]:
        expected[left], expected[right] = right, left
    assert DEFAULT_MIRROR.tolist() == expected
    assert JOINT_NAMES[DEFAULT_MIRROR[JOINT["left_wrist"]]] == "right_wrist"
    with pytest.raises(ValueError, match="'left_ear' has no partner 'right_ear'"):
        mirror_permutation(["pelvis", "left_ear"])


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_mirroring_twice_is_the_identity(seed):
    gen = torch.Generator().manual_seed(seed)
    positions = torch.randn(3, 22, 3, generator=gen, dtype=torch.float64)
    rotations = torch.randn(3, 22, 4, generator=gen, dtype=torch.float64)
    assert torch.equal(mirror_positions(mirror_positions(positions)), positions)
    assert torch.equal(mirror_rotations(mirror_rotations(rotations)), rotations)


def test_mirrored_quaternion_is_the_reflected_rotation():
    rotations = Rotation.random(22, random_state=2)
    q = torch.tensor(np.roll(rotations.as_quat(), 1, axis=-1))
    mirrored = mirror_rotations(q)[DEFAULT_MIRROR]  # undo the swap: compare joint by joint
    matrices = Rotation.from_quat(np.roll(mirrored.numpy(), -1, axis=-1)).as_matrix()
    np.testing.assert_allclose(matrices, REFLECT @ rotations.as_matrix() @ REFLECT, atol=1e-12)


@pytest.mark.parametrize("body", [0, 1])
def test_body_types_are_left_right_symmetric(body):
    offsets = torch.tensor(body_skeleton(body).offsets)
    torch.testing.assert_close(mirror_positions(offsets), offsets, rtol=0, atol=0)


def test_forward_kinematics_of_mirrored_rotations_gives_mirrored_positions(clips):
    mirrored_rotations = mirror_rotations(clips.rotations)
    mirrored_root = clips.root_positions * clips.root_positions.new_tensor([1.0, -1.0, 1.0])
    mirrored_offsets = mirror_positions(clips.offsets)  # equal to the offsets (symmetric bodies), used anyway
    positions = forward_kinematics(
        mirrored_rotations, mirrored_root, mirrored_offsets[clips.body][:, None], PARENTS
    )[0]
    torch.testing.assert_close(positions, mirror_positions(clips.positions), rtol=0, atol=1e-12)
    # an asymmetric skeleton needs its offsets mirrored too
    lopsided = clips.offsets[0].clone()
    lopsided[JOINT["left_elbow"], 0] = 0.05
    positions = forward_kinematics(clips.rotations, clips.root_positions, lopsided, PARENTS)[0]
    mirrored = forward_kinematics(mirrored_rotations, mirrored_root, mirror_positions(lopsided), PARENTS)[0]
    torch.testing.assert_close(mirrored, mirror_positions(positions), rtol=0, atol=1e-12)


def test_mirroring_flips_sideways_motion_yaw_rate_and_roll(clips):
    mirrored_rotations = mirror_rotations(clips.rotations)
    mirrored_root = mirror_positions(clips.positions)[..., 0, :]
    original = dict(
        zip(ROOT_FEATURES, to_motion_cell(clips.rotations, clips.root_positions)[..., 84:].unbind(-1))
    )
    flipped = dict(zip(ROOT_FEATURES, to_motion_cell(mirrored_rotations, mirrored_root)[..., 84:].unbind(-1)))
    for name, sign in [
        ("forward_velocity", 1),
        ("sideways_velocity", -1),
        ("root_height", 1),
        ("yaw_rate", -1),
        ("pitch", 1),
        ("roll", -1),
    ]:
        torch.testing.assert_close(flipped[name], sign * original[name], rtol=0, atol=1e-12)
    control = to_moglow(clips.positions, clips.rotations[..., 0, :])[..., 64:]
    mirrored_control = to_moglow(mirror_positions(clips.positions), mirrored_rotations[..., 0, :])[..., 64:]
    torch.testing.assert_close(
        mirrored_control, control * control.new_tensor([1.0, -1.0, -1.0]), rtol=0, atol=1e-12
    )


def test_random_mirror_is_seeded_and_follows_its_draws(clips):
    positions, rotations = random_mirror(clips.positions, clips.rotations, torch.Generator().manual_seed(5))
    again = random_mirror(clips.positions, clips.rotations, torch.Generator().manual_seed(5))
    assert torch.equal(positions, again[0]) and torch.equal(rotations, again[1])
    flip = torch.rand(4, generator=torch.Generator().manual_seed(5)) < 0.5
    assert 0 < int(flip.sum()) < 4  # this seed mirrors some clips and keeps others
    for i in range(4):
        expected = mirror_positions(clips.positions[i]) if flip[i] else clips.positions[i]
        assert torch.equal(positions[i], expected)
        expected = mirror_rotations(clips.rotations[i]) if flip[i] else clips.rotations[i]
        assert torch.equal(rotations[i], expected)
    never = random_mirror(clips.positions, clips.rotations, torch.Generator().manual_seed(5), p=0.0)
    assert torch.equal(never[0], clips.positions)
    always = random_mirror(clips.positions, clips.rotations, torch.Generator().manual_seed(5), p=1.0)
    assert torch.equal(always[1], mirror_rotations(clips.rotations))


def test_rotate_yaw_matches_scipy_and_forward_kinematics(clips):
    angle = torch.tensor([0.3, -2.0, 3.1, 1.0], dtype=torch.float64)
    positions, rotations = rotate_yaw(clips.positions, clips.rotations, angle)
    for i in range(4):
        turn = Rotation.from_euler("z", [angle[i].item()])
        expected = turn.apply(clips.positions[i].reshape(-1, 3).numpy()).reshape(30, 22, 3)
        np.testing.assert_allclose(positions[i].numpy(), expected, atol=1e-12)
    assert torch.equal(rotations[..., 1:, :], clips.rotations[..., 1:, :])
    root = positions[..., 0, :]
    posed = forward_kinematics(rotations, root, clips.offsets[clips.body][:, None], PARENTS)[0]
    torch.testing.assert_close(posed, positions, rtol=0, atol=1e-12)
    turned = heading_yaw(rotations[..., 0, :]) - heading_yaw(clips.rotations[..., 0, :])
    torch.testing.assert_close(
        torch.remainder(turned - angle[:, None] + math.pi, 2 * math.pi) - math.pi,
        torch.zeros_like(turned),
        rtol=0,
        atol=1e-12,
    )


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_random_yaw_preserves_bones_heights_and_heading_frame_features(seed):
    clips = make_clips(n_clips=2, n_frames=8, seed=seed % 1000)
    positions, rotations = random_yaw(clips.positions, clips.rotations, torch.Generator().manual_seed(seed))
    parents = torch.tensor(PARENTS[1:])
    bones = lambda p: torch.linalg.vector_norm(p[..., 1:, :] - p[..., parents, :], dim=-1)  # noqa: E731
    torch.testing.assert_close(bones(positions), bones(clips.positions), rtol=0, atol=1e-12)
    torch.testing.assert_close(positions[..., 2], clips.positions[..., 2], rtol=0, atol=0)
    for name in ("motion_cell", "moglow"):
        rep = representation(name)
        torch.testing.assert_close(
            rep.encode(positions, rotations), rep.encode(clips.positions, clips.rotations), rtol=0, atol=1e-12
        )


def test_random_yaw_is_seeded_and_uniform(clips):
    first = random_yaw(clips.positions, clips.rotations, torch.Generator().manual_seed(11))
    second = random_yaw(clips.positions, clips.rotations, torch.Generator().manual_seed(11))
    assert all(torch.equal(a, b) for a, b in zip(first, second))
    angle = (
        2 * torch.rand(4, generator=torch.Generator().manual_seed(11), dtype=torch.float64) - 1
    ) * math.pi
    expected = rotate_yaw(clips.positions, clips.rotations, angle)
    assert all(torch.equal(a, b) for a, b in zip(first, expected))
    many = torch.zeros(4000, 1, 1, 3)
    turned, _ = random_yaw(
        many + torch.tensor([1.0, 0.0, 0.0]),
        torch.ones(4000, 1, 1, 4) * 0.5,
        torch.Generator().manual_seed(0),
    )
    angles = torch.atan2(turned[:, 0, 0, 1], turned[:, 0, 0, 0])
    counts = torch.histc(angles, bins=8, min=-math.pi, max=math.pi)
    assert counts.min() > 400 and counts.max() < 600  # 500 expected per bin


def test_augment_errors():
    with pytest.raises(ValueError, match=r"mirror_positions: permutation must be a permutation of 5"):
        mirror_positions(torch.zeros(5, 3))
    with pytest.raises(ValueError, match=r"random_mirror: p \(a probability\) must be in \[0, 1\], got"):
        random_mirror(torch.zeros(2, 22, 3), torch.zeros(2, 22, 4), torch.Generator(), p=1.5)
    with pytest.raises(ValueError, match=r"rotate_yaw: angle must have the clips' leading shape \(2,\)"):
        rotate_yaw(torch.zeros(2, 3, 22, 3), torch.ones(2, 3, 22, 4), torch.zeros(3))
    with pytest.raises(ValueError, match="must share"):
        random_yaw(torch.zeros(2, 3, 22, 3), torch.ones(2, 3, 21, 4), torch.Generator())
    with pytest.raises(ValueError, match="contains NaN"):
        mirror_rotations(torch.full((22, 4), float("nan")))
