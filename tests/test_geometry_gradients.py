"""Gradients of motionlab.geometry: gradcheck (float64) away from singular points, and finite
(no NaN, no inf) gradients exactly at them: identical and opposite rotations, half turns, the zero
rotation vector, gimbal lock in every Euler order, degenerate interpolation endpoints.
"""

import math

import pytest
import torch
from torch.autograd import gradcheck

from motionlab import geometry as g

DTYPES = [torch.float32, torch.float64]
ORDERS = [o for base in ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX", "XYX", "XZX", "YXY", "YZY", "ZXZ", "ZYZ"]
          for o in (base, base.lower())]  # fmt: skip


def random_quats(n: int, seed: int, dtype=torch.float64) -> torch.Tensor:
    """Unit quaternions with w >= 0.3 (away from the w = 0 sign switch of matrix_to_quat)."""
    q = torch.randn(n, 4, dtype=torch.float64, generator=torch.Generator().manual_seed(seed))
    q[:, 0] = q[:, 0].abs() + 0.5
    return (q / q.norm(dim=-1, keepdim=True)).to(dtype)


def check(fn, *inputs):
    inputs = tuple(x.detach().double().requires_grad_(True) for x in inputs)
    assert gradcheck(fn, inputs, eps=1e-6, atol=1e-6, rtol=1e-5)


def test_gradcheck_quaternion_algebra():
    q1, q2 = random_quats(4, 0), random_quats(4, 1)
    vectors = torch.randn(4, 3, dtype=torch.float64, generator=torch.Generator().manual_seed(2))
    check(g.quat_mul, q1, q2)
    check(g.quat_conjugate, q1)
    check(g.quat_normalize, 1.7 * q1)
    check(g.quat_apply, 1.3 * q1, vectors)
    check(g.quat_from_two_vectors, vectors, q2[:, 1:])


def test_gradcheck_conversions():
    q = random_quats(4, 3)
    check(g.quat_to_matrix, 0.8 * q)
    check(g.matrix_to_quat, g.quat_to_matrix(q))
    check(g.axis_angle_to_quat, g.quat_to_axis_angle(q))
    check(g.quat_to_axis_angle, 1.2 * q)
    check(g.sixd_to_matrix, g.matrix_to_sixd(g.quat_to_matrix(q)) + 0.1)
    check(
        g.gram_schmidt, torch.randn(4, 3, 3, dtype=torch.float64, generator=torch.Generator().manual_seed(4))
    )
    check(g.matrix_to_sixd, g.quat_to_matrix(q))


@pytest.mark.parametrize("order", ["XYZ", "zyx", "ZXZ", "yxy"])
def test_gradcheck_euler(order):
    angles = torch.tensor([[0.3, 0.4, -0.5], [1.0, 0.9, 2.0], [-2.0, 1.2, 0.1]], dtype=torch.float64)
    check(lambda a: g.euler_to_quat(a, order), angles)
    check(lambda q: g.quat_to_euler(q, order), g.euler_to_quat(angles, order))


def test_gradcheck_interpolation():
    q0, q1 = random_quats(3, 5), random_quats(3, 6)
    w = torch.tensor([0.2, 0.5, 0.9], dtype=torch.float64)
    check(g.quat_slerp, q0, q1, w)
    check(g.quat_nlerp, q0, q1, w)


def test_gradcheck_distances_and_penalties():
    q1, q2 = random_quats(5, 7), random_quats(5, 8)
    for distance in (g.quat_geodesic, g.quat_d2, g.quat_d3):
        check(distance, q1, q2)
    check(g.matrix_geodesic, g.quat_to_matrix(q1), g.quat_to_matrix(q2))
    raw = torch.randn(5, 3, 3, dtype=torch.float64, generator=torch.Generator().manual_seed(9))
    check(g.orthogonality_penalty, raw)
    check(g.determinant_penalty, raw)
    check(g.quat_norm_penalty, 1.5 * q1)


def assert_finite_gradients(fn, *inputs):
    inputs = tuple(x.detach().clone().requires_grad_(True) for x in inputs)
    out = fn(*inputs)
    assert torch.isfinite(out).all(), out
    grads = torch.autograd.grad(out.sum(), inputs, allow_unused=True)
    for grad in grads:
        assert grad is not None and torch.isfinite(grad).all(), grad


@pytest.mark.parametrize("dtype", DTYPES)
def test_distances_have_finite_gradients_at_identical_opposite_and_half_turn_inputs(dtype):
    q = random_quats(6, 10, dtype)
    half_turned = g.quat_mul(q, torch.tensor([0.0, 0.6, 0.0, 0.8], dtype=dtype))  # <q, q'> = 0
    for other in (q, -q, half_turned):
        for distance in (g.quat_geodesic, g.quat_d2, g.quat_d3):
            assert_finite_gradients(distance, q, other)
        assert_finite_gradients(g.matrix_geodesic, g.quat_to_matrix(q), g.quat_to_matrix(other))
    tolerance = 1e-6 if dtype == torch.float32 else 1e-14
    assert g.quat_geodesic(q, -q).abs().max() < tolerance
    assert (g.quat_geodesic(q, half_turned) - math.pi).abs().max() < tolerance


@pytest.mark.parametrize("dtype", DTYPES)
def test_d1_gradient_is_the_unit_slope_of_the_angle(dtype):
    # d1 is the angle itself, so d d1 / d angle = 1; at angle 0 (a kink, like |x|) we get the subgradient 0
    identity = torch.tensor([1.0, 0, 0, 0], dtype=dtype)
    axis = torch.tensor([0.0, 0.0, 1.0], dtype=dtype)
    for start, slope in ((0.0, 0.0), (1e-3, 1.0), (1.0, 1.0), (math.pi - 1e-3, 1.0)):
        angle = torch.tensor(start, dtype=dtype, requires_grad=True)
        (grad,) = torch.autograd.grad(g.quat_geodesic(identity, g.axis_angle_to_quat(angle * axis)), angle)
        assert abs(grad.item() - slope) < 1e-3, (start, grad)


@pytest.mark.parametrize("dtype", DTYPES)
def test_conversions_have_finite_gradients_at_singular_points(dtype):
    identity = torch.tensor([[1.0, 0, 0, 0]], dtype=dtype)
    half_turns = torch.tensor(
        [[0.0, 1, 0, 0], [0.0, 0, 1, 0], [0.0, 0, 0, 1], [0.0, 0.6, 0.8, 0]], dtype=dtype
    )
    quats = torch.cat([identity, half_turns])
    assert_finite_gradients(g.quat_to_axis_angle, quats)
    assert_finite_gradients(g.axis_angle_to_quat, torch.zeros(2, 3, dtype=dtype))
    assert_finite_gradients(g.axis_angle_to_quat, torch.tensor([[math.pi, 0, 0]], dtype=dtype))
    assert_finite_gradients(g.matrix_to_quat, g.quat_to_matrix(quats))  # branch switches of Shepperd's method
    assert_finite_gradients(g.quat_to_matrix, quats)
    assert_finite_gradients(g.quat_norm_penalty, torch.zeros(1, 4, dtype=dtype))
    vectors = torch.tensor([[1.0, 2.0, 3.0], [0.0, 0.0, 1.0]], dtype=dtype)
    assert_finite_gradients(g.quat_from_two_vectors, vectors, vectors)  # identical
    assert_finite_gradients(g.quat_from_two_vectors, vectors, -vectors)  # opposite
    # the zero rotation vector: q = (1, r/2 + O(r^3)), so d vec(q) / d r = I/2 exactly
    zero = torch.zeros(3, dtype=dtype, requires_grad=True)
    jacobian = torch.autograd.functional.jacobian(g.axis_angle_to_quat, zero)
    assert torch.allclose(
        jacobian, torch.cat([torch.zeros(1, 3, dtype=dtype), 0.5 * torch.eye(3, dtype=dtype)])
    )
    jacobian = torch.autograd.functional.jacobian(g.quat_to_axis_angle, identity[0].clone())
    assert torch.allclose(jacobian[:, 1:], 2 * torch.eye(3, dtype=dtype))


@pytest.mark.parametrize("dtype", DTYPES)
def test_euler_has_finite_gradients_in_gimbal_lock(dtype):
    for order in ORDERS:
        proper = order[0].lower() == order[2].lower()
        middles = [0.0, math.pi] if proper else [math.pi / 2, -math.pi / 2]
        angles = torch.tensor([[0.7, middle, -0.4] for middle in middles], dtype=dtype)
        assert_finite_gradients(
            lambda a, order=order: g.quat_to_euler(g.euler_to_quat(a, order), order), angles
        )
        exact = torch.tensor([[1.0, 0, 0, 0], [0.5, 0.5, 0.5, 0.5], [0.0, 0.0, 0.0, 1.0]], dtype=dtype)
        assert_finite_gradients(lambda q, order=order: g.quat_to_euler(q, order), exact)


@pytest.mark.parametrize("dtype", DTYPES)
def test_interpolation_has_finite_gradients_for_equal_and_opposite_endpoints(dtype):
    q = random_quats(3, 11, dtype)
    w = torch.tensor([0.0, 0.3, 1.0], dtype=dtype)
    for other in (q, -q):
        assert_finite_gradients(g.quat_slerp, q, other, w)
        assert_finite_gradients(g.quat_nlerp, q, other, w)
    assert torch.allclose(g.quat_slerp(q, -q, w), q, atol=1e-6)


def test_normalisation_gradient_is_orthogonal_to_q_and_the_penalty_gradient_is_parallel():
    q = (1.7 * random_quats(8, 12)).requires_grad_(True)
    target = random_quats(8, 13)
    (grad_normalised,) = torch.autograd.grad(g.quat_d3(g.quat_normalize(q), target).sum(), q)
    assert torch.allclose((grad_normalised * q).sum(-1), torch.zeros(8, dtype=torch.float64), atol=1e-12)
    (grad_penalty,) = torch.autograd.grad(g.quat_norm_penalty(q).sum(), q)
    # 2 (|q| - 1) q / |q| with |q| = 1.7
    assert torch.allclose(grad_penalty, 2 * 0.7 * q.detach() / 1.7)


@pytest.mark.parametrize("dtype", DTYPES)
def test_rotation_gradients_of_tiny_and_huge_quaternions_are_those_of_the_unit_one(dtype):
    """f(s q) = f(q) for every s > 0, so d/dq f(s q) = f'(q): exactly what the unit quaternion gets."""
    q = random_quats(5, 21, dtype)
    vectors = torch.randn(5, 3, dtype=dtype, generator=torch.Generator().manual_seed(22))
    scales = [1e-20, 1e20] if dtype == torch.float32 else [1e-157, 1e-300, 1e160]
    calls = [
        g.quat_to_matrix,
        lambda p: g.quat_apply(p, vectors),
        g.quat_normalize,
        lambda p: g.quat_to_euler(p, "YZX"),
    ]
    for call in calls:
        expected = torch.autograd.functional.jacobian(call, q)
        for scale in scales:
            jacobian = torch.autograd.functional.jacobian(
                lambda p, call=call, scale=scale: call(p * scale), q
            )
            torch.testing.assert_close(jacobian, expected, msg=f"scale {scale:g}")
