"""Bad input to motionlab.geometry raises a clear exception naming the function, the argument and what
is wrong, instead of returning NaNs."""

import math
import re

import pytest
import torch

from motionlab import geometry as g

Q = torch.tensor([[1.0, 0.0, 0.0, 0.0], [0.0, 0.6, 0.8, 0.0]])
M = g.quat_to_matrix(Q)
V = torch.tensor([[1.0, 2.0, 3.0], [0.0, 0.0, 1.0]])

# (function name, call taking the main argument, a valid main argument, its expected trailing shape)
CALLS = [
    ("quat_mul", lambda x: g.quat_mul(x, Q), Q, "(..., 4)"),
    ("quat_mul", lambda x: g.quat_mul(Q, x), Q, "(..., 4)"),
    ("quat_conjugate", g.quat_conjugate, Q, "(..., 4)"),
    ("quat_normalize", g.quat_normalize, Q, "(..., 4)"),
    ("quat_standardize", g.quat_standardize, Q, "(..., 4)"),
    ("quat_apply", lambda x: g.quat_apply(x, V), Q, "(..., 4)"),
    ("quat_apply", lambda x: g.quat_apply(Q, x), V, "(..., 3)"),
    ("quat_from_two_vectors", lambda x: g.quat_from_two_vectors(x, V), V, "(..., 3)"),
    ("quat_to_matrix", g.quat_to_matrix, Q, "(..., 4)"),
    ("matrix_to_quat", g.matrix_to_quat, M, "(..., 3, 3)"),
    ("axis_angle_to_quat", g.axis_angle_to_quat, V, "(..., 3)"),
    ("quat_to_axis_angle", g.quat_to_axis_angle, Q, "(..., 4)"),
    ("euler_to_quat", lambda x: g.euler_to_quat(x, "XYZ"), V, "(..., 3)"),
    ("quat_to_euler", lambda x: g.quat_to_euler(x, "zxz"), Q, "(..., 4)"),
    ("matrix_to_sixd", g.matrix_to_sixd, M, "(..., 3, 3)"),
    ("sixd_to_matrix", g.sixd_to_matrix, g.matrix_to_sixd(M), "(..., 6)"),
    ("gram_schmidt", g.gram_schmidt, M, "(..., 3, 2)"),
    ("quat_slerp", lambda x: g.quat_slerp(x, Q, 0.5), Q, "(..., 4)"),
    ("quat_nlerp", lambda x: g.quat_nlerp(Q, x, 0.5), Q, "(..., 4)"),
    ("quat_geodesic", lambda x: g.quat_geodesic(x, Q), Q, "(..., 4)"),
    ("quat_d2", lambda x: g.quat_d2(Q, x), Q, "(..., 4)"),
    ("quat_d3", lambda x: g.quat_d3(x, Q), Q, "(..., 4)"),
    ("matrix_geodesic", lambda x: g.matrix_geodesic(x, M), M, "(..., 3, 3)"),
    ("orthogonality_penalty", g.orthogonality_penalty, M, "(..., 3, 3)"),
    ("determinant_penalty", g.determinant_penalty, M, "(..., 3, 3)"),
    ("quat_norm_penalty", g.quat_norm_penalty, Q, "(..., 4)"),
]
IDS = [f"{name}-{i}" for i, (name, *_) in enumerate(CALLS)]


@pytest.mark.parametrize(("name", "call", "valid", "shape"), CALLS, ids=IDS)
def test_valid_input_passes_and_wrong_shape_names_function_and_expected_shape(name, call, valid, shape):
    assert torch.isfinite(call(valid)).all()
    wrong = torch.ones(*valid.shape[:-1], valid.shape[-1] + 1)
    with pytest.raises(ValueError, match=rf"^{name}: .*must have shape {re.escape(shape)}, got"):
        call(wrong)
    with pytest.raises(ValueError, match=name):
        call(torch.tensor(1.0))  # a scalar has no trailing dimensions at all


@pytest.mark.parametrize(("name", "call", "valid", "shape"), CALLS, ids=IDS)
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_input_raises(name, call, valid, shape, bad):
    corrupt = valid.clone()
    corrupt.view(-1)[-1] = bad
    with pytest.raises(ValueError, match=rf"^{name}: .*(NaN|not finite)"):
        call(corrupt)


@pytest.mark.parametrize(("name", "call", "valid", "shape"), CALLS, ids=IDS)
def test_non_tensor_and_integer_input_raise_type_error(name, call, valid, shape):
    with pytest.raises(TypeError, match=name):
        call(valid.tolist())
    with pytest.raises(TypeError, match=rf"{name}: .*floating-point dtype"):
        call(valid.round().long())


@pytest.mark.parametrize(
    "call",
    [
        g.quat_normalize,
        g.quat_to_matrix,
        g.quat_to_axis_angle,
        lambda q: g.quat_apply(q, V),
        lambda q: g.quat_to_euler(q, "XYZ"),
        lambda q: g.quat_to_euler(q, "zyz"),
        lambda q: g.quat_geodesic(Q, q),
        lambda q: g.quat_slerp(q, Q, 0.3),
    ],
)
def test_zero_quaternion_raises_and_names_the_index(call):
    zero_second = Q.clone()
    zero_second[1] = 0
    with pytest.raises(ValueError, match=r"zero or not finite at index \(1,\)"):
        call(zero_second)


def test_degenerate_vectors_and_columns_raise():
    with pytest.raises(ValueError, match="quat_from_two_vectors: the norm of b is zero"):
        g.quat_from_two_vectors(V, torch.zeros(3))
    with pytest.raises(ValueError, match="gram_schmidt: the norm of the first column is zero"):
        g.gram_schmidt(torch.zeros(3, 2))
    parallel = torch.tensor([[1.0, 2.0], [2.0, 4.0], [3.0, 6.0]])
    with pytest.raises(ValueError, match="gram_schmidt: the second column is parallel to the first"):
        g.gram_schmidt(parallel)
    with pytest.raises(
        ValueError, match=r"gram_schmidt: columns \(or a \(\.\.\., 3, 3\) matrix\) must have shape"
    ):
        g.gram_schmidt(torch.ones(3, 4))


@pytest.mark.parametrize("order", ["XXY", "XYY", "xYz", "abc", "XY", "XYZX", "", 3, None])
def test_invalid_euler_orders_raise(order):
    with pytest.raises(ValueError, match="euler_to_quat: .*order"):
        g.euler_to_quat(V, order)
    with pytest.raises(ValueError, match="quat_to_euler: .*order"):
        g.quat_to_euler(Q, order)


def test_interpolation_arguments_are_checked():
    with pytest.raises(ValueError, match="quat_slerp: w contains NaN"):
        g.quat_slerp(Q, Q, torch.tensor([0.1, math.nan]))
    with pytest.raises(ValueError, match="interpolation_paths: n must be an integer >= 2"):
        g.interpolation_paths(Q[0], Q[1], n=1)


def test_checks_leave_valid_batches_and_empty_batches_alone():
    empty = torch.zeros(0, 4)
    assert g.quat_to_matrix(empty).shape == (0, 3, 3)
    assert g.quat_normalize(empty).shape == (0, 4)
    assert g.quat_geodesic(empty, empty).shape == (0,)
    # a huge but finite batch sum does not trip the fast finiteness check into a false alarm
    big = torch.full((4, 3, 3), 3e38)
    assert g.matrix_to_sixd(big).shape == (4, 6)


@pytest.mark.parametrize(("name", "call", "valid", "shape"), CALLS, ids=IDS)
@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
def test_dtype_and_batch_dims_are_preserved(name, call, valid, shape, dtype):
    batched = valid.to(dtype).expand(3, *valid.shape)  # an extra leading dimension
    out = call(batched)
    assert out.dtype == dtype
    assert out.shape[:2] == (3, valid.shape[0])
    assert torch.equal(out[1], call(valid.to(dtype)))  # deterministic and batch-independent


# Unit quaternions (general rotations and special ones), and scales whose squared norm underflows or overflows
# the dtype or whose `2 / |q|^2` overflows (1e-20 in float32), plus scales just inside the range used as it
# is.
SCALED_UNITS = torch.tensor(
    [[0.5, 0.5, 0.5, 0.5], [0.1, -0.7, 0.3, 0.64], [0.0, 0.0, 0.0, 1.0], [-0.9, 0.2, 0.3, 0.2]]
)
EXTREME_SCALES = {
    torch.float32: [1e-20, 1e-25, 1e-30, 1e20, 1e30, 1e38, 1e-15, 1e15],
    torch.float64: [1e-157, 1e-170, 1e-300, 1e155, 1e160, 1e300, 1e-145, 1e145],
}
ROTATION_CALLS = [
    ("quat_to_matrix", g.quat_to_matrix),
    ("quat_apply", lambda q: g.quat_apply(q, V[:1])),
    ("quat_normalize", g.quat_normalize),
    ("quat_to_euler", lambda q: g.quat_to_euler(q, "XYZ")),
    ("quat_to_euler", lambda q: g.quat_to_euler(q, "zxz")),
    ("quat_slerp", lambda q: g.quat_slerp(q, Q[1:], 0.3)),
    ("quat_nlerp", lambda q: g.quat_nlerp(Q[1:], q, 0.3)),
]


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
@pytest.mark.parametrize(
    ("name", "call"), ROTATION_CALLS, ids=[f"{n}-{i}" for i, (n, _) in enumerate(ROTATION_CALLS)]
)
def test_tiny_and_huge_quaternions_give_the_rotation_of_their_unit_version(name, call, dtype):
    unit = SCALED_UNITS.to(dtype)
    unit = unit / unit.norm(dim=-1, keepdim=True)
    expected = call(unit)
    for scale in EXTREME_SCALES[dtype]:
        result = call(unit * scale)
        assert torch.isfinite(result).all(), (name, scale)
        torch.testing.assert_close(result, expected, msg=f"{name} at scale {scale:g}")
    mixed = unit * torch.tensor([EXTREME_SCALES[dtype][i] for i in (0, 1, 3, 4)], dtype=dtype)[:, None]
    torch.testing.assert_close(call(mixed), expected)


@pytest.mark.parametrize(
    ("name", "call", "what"),
    [
        ("quat_to_matrix", g.quat_to_matrix, "the squared norm of q"),
        ("quat_apply", lambda q: g.quat_apply(q, V), "the squared norm of q"),
        ("quat_normalize", g.quat_normalize, "the norm of q"),
        ("quat_to_euler", lambda q: g.quat_to_euler(q, "XYZ"), "the squared norm of q"),
    ],
)
@pytest.mark.parametrize(
    ("row", "shown"),
    [
        ([0.0, 0.0, 0.0, 0.0], "0.0"),
        ([1e30, 1e30, math.inf, 1e30], "inf"),  # huge finite components alongside do not change the message
        ([1e-30, -math.inf, 0.0, 0.0], "inf"),
        ([1e30, 0.0, math.nan, 1e-30], "nan"),
    ],
)
def test_zero_and_non_finite_quaternions_raise_as_before_next_to_tiny_and_huge_parts(
    name, call, what, row, shown
):
    corrupt = Q.clone()
    corrupt[1] = torch.tensor(row)
    with pytest.raises(
        ValueError, match=rf"^{name}: {what} is zero or not finite at index \(1,\) \(value {shown}\)$"
    ):
        call(corrupt)


@pytest.mark.parametrize(
    "dtype, scale", [(torch.float32, 1e-20), (torch.float32, 1e20), (torch.float64, 1e-157)]
)
def test_axis_angle_and_geodesic_of_tiny_and_huge_quaternions_are_those_of_their_unit_versions(dtype, scale):
    q = torch.tensor([[0.9, 0.1, -0.3, 0.2], [0.5, 0.5, 0.5, 0.5]], dtype=dtype)
    r = torch.tensor([[0.2, 0.7, 0.1, -0.4], [1.0, 0.0, 0.0, 0.0]], dtype=dtype)
    unit_q, unit_r = q / q.norm(dim=-1, keepdim=True), r / r.norm(dim=-1, keepdim=True)
    torch.testing.assert_close(g.quat_to_axis_angle(q * scale), g.quat_to_axis_angle(unit_q))
    torch.testing.assert_close(g.quat_geodesic(q * scale, r / scale), g.quat_geodesic(unit_q, unit_r))
