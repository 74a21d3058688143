"""Tests of motionlab.data.representations: heading split, root control, the four representations.

Oracles: scipy's Rotation (heading split), hand-computed circles and straight lines (root control),
and round trips through forward kinematics on smooth random motions (:func:`make_clips`, also used by
the augmentation and data-set tests).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from motionlab.data.representations import (
    REPRESENTATION_NAMES,
    ROOT_FEATURES,
    RootStart,
    from_moglow,
    from_motion_cell,
    from_odmo,
    from_trajevae,
    heading_yaw,
    integrate_root_control,
    representation,
    root_control,
    root_start,
    split_heading,
    to_moglow,
    to_motion_cell,
    to_odmo,
    to_trajevae,
    yaw_to_quat,
)
from motionlab.geometry import axis_angle_to_quat, quat_mul
from motionlab.skeleton import PARENTS, body_skeleton, forward_kinematics

FPS = 30.0


def make_clips(
    n_clips: int = 3, n_frames: int = 40, seed: int = 0, dtype: torch.dtype = torch.float64, n_modes: int = 3
) -> SimpleNamespace:
    """Smooth random motions in the generator's format, posed with forward kinematics.

    Local joint rotations are sums of two slow sinusoids per axis (up to 0.4 rad each); the root
    walks at 0.5-1.5 m/s along a curving path with a little sideways sway, bobs around 0.9 m and
    tilts up to ~0.2 rad about a random axis. Returns positions ``(N, T, 22, 3)``, rotations
    ``(N, T, 22, 4)``, action/mode/body ``(N,)`` int64 and the per-body ``offsets (2, 22, 3)``.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames) / FPS
    n_joints = len(PARENTS)
    amplitude = rng.uniform(-0.4, 0.4, (n_clips, 2, 1, n_joints, 3))
    frequency = rng.uniform(0.3, 2.0, (n_clips, 2, 1, n_joints, 3))
    phase = rng.uniform(0, 2 * np.pi, (n_clips, 2, 1, n_joints, 3))
    rotvec = (amplitude * np.sin(2 * np.pi * frequency * t[None, None, :, None, None] + phase)).sum(axis=1)

    yaw0 = rng.uniform(-np.pi, np.pi, (n_clips, 1))
    turn = rng.uniform(-1.5, 1.5, (n_clips, 1))
    yaw = yaw0 + turn * t + 0.2 * np.sin(2 * np.pi * 0.7 * t)
    tilt = 0.12 * np.sin(
        2 * np.pi * rng.uniform(0.5, 1.5, (n_clips, 1, 3)) * t[None, :, None]
        + rng.uniform(0, 2 * np.pi, (n_clips, 1, 3))
    )
    root = Rotation.from_euler("z", yaw.reshape(-1, 1)) * Rotation.from_rotvec(tilt.reshape(-1, 3))
    root_quat = np.roll(root.as_quat(), 1, axis=-1).reshape(n_clips, n_frames, 4)  # scipy is (x, y, z, w)

    speed = rng.uniform(0.5, 1.5, (n_clips, 1))
    sway = 0.1 * np.sin(2 * np.pi * 1.0 * t)
    velocity = np.stack(
        [speed * np.cos(yaw) - sway * np.sin(yaw), speed * np.sin(yaw) + sway * np.cos(yaw)], -1
    )
    xy = rng.uniform(-2, 2, (n_clips, 1, 2)) + np.cumsum(velocity / FPS, axis=1)
    height = 0.9 + 0.03 * np.sin(2 * np.pi * 1.8 * t) * np.ones((n_clips, 1))
    root_positions = torch.tensor(np.concatenate([xy, height[..., None]], -1), dtype=dtype)

    rotations = axis_angle_to_quat(torch.tensor(rotvec, dtype=dtype))
    rotations[:, :, 0] = torch.tensor(root_quat, dtype=dtype)
    body = torch.tensor(rng.integers(0, 2, n_clips))
    offsets = torch.tensor(np.stack([body_skeleton(b).offsets for b in range(2)]), dtype=dtype)
    positions, _ = forward_kinematics(rotations, root_positions, offsets[body][:, None], PARENTS)
    return SimpleNamespace(
        positions=positions,
        rotations=rotations,
        root_positions=root_positions,
        action=torch.tensor(rng.integers(0, 4, n_clips)),
        mode=torch.arange(n_clips) % n_modes,
        body=body,
        offsets=offsets,
    )


@pytest.fixture(scope="module")
def clips() -> SimpleNamespace:
    return make_clips()


def _same_rotation(q1: torch.Tensor, q2: torch.Tensor) -> torch.Tensor:
    """Largest 1 - |<q1, q2>| (zero when every pair is the same rotation, whatever the sign)."""
    return (1 - (q1 * q2).sum(-1).abs()).max()


def _scipy_quat(q: torch.Tensor) -> Rotation:
    return Rotation.from_quat(np.roll(q.reshape(-1, 4).numpy(), -1, axis=-1))


# ----------------------------------------------------------------------------------------------------
# heading


def test_split_heading_matches_scipy_shortest_arc_oracle():
    rotations = Rotation.random(200, random_state=1)
    keep = np.abs(rotations.apply([0, 0, 1])[:, 2] + 1) > 1e-3  # not upside down
    rotations = rotations[keep]
    q = torch.tensor(np.roll(rotations.as_quat(), 1, axis=-1))
    yaw, tilt = split_heading(q)
    # yaw_to_quat(yaw) ⊗ tilt rebuilds the rotation, and the tilt's axis is horizontal
    rebuilt = Rotation.from_euler("z", yaw.numpy()[:, None]) * _scipy_quat(tilt)
    np.testing.assert_allclose(rebuilt.as_matrix(), rotations.as_matrix(), atol=1e-12)
    tilt_vector = _scipy_quat(tilt).as_rotvec()
    np.testing.assert_allclose(tilt_vector[:, 2], 0, atol=1e-12)
    # the tilt is the shortest arc from world up to the pelvis's up axis seen in the heading frame
    up = (Rotation.from_euler("z", -yaw.numpy()[:, None]) * rotations).apply([0, 0, 1])
    axis = np.cross([0, 0, 1], up)
    expected = (
        axis / np.linalg.norm(axis, axis=-1, keepdims=True) * np.arccos(np.clip(up[:, 2], -1, 1))[:, None]
    )
    np.testing.assert_allclose(tilt_vector, expected, atol=1e-9)
    assert bool(((yaw >= -math.pi) & (yaw < math.pi)).all())


@pytest.mark.parametrize(
    "yaw, pitch, roll", [(0.3, 0.0, 0.0), (-2.5, 0.4, 0.0), (1.2, 0.0, -0.3), (3.0, 0.2, 0.1)]
)
def test_motion_cell_root_angles_by_hand(yaw, pitch, roll):
    # a root turned by `yaw` about z after a tilt with rotation vector (roll, pitch, 0)
    q = quat_mul(
        yaw_to_quat(torch.tensor(yaw, dtype=torch.float64)),
        axis_angle_to_quat(torch.tensor([roll, pitch, 0.0], dtype=torch.float64)),
    )
    rotations = torch.zeros(2, 3, 4, dtype=torch.float64)
    rotations[..., 0] = 1
    rotations[:, 0] = q
    features = to_motion_cell(rotations, torch.zeros(2, 3, dtype=torch.float64))
    root = dict(zip(ROOT_FEATURES, features[1, -6:].tolist()))
    assert heading_yaw(q).item() == pytest.approx(yaw, abs=1e-12)
    assert root["pitch"] == pytest.approx(pitch, abs=1e-12)
    assert root["roll"] == pytest.approx(roll, abs=1e-12)


def test_pitch_sign_leans_forward_and_heading_ignores_lean():
    # a root facing +y (yaw pi/2) and leaning forward: its up axis points partly along +y
    q = quat_mul(yaw_to_quat(torch.tensor(math.pi / 2)), axis_angle_to_quat(torch.tensor([0.0, 0.5, 0.0])))
    up = _scipy_quat(q).apply([0, 0, 1])[0]
    assert up[1] > 0.4 and abs(up[0]) < 1e-6
    assert heading_yaw(q).item() == pytest.approx(math.pi / 2, abs=1e-6)


def test_split_heading_rejects_upside_down_root():
    upside_down = torch.tensor([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match=r"index \(1,\) is upside down"):
        split_heading(upside_down)


# ----------------------------------------------------------------------------------------------------
# root control


def test_root_control_on_a_circle_by_hand():
    radius, turn, n_frames = 2.0, 0.05, 30
    angle = turn * torch.arange(n_frames, dtype=torch.float64)
    xy = radius * torch.stack([torch.sin(angle), 1 - torch.cos(angle)], -1)  # counter-clockwise, facing along
    control = root_control(xy, angle)
    torch.testing.assert_close(control[0], torch.zeros(3, dtype=torch.float64))
    # the chord from t-1 to t is 2 r sin(w/2) long and points w/2 left of the heading at t-1
    expected = torch.tensor(
        [radius * math.sin(turn), radius * (1 - math.cos(turn)), turn], dtype=torch.float64
    )
    torch.testing.assert_close(control[1:], expected.expand(n_frames - 1, 3), rtol=0, atol=1e-12)


def test_root_control_straight_sidestep_to_the_left():
    # facing -x (yaw pi) and stepping towards -y: that is the character's left
    xy = torch.stack([torch.zeros(5), -0.1 * torch.arange(5.0)], -1)
    control = root_control(xy, torch.full((5,), math.pi))
    torch.testing.assert_close(control[1:], torch.tensor([0.0, 0.1, 0.0]).expand(4, 3), rtol=0, atol=1e-6)


def test_yaw_rate_wraps_across_pi():
    yaw = torch.tensor([3.1, -3.1])  # a small left turn through the back
    assert root_control(torch.zeros(2, 2), yaw)[1, 2].item() == pytest.approx(2 * math.pi - 6.2, abs=1e-5)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n_frames=st.integers(1, 12))
def test_integrate_root_control_inverts_root_control(seed, n_frames):
    gen = torch.Generator().manual_seed(seed)
    xy = torch.randn(2, n_frames, 2, generator=gen, dtype=torch.float64)
    yaw = 4 * torch.randn(2, n_frames, generator=gen, dtype=torch.float64)
    back_xy, back_yaw = integrate_root_control(root_control(xy, yaw), xy[:, 0], yaw[:, 0])
    torch.testing.assert_close(back_xy, xy, rtol=0, atol=1e-10)
    torch.testing.assert_close(
        torch.remainder(back_yaw - yaw + math.pi, 2 * math.pi) - math.pi,
        torch.zeros_like(yaw),
        rtol=0,
        atol=1e-10,
    )


# ----------------------------------------------------------------------------------------------------
# (a) Motion Cell


def test_motion_cell_layout(clips):
    features = to_motion_cell(clips.rotations, clips.root_positions)
    assert features.shape == (3, 40, 90)
    torch.testing.assert_close(features[..., :84], clips.rotations[..., 1:, :].flatten(-2))
    root = dict(zip(ROOT_FEATURES, features[..., 84:].unbind(-1)))
    torch.testing.assert_close(root["root_height"], clips.root_positions[..., 2])
    for name in ("forward_velocity", "sideways_velocity", "yaw_rate"):
        assert bool((root[name][:, 0] == 0).all())
    speed = torch.linalg.vector_norm(
        clips.root_positions[:, 1:, :2] - clips.root_positions[:, :-1, :2], dim=-1
    )
    torch.testing.assert_close(torch.hypot(root["forward_velocity"], root["sideways_velocity"])[:, 1:], speed)
    # these clips walk forwards at 0.5-1.5 m/s: 1/60 to 1/20 m per frame, give or take the sway
    assert 0.01 < root["forward_velocity"][:, 1:].min() and root["forward_velocity"].max() < 0.06


def test_motion_cell_round_trip_through_forward_kinematics(clips):
    features = to_motion_cell(clips.rotations, clips.root_positions)
    start = root_start(clips.positions, clips.rotations)
    rotations, root_positions = from_motion_cell(features, start)
    assert _same_rotation(rotations, clips.rotations) < 1e-12
    torch.testing.assert_close(root_positions, clips.root_positions, rtol=0, atol=1e-12)
    decoded = representation("motion_cell").decode(
        features, start, clips.offsets[clips.body][:, None], PARENTS
    )
    torch.testing.assert_close(decoded, clips.positions, rtol=0, atol=1e-12)


def test_motion_cell_round_trip_in_float32():
    clips32 = make_clips(n_frames=90, seed=3, dtype=torch.float32)
    rep = representation("motion_cell")
    features = rep.encode(clips32.positions, clips32.rotations)
    decoded = rep.decode(
        features,
        root_start(clips32.positions, clips32.rotations),
        clips32.offsets[clips32.body][:, None],
        PARENTS,
    )
    assert features.dtype == decoded.dtype == torch.float32
    torch.testing.assert_close(
        decoded, clips32.positions, rtol=0, atol=2e-5
    )  # 3 s of integrated float32 steps


def test_motion_cell_default_start_is_origin_facing_x(clips):
    rotations, root_positions = from_motion_cell(to_motion_cell(clips.rotations, clips.root_positions))
    torch.testing.assert_close(root_positions[:, 0, :2], torch.zeros(3, 2, dtype=torch.float64))
    torch.testing.assert_close(heading_yaw(rotations[:, 0, 0]), torch.zeros(3, dtype=torch.float64))


def test_from_motion_cell_normalises_model_output():
    raw = torch.randn(2, 5, 90, generator=torch.Generator().manual_seed(0))
    rotations, _ = from_motion_cell(raw)
    torch.testing.assert_close(rotations.norm(dim=-1), torch.ones(2, 5, 22))


# ----------------------------------------------------------------------------------------------------
# (b) ODMO, (c) MoGlow, (d) TrajeVAE


def test_odmo_layout_and_round_trip(clips):
    features = to_odmo(clips.positions)
    assert features.shape == (3, 40, 66)
    local = (clips.positions[..., 1:, :] - clips.positions[..., :1, :]).flatten(-2)
    torch.testing.assert_close(features[..., :63], local)
    torch.testing.assert_close(features[:, 0, 63:], torch.zeros(3, 3, dtype=torch.float64))
    back = from_odmo(features, root_start(clips.positions, clips.rotations))
    torch.testing.assert_close(back, clips.positions, rtol=0, atol=1e-12)
    torch.testing.assert_close(from_odmo(features)[:, 0, 0], torch.zeros(3, 3, dtype=torch.float64))


def test_moglow_pose_is_in_the_heading_frame():
    # one frame: root at (1, 2, 0.9) facing +y; a joint 0.3 m to the character's left and 0.1 m ahead
    rotations = torch.zeros(1, 2, 4)
    rotations[..., 0] = 1
    rotations[0, 0] = yaw_to_quat(torch.tensor(math.pi / 2))
    positions = torch.tensor([[[1.0, 2.0, 0.9], [0.7, 2.1, 0.5]]])
    features = to_moglow(positions, rotations[:, 0])
    torch.testing.assert_close(features[0, :4], torch.tensor([0.9, 0.1, 0.3, 0.5]))
    torch.testing.assert_close(features[0, 4:], torch.zeros(3))


def test_moglow_layout_and_round_trip(clips):
    features = to_moglow(clips.positions, clips.rotations[..., 0, :])
    assert features.shape == (3, 40, 67)
    torch.testing.assert_close(features[..., 0], clips.positions[..., 0, 2])
    yaw = heading_yaw(clips.rotations[..., 0, :])
    torch.testing.assert_close(features[..., 64:], root_control(clips.positions[..., 0, :2], yaw))
    back = from_moglow(features, root_start(clips.positions, clips.rotations))
    torch.testing.assert_close(back, clips.positions, rtol=0, atol=1e-12)


def test_trajevae_layout_and_round_trip(clips):
    features = to_trajevae(clips.positions)
    assert features.shape == (3, 40, 66)
    shifted = features.unflatten(-1, (22, 3))
    torch.testing.assert_close(shifted[:, 0, 0, :2], torch.zeros(3, 2, dtype=torch.float64))
    torch.testing.assert_close(shifted[..., 2], clips.positions[..., 2])  # heights untouched
    torch.testing.assert_close(shifted - shifted[:, :1, :1], clips.positions - clips.positions[:, :1, :1])
    back = from_trajevae(features, root_start(clips.positions, clips.rotations))
    torch.testing.assert_close(back, clips.positions, rtol=0, atol=1e-12)


# ----------------------------------------------------------------------------------------------------
# descriptions, batching, errors


@pytest.mark.parametrize("name, dim", [("motion_cell", 90), ("odmo", 66), ("moglow", 67), ("trajevae", 66)])
def test_representation_descriptions(clips, name, dim):
    rep = representation(name)
    assert rep.name == name and rep.dim == dim and rep.n_joints == 22
    covered = set()
    for group in rep.channels.values():
        covered |= set(range(dim)[group])
    assert covered == set(range(dim))
    features = rep.encode(clips.positions, clips.rotations)
    assert features.shape == (3, 40, dim)
    decoded = rep.decode(
        features, root_start(clips.positions, clips.rotations), clips.offsets[clips.body][:, None], PARENTS
    )
    torch.testing.assert_close(decoded, clips.positions, rtol=0, atol=1e-12)


def test_representation_channel_groups(clips):
    moglow = representation("moglow")
    features = moglow.encode(clips.positions, clips.rotations)
    torch.testing.assert_close(moglow.select(features, "root_height")[..., 0], clips.positions[..., 0, 2])
    trajevae = representation("trajevae")
    assert trajevae.select(trajevae.encode(clips.positions, clips.rotations), "root").shape == (3, 40, 3)
    assert representation("odmo", n_joints=5).dim == 15
    with pytest.raises(KeyError, match="no channel group 'velocity'"):
        moglow.select(features, "velocity")


@pytest.mark.parametrize("name", REPRESENTATION_NAMES)
def test_representations_batch_over_leading_dims(clips, name):
    rep = representation(name)
    nested_positions = clips.positions[:2].unsqueeze(0).expand(2, 2, 40, 22, 3)
    nested_rotations = clips.rotations[:2].unsqueeze(0).expand(2, 2, 40, 22, 4)
    nested = rep.encode(nested_positions, nested_rotations)
    torch.testing.assert_close(nested[1], rep.encode(clips.positions[:2], clips.rotations[:2]))
    offsets = clips.offsets[clips.body[:2]][:, None]
    decoded = rep.decode(nested, root_start(nested_positions, nested_rotations), offsets, PARENTS)
    torch.testing.assert_close(decoded, nested_positions, rtol=0, atol=1e-12)


def test_errors_name_the_problem(clips):
    with pytest.raises(ValueError, match=r"to_odmo: positions must have shape \(\.\.\., \*, 3\)"):
        to_odmo(clips.positions[..., :2])
    bad = clips.positions.clone()
    bad[1, 4, 7, 0] = float("nan")
    with pytest.raises(
        ValueError,
        match=r"to_trajevae: positions contains NaN or infinite values \(first at index \(1, 4, 7, 0\)",
    ):
        to_trajevae(bad)
    with pytest.raises(ValueError, match="must share"):
        to_motion_cell(clips.rotations, clips.root_positions[:, :-1])
    with pytest.raises(ValueError, match=r"from_motion_cell: features has 89 features"):
        from_motion_cell(torch.zeros(4, 89))
    with pytest.raises(ValueError, match="start must have position"):
        from_moglow(torch.zeros(2, 4, 67), RootStart(torch.zeros(3), torch.zeros(())))
    with pytest.raises(ValueError, match="needs the skeleton's offsets and parents"):
        representation("motion_cell").decode(torch.zeros(4, 90))
    with pytest.raises(ValueError, match="representation: name must be one of 'motion_cell', .*, got 'smpl'"):
        representation("smpl")
    with pytest.raises(ValueError, match="representation: n_joints must be at least 2, got 1"):
        representation("odmo", n_joints=1)
    with pytest.raises(TypeError, match="representation: n_joints must be an integer, got True"):
        representation("odmo", n_joints=True)
    with pytest.raises(TypeError, match="must be a torch.Tensor"):
        to_odmo(clips.positions.numpy())
    with pytest.raises(
        TypeError, match="to_odmo: positions must have a floating-point dtype, got torch.int64"
    ):
        to_odmo(clips.positions.long())
