"""The generator's NumPy building blocks: rotations, leg IK and curves, against scipy and hand
computations."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from motionlab.data import rig
from motionlab.data.curves import ease, hermite_keys, interp_rows, keyframes, place_event, smooth_noise


def test_euler_matrix_and_quaternions_match_scipy():
    rng = np.random.default_rng(0)
    roll, pitch, yaw = rng.uniform(-3, 3, size=(3, 500))
    expected = Rotation.from_euler("ZYX", np.stack([yaw, pitch, roll], -1)).as_matrix()
    np.testing.assert_allclose(rig.euler_matrix(roll, pitch, yaw), expected, atol=1e-12)
    rotations = Rotation.concatenate(
        [
            Rotation.random(500, random_state=1),
            Rotation.from_rotvec(np.pi * np.array([[1, 0, 0], [0, 1, 0], [0.6, -0.8, 0]])),
            Rotation.from_euler("ZY", [[np.pi, 0.1]]),
            Rotation.identity(),
        ]
    )
    quats = rig.matrix_to_quaternion(rotations.as_matrix())
    assert np.all(quats[:, 0] >= 0)
    back = Rotation.from_quat(quats[:, [1, 2, 3, 0]]).as_matrix()
    np.testing.assert_allclose(back, rotations.as_matrix(), atol=1e-12)


def test_continuous_quaternions_remove_sign_flips():
    yaw = np.linspace(0, 4 * np.pi, 50)
    quats = rig.matrix_to_quaternion(rig.yaw_matrix(yaw))[None]  # w >= 0 flips sign at every half turn
    assert np.any(np.sum(quats[:, 1:] * quats[:, :-1], -1) < 0)
    smooth = rig.continuous_quaternions(quats, time_axis=1)
    assert np.all(np.sum(smooth[:, 1:] * smooth[:, :-1], -1) > 0)
    np.testing.assert_allclose(np.abs(smooth), np.abs(quats))


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_leg_ik_reaches_the_target_with_a_hinge_knee(seed):
    rng = np.random.default_rng(seed)
    thigh, shank = rng.uniform(0.35, 0.5, size=2)
    hip = rng.normal(size=3)
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    distance = rng.uniform(abs(thigh - shank) + 0.05, rig.LEG_REACH * (thigh + shank))
    ankle = hip + distance * direction
    forward = np.cross(direction, rng.normal(size=3))  # any direction not along the leg
    rotation, knee = rig.leg_ik(hip, ankle, thigh, shank, forward)
    np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(rotation) == pytest.approx(1.0)
    knee_position = hip + rotation @ [0, 0, -thigh]
    reached = knee_position + rotation @ rig.pitch_matrix(np.array(knee)) @ [0, 0, -shank]
    np.testing.assert_allclose(reached, ankle, atol=1e-10)
    assert 0 <= knee < np.pi  # the knee only bends one way
    assert np.dot(knee_position - hip, forward) >= -1e-12  # ... and points towards knee_forward


def test_leg_ik_approaches_far_targets_smoothly():
    hip = np.zeros(3)
    distances = np.linspace(0.7, 1.2, 200)
    ankles = np.stack([np.zeros_like(distances), np.zeros_like(distances), -distances], -1)
    forward = np.tile([1.0, 0, 0], (200, 1))
    rotation, knee = rig.leg_ik(hip[None], ankles, 0.45, 0.4, forward)
    reached = np.linalg.norm(
        rotation @ [0, 0, -0.45] + (rotation @ rig.pitch_matrix(knee) @ [0, 0, -0.4]), axis=-1
    )
    exact = distances <= rig.LEG_REACH * 0.85
    np.testing.assert_allclose(reached[exact], distances[exact], atol=1e-12)
    assert np.all(np.diff(reached) >= 0) and reached.max() <= 0.85 + 1e-12  # closer and closer, then straight
    assert np.all(np.diff(knee) <= 1e-12) and np.all(knee >= 0) and np.all(knee[reached < 0.849] > 0)
    edge = rig.LEG_REACH * 0.85 + np.array([-2e-6, 0.0, 2e-6])  # no kink where the exact range ends
    rotation, knee = rig.leg_ik(np.zeros((3, 3)), edge[:, None] * [0, 0, -1.0], 0.45, 0.4, forward[:3])
    reached = np.linalg.norm(
        rotation @ [0, 0, -0.45] + (rotation @ rig.pitch_matrix(knee) @ [0, 0, -0.4]), axis=-1
    )
    np.testing.assert_allclose(np.diff(reached) / 2e-6, [1.0, 1.0], atol=1e-3)


def test_keyframes_pass_through_keys_without_overshoot_and_hold_outside():
    times = np.array([[0.5, 1.0, 1.2, 2.0], [0.2, 0.4, 1.5, 1.8]])
    values = np.array([[0.0, 1.0, 0.8, 0.0], [1.0, 2.0, 3.0, 3.5]])
    t = np.linspace(0, 2.5, 501)
    curve = keyframes(times, values, t)
    np.testing.assert_allclose(keyframes(times, values, times), values, atol=1e-12)
    for row in range(2):
        for i in range(3):
            inside = (t >= times[row, i]) & (t <= times[row, i + 1])
            lo, hi = sorted(values[row, i : i + 2])
            assert np.all((curve[row, inside] >= lo - 1e-12) & (curve[row, inside] <= hi + 1e-12))
        assert np.all(curve[row, t <= times[row, 0]] == values[row, 0])
        assert np.all(curve[row, t >= times[row, -1]] == values[row, -1])
    assert np.all(np.diff(curve[1]) >= -1e-12)  # monotone keys give a monotone curve


def test_hermite_keys_reproduce_a_ballistic_parabola():
    g, v0, flight = 9.81, 2.0, 2 * 2.0 / 9.81
    times = np.array([[0.0, flight]])
    t = np.linspace(0, flight, 50)
    curve = hermite_keys(times, np.array([[1.0, 1.0]]), np.array([[v0, -v0]]), t)
    np.testing.assert_allclose(curve[0], 1.0 + v0 * t - g * t**2 / 2, atol=1e-12)


def test_small_curve_helpers():
    np.testing.assert_allclose(ease(np.array([-1.0, 0.0, 0.5, 1.0, 2.0])), [0, 0, 0.5, 1, 1])
    x = np.array([[0.0, 1.0, 3.0]])
    y = np.array([[[0.0], [2.0], [0.0]]])
    np.testing.assert_allclose(interp_rows(x, y, np.array([[0.5, 2.0, 4.0, -1.0]]))[0, :, 0], [1, 1, -1, -2])
    rng = np.random.default_rng(0)
    noise = smooth_noise(
        np.linspace(0, 200, 20001), rng.uniform(0.1, 0.5, (1, 3)), rng.uniform(-3, 3, (1, 3))
    )
    assert noise.std() == pytest.approx(1.0, rel=0.05)  # unit root-mean-square
    start, scale = place_event(np.array([1.0, 10.0]), n_frames=120, fps=30, where=np.array([0.99, 0.0]))
    last = 119 / 30
    assert scale[0] == 1.0 and 0.25 <= start[0] and start[0] + 1.0 <= last - 0.25 + 1e-12
    assert scale[1] == pytest.approx((last - 0.5) / 10.0) and start[1] == pytest.approx(0.25)
