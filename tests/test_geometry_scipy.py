"""motionlab.geometry against scipy.spatial.transform.Rotation: random rotations (hypothesis) and edge
cases (identity, half turns about axes and diagonals, tiny angles, angles near pi, gimbal lock), in
float32 and float64. scipy quaternions are (x, y, z, w); ours are (w, x, y, z).
"""

import math
import warnings

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation, Slerp

from motionlab import geometry as g

SETTINGS = settings(max_examples=25, deadline=None, derandomize=True, database=None)
DTYPES = [torch.float32, torch.float64]
# Absolute tolerances on matrix entries / angles: float32 has ~7 digits.
TOL = {torch.float32: 2e-5, torch.float64: 1e-11}
TAIT_BRYAN = ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"]
PROPER = ["XYX", "XZX", "YXY", "YZY", "ZXZ", "ZYZ"]
ORDERS = [o for base in TAIT_BRYAN + PROPER for o in (base, base.lower())]


def to_scipy(q: torch.Tensor) -> Rotation:
    """Our (w, x, y, z) quaternions (any dtype) as a scipy Rotation (computed in float64)."""
    q = q.detach().double().reshape(-1, 4).numpy()
    return Rotation.from_quat(np.concatenate([q[:, 1:], q[:, :1]], axis=1))


def from_scipy(rotation: Rotation, dtype: torch.dtype) -> torch.Tensor:
    xyzw = np.atleast_2d(rotation.as_quat())
    return torch.tensor(np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1), dtype=dtype)


def _axis_angle_quats(axes: list[list[float]], angles: list[float]) -> np.ndarray:
    rows = []
    for axis in axes:
        axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
        for angle in angles:
            rows.append(np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis]))
    return np.array(rows)


AXES = [
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 1, 0],
    [1, -1, 0],
    [0, 1, 1],
    [1, 1, 1],
    [-1, 1, 1],
    [0.3, -0.5, 0.8],
]
EDGE_QUATERNIONS = np.concatenate(
    [
        _axis_angle_quats(
            AXES, [0.0, 1e-7, -1e-7, 1e-4, math.pi / 2, math.pi - 1e-4, math.pi - 1e-7, math.pi]
        ),
        -_axis_angle_quats(AXES, [math.pi, 2.0]),  # w < 0 representatives
    ]
)


def _unit_rows(raw: np.ndarray) -> np.ndarray:
    norms = np.linalg.norm(raw, axis=-1, keepdims=True)
    return np.where(norms > 1e-3, raw / np.maximum(norms, 1e-3), np.array([1.0, 0, 0, 0]))


unit_quaternions = st.one_of(
    arrays(np.float64, st.tuples(st.integers(1, 16), st.just(4)), elements=st.floats(-1, 1)).map(_unit_rows),
    st.just(EDGE_QUATERNIONS),
)


def quats(array: np.ndarray, dtype: torch.dtype) -> torch.Tensor:
    return torch.tensor(array, dtype=dtype)


def assert_close(actual, expected, dtype, scale=1.0):
    actual = actual.detach().double().numpy() if isinstance(actual, torch.Tensor) else np.asarray(actual)
    np.testing.assert_allclose(actual, expected, rtol=0, atol=scale * TOL[dtype])


@pytest.mark.parametrize("dtype", DTYPES)
@SETTINGS
@given(q=unit_quaternions)
def test_quat_to_matrix_matches_scipy(dtype, q):
    q = quats(q, dtype)
    matrix = g.quat_to_matrix(q)
    assert matrix.dtype == dtype and matrix.shape == q.shape[:-1] + (3, 3)
    assert_close(matrix, to_scipy(q).as_matrix(), dtype)
    # any non-zero scale gives the same rotation
    assert_close(g.quat_to_matrix(3.5 * q), to_scipy(q).as_matrix(), dtype)


@pytest.mark.parametrize("dtype", DTYPES)
@SETTINGS
@given(q=unit_quaternions)
def test_matrix_to_quat_inverts_quat_to_matrix(dtype, q):
    q = quats(q, dtype)
    back = g.matrix_to_quat(torch.tensor(to_scipy(q).as_matrix(), dtype=dtype))
    assert (back[..., 0] >= 0).all()
    assert_close(back.norm(dim=-1), np.ones(len(q)), dtype)
    # same rotation: equal up to the sign of the quaternion
    reference = q.double() * torch.where(q[..., :1] < 0, -1.0, 1.0).double()
    sign = torch.where((back.double() * reference).sum(-1, keepdim=True) < 0, -1.0, 1.0).double()
    assert_close(back.double() * sign, reference.numpy(), dtype, scale=4)


@pytest.mark.parametrize("dtype", DTYPES)
@SETTINGS
@given(q=unit_quaternions, seed=st.integers(0, 2**31))
def test_quat_mul_and_apply_match_scipy(dtype, q, seed):
    q1 = quats(q, dtype)
    q2 = from_scipy(Rotation.random(len(q1), random_state=seed), dtype)
    vectors = torch.tensor(np.random.default_rng(seed).normal(size=(len(q1), 3)), dtype=dtype)
    assert_close(g.quat_to_matrix(g.quat_mul(q1, q2)), (to_scipy(q1) * to_scipy(q2)).as_matrix(), dtype)
    assert_close(g.quat_apply(q1, vectors), to_scipy(q1).apply(vectors.double().numpy()), dtype, scale=4)
    assert_close(g.quat_to_matrix(g.quat_conjugate(q1)), to_scipy(q1).inv().as_matrix(), dtype)


@pytest.mark.parametrize("dtype", DTYPES)
def test_quat_mul_and_apply_broadcast(dtype):
    q = from_scipy(Rotation.random(5, random_state=0), dtype)
    vectors = torch.randn(7, 1, 3, dtype=dtype, generator=torch.Generator().manual_seed(0))
    rotated = g.quat_apply(q, vectors)
    assert rotated.shape == (7, 5, 3)
    assert_close(rotated[3], to_scipy(q).apply(vectors[3, 0].double().numpy()), dtype, scale=4)
    assert g.quat_mul(q[:1], q).shape == (5, 4)


@pytest.mark.parametrize("dtype", DTYPES)
@settings(max_examples=12, deadline=None, derandomize=True, database=None)
@given(q=unit_quaternions)
def test_euler_round_trips_match_scipy(dtype, q):
    q = quats(q, dtype)
    rotation = to_scipy(q)
    slack = 4 * TOL[dtype]
    for order in ORDERS:
        angles = g.quat_to_euler(q, order)
        # the same rotation (compare matrices, not angles)
        assert_close(
            Rotation.from_euler(order, angles.double().numpy()).as_matrix(), rotation.as_matrix(), dtype, 4
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # scipy warns about gimbal lock in the edge cases
            reference_angles = torch.tensor(rotation.as_euler(order), dtype=dtype)
        # scipy snaps to gimbal lock within 1e-7 rad, so compare with from_euler, not with `rotation`
        expected = Rotation.from_euler(order, reference_angles.double().numpy()).as_matrix()
        assert_close(g.quat_to_matrix(g.euler_to_quat(reference_angles, order)), expected, dtype, scale=4)
        # scipy's ranges: middle angle in [0, pi] (proper) or [-pi/2, pi/2] (Tait-Bryan), outer in [-pi, pi]
        middle = angles[..., 1].double()
        if order[0].lower() == order[2].lower():
            assert ((middle >= -slack) & (middle <= math.pi + slack)).all(), order
        else:
            assert (middle.abs() <= math.pi / 2 + slack).all(), order
        assert (angles.abs() <= math.pi + slack).all(), order


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("order", ORDERS)
def test_euler_gimbal_lock_gives_the_same_rotation(dtype, order):
    proper = order[0].lower() == order[2].lower()
    lock = [0.0, math.pi] if proper else [math.pi / 2, -math.pi / 2]
    rows = [
        [a, mid + nudge, c]
        for mid in lock
        for nudge in (0.0, 1e-9, -1e-9)
        for a, c in ((0.7, -0.4), (-2.9, 2.5))
    ]
    angles = torch.tensor(rows, dtype=torch.float64)
    rotation = Rotation.from_euler(order, angles.numpy())
    q = g.euler_to_quat(angles.to(dtype), order)
    assert_close(g.quat_to_matrix(q), rotation.as_matrix(), dtype)
    extracted = g.quat_to_euler(q, order)
    assert_close(
        Rotation.from_euler(order, extracted.double().numpy()).as_matrix(), rotation.as_matrix(), dtype, 4
    )
    exact = [row[1] in lock for row in rows]
    # like scipy, the third angle is set to zero in (exact) gimbal lock
    assert (extracted[exact, 2].abs() <= TOL[dtype]).all()


@pytest.mark.parametrize("order", ORDERS)
def test_euler_near_gimbal_lock_is_as_accurate_as_scipy_in_float32(order):
    """Middle angle 1e-6 to 1e-4 rad from the lock: the outer angles are determined, so none may be zeroed.

    Euler angles -> float32 quaternion (the input) -> Euler angles -> rotation, against the input rotation
    (geodesic angle); scipy gets the same input (it computes in float64) and returns float32 angles here too.
    """
    proper = order[0].lower() == order[2].lower()
    lock = [0.0, math.pi] if proper else [math.pi / 2, -math.pi / 2]
    rng = np.random.default_rng(0)
    rows = [
        [a, mid + sign * offset, c]
        for mid in lock
        for offset in np.geomspace(1e-6, 1e-4, 9)
        for sign in (1, -1)
        for a, c in rng.uniform(-math.pi, math.pi, size=(8, 2))
    ]
    q = g.euler_to_quat(torch.tensor(rows, dtype=torch.float32), order)
    given = to_scipy(q)
    ours = Rotation.from_euler(order, g.quat_to_euler(q, order).double().numpy())
    theirs = Rotation.from_euler(order, given.as_euler(order).astype(np.float32).astype(np.float64))
    our_error, scipy_error = (ours.inv() * given).magnitude().max(), (theirs.inv() * given).magnitude().max()
    assert our_error <= 3 * scipy_error, (our_error, scipy_error)


@pytest.mark.parametrize("dtype", DTYPES)
@SETTINGS
@given(q=unit_quaternions)
def test_axis_angle_matches_scipy(dtype, q):
    q = quats(q, dtype)
    rotation = to_scipy(q)
    rotvec = g.quat_to_axis_angle(q)
    assert (rotvec.double().norm(dim=-1) <= math.pi + TOL[dtype]).all()
    assert_close(
        Rotation.from_rotvec(rotvec.double().numpy()).as_matrix(), rotation.as_matrix(), dtype, scale=4
    )
    back = g.axis_angle_to_quat(torch.tensor(rotation.as_rotvec(), dtype=dtype))
    assert_close(g.quat_to_matrix(back), rotation.as_matrix(), dtype)
    # away from the half turn (where the sign of the vector is ambiguous) the vectors agree
    away = rotation.magnitude() < math.pi - 1e-3
    assert_close(rotvec[torch.from_numpy(away)], rotation.as_rotvec()[away], dtype, scale=4)


@pytest.mark.parametrize("dtype", DTYPES)
def test_axis_angle_of_large_and_tiny_vectors(dtype):
    rotvec = torch.tensor(
        [[0.0, 0, 0], [1e-7, 0, 0], [0, 3 * math.pi, 0], [-5.0, 2.0, 1.0]], dtype=torch.float64
    )
    q = g.axis_angle_to_quat(rotvec.to(dtype))
    assert_close(g.quat_to_matrix(q), Rotation.from_rotvec(rotvec.numpy()).as_matrix(), dtype)
    assert_close(g.quat_to_axis_angle(q)[1], [1e-7, 0, 0], dtype, scale=1e-2)


@pytest.mark.parametrize("dtype", DTYPES)
@SETTINGS
@given(q=unit_quaternions, seed=st.integers(0, 2**31))
def test_sixd_round_trip_and_gram_schmidt(dtype, q, seed):
    matrix = torch.tensor(to_scipy(quats(q, dtype)).as_matrix(), dtype=dtype)
    sixd = g.matrix_to_sixd(matrix)
    assert sixd.shape == matrix.shape[:-2] + (6,)
    assert_close(sixd[..., :3], matrix[..., :, 0].double().numpy(), dtype, scale=0)
    assert_close(g.sixd_to_matrix(sixd), matrix.double().numpy(), dtype)
    # a scaled, slightly sheared 6D vector still maps to a proper rotation
    noise = torch.tensor(np.random.default_rng(seed).normal(scale=0.05, size=sixd.shape), dtype=dtype)
    rotation = g.sixd_to_matrix(2.0 * sixd + noise).double()
    eye = torch.eye(3, dtype=torch.float64).expand_as(rotation)
    assert_close(rotation.transpose(-1, -2) @ rotation, eye.numpy(), dtype)
    assert_close(torch.linalg.det(rotation), np.ones(len(rotation)), dtype)


def test_gram_schmidt_equals_classical_gram_schmidt_for_positive_determinant():
    rng = np.random.default_rng(3)
    raw = rng.normal(size=(50, 3, 3))
    raw[np.linalg.det(raw) < 0, :, 2] *= -1
    q_factor, r_factor = np.linalg.qr(raw)  # oracle: QR with the signs fixed so that diag(R) > 0
    classical = q_factor * np.sign(np.diagonal(r_factor, axis1=-2, axis2=-1))[:, None, :]
    np.testing.assert_allclose(g.gram_schmidt(torch.tensor(raw)).numpy(), classical, atol=1e-12)


@pytest.mark.parametrize("dtype", DTYPES)
@SETTINGS
@given(q=unit_quaternions, seed=st.integers(0, 2**31))
def test_distances_match_scipy_angle(dtype, q, seed):
    q1 = quats(q, dtype)
    q2 = from_scipy(Rotation.random(len(q1), random_state=seed), dtype)
    q2[::3] = q1[::3]  # include identical rotations
    angle = (to_scipy(q1).inv() * to_scipy(q2)).magnitude()
    for flip in (1.0, -1.0):  # invariance to q -> -q
        assert_close(g.quat_geodesic(q1, flip * q2), angle, dtype, scale=8)
        assert_close(g.quat_d2(q1, flip * q2), 1 - np.cos(angle / 2), dtype)
        assert_close(g.quat_d3(flip * q1, q2), 2 - 2 * np.cos(angle / 2), dtype)
    assert_close(g.quat_geodesic(0.2 * q1, 7.0 * q2), angle, dtype, scale=8)  # d1 is scale invariant
    m1, m2 = g.quat_to_matrix(q1), g.quat_to_matrix(q2)
    assert_close(g.matrix_geodesic(m1, m2), angle, dtype, scale=8)
    assert_close(g.matrix_geodesic(m2, m1), angle, dtype, scale=8)


@pytest.mark.parametrize("dtype", DTYPES)
def test_distances_at_tiny_and_near_half_turn_angles(dtype):
    angles = np.array([0.0, 1e-7, 1e-5, 1e-3, 1.0, math.pi - 1e-3, math.pi - 1e-5, math.pi])
    q1 = from_scipy(Rotation.random(len(angles), random_state=7), torch.float64)
    axis = torch.tensor([[0.6, 0.0, 0.8]], dtype=torch.float64)
    q2 = g.quat_mul(q1, g.axis_angle_to_quat(torch.tensor(angles)[:, None] * axis))
    q1, q2 = q1.to(dtype), q2.to(dtype)
    assert_close(g.quat_geodesic(q1, q2), angles, dtype, scale=8)
    assert_close(g.matrix_geodesic(g.quat_to_matrix(q1), g.quat_to_matrix(q2)), angles, dtype, scale=8)


@pytest.mark.parametrize("dtype", DTYPES)
@SETTINGS
@given(q=unit_quaternions, seed=st.integers(0, 2**31))
def test_slerp_matches_scipy(dtype, q, seed):
    q0 = quats(q, dtype)
    q1 = from_scipy(Rotation.random(len(q0), random_state=seed), dtype)
    w = torch.tensor(np.random.default_rng(seed).uniform(size=len(q0)), dtype=dtype)
    expected = np.stack(
        [
            Slerp([0.0, 1.0], to_scipy(torch.stack([a, b])))([float(s)]).as_matrix()[0]
            for a, b, s in zip(q0, q1, w)
        ]
    )
    assert_close(g.quat_to_matrix(g.quat_slerp(q0, q1, w)), expected, dtype, scale=4)


def test_interpolation_paths_slerp_has_constant_speed_nlerp_does_not():
    q0, q1 = from_scipy(Rotation.from_rotvec([[0.0, 0, 0], [0.0, 0, 2.5]]), torch.float64)
    paths = g.interpolation_paths(q0, q1, n=11)
    assert paths.slerp.shape == paths.nlerp.shape == (11, 4)
    steps = g.quat_geodesic(paths.slerp[:-1], paths.slerp[1:])
    np.testing.assert_allclose(steps.numpy(), 0.25, atol=1e-12)
    nlerp_steps = g.quat_geodesic(paths.nlerp[:-1], paths.nlerp[1:])
    assert nlerp_steps[5] > 0.25 > nlerp_steps[0]  # fastest in the middle
    for path in (paths.slerp, paths.nlerp):
        np.testing.assert_allclose(path.norm(dim=-1).numpy(), 1.0, atol=1e-12)
        # both stay on the rotation about z: the x and y components are 0
        np.testing.assert_allclose(path[:, 1:3].numpy(), 0.0, atol=1e-12)
    # a batch of pairs: path index first
    batch = g.interpolation_paths(torch.stack([q0, q1]), torch.stack([q1, q0]), n=5)
    assert batch.slerp.shape == (5, 2, 4)
    np.testing.assert_allclose(
        batch.slerp[:, 0].numpy(), g.interpolation_paths(q0, q1, 5).slerp.numpy(), atol=1e-12
    )


def test_slerp_takes_the_short_way():
    q0 = torch.tensor([1.0, 0, 0, 0], dtype=torch.float64)
    q1 = -g.axis_angle_to_quat(
        torch.tensor([0.0, 0, 0.4], dtype=torch.float64)
    )  # same rotation, far hemisphere
    middle = g.quat_slerp(q0, q1, 0.5)
    assert abs(g.quat_geodesic(q0, middle).item() - 0.2) < 1e-12


@pytest.mark.parametrize("dtype", DTYPES)
@SETTINGS
@given(
    a=arrays(np.float64, (8, 3), elements=st.floats(-1, 1)).filter(
        lambda a: (np.linalg.norm(a, axis=-1) > 1e-2).all()
    ),
    scale=st.floats(0.1, 10),
)
def test_quat_from_two_vectors_is_the_shortest_arc(dtype, a, scale):
    b = np.random.default_rng(0).normal(size=(8, 3))
    b[0], b[1] = a[0] * scale, -a[1] * scale  # identical and opposite directions
    q = g.quat_from_two_vectors(torch.tensor(a, dtype=dtype), torch.tensor(b, dtype=dtype))
    rotated = to_scipy(q).apply(a)
    unit = lambda x: x / np.linalg.norm(x, axis=-1, keepdims=True)  # noqa: E731
    assert_close(unit(rotated), unit(b), dtype, scale=8)
    between = np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), (a * b).sum(-1))
    assert_close(to_scipy(q).magnitude(), between, dtype, scale=8)
