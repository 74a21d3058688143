"""motionlab.validation: one scalar check, one tensor check (and its NumPy counterparts), one policy.

TypeError for a wrong type or dtype, ValueError for a wrong value or shape; every message names the function
(``where``), the argument, what was expected and what came, and for arrays the first bad index.
"""

import math
import numbers
from fractions import Fraction

import numpy as np
import pytest
import torch

from motionlab.validation import (
    as_array,
    as_float_array,
    as_labels,
    as_rng,
    check_array,
    check_choice,
    check_finite,
    check_finite_array,
    check_none,
    check_positive_finite,
    check_same_shape,
    check_scalar,
    check_tensor,
)

# --- check_scalar -------------------------------------------------------------------------------------------


@pytest.mark.parametrize("value", [3, 2.5, np.float32(0.5), np.int64(7), Fraction(1, 3), -4])
def test_check_scalar_returns_real_numbers_unchanged(value):
    assert check_scalar(value, "x", "f") is value


@pytest.mark.parametrize("value", [True, False, np.bool_(True)])
def test_check_scalar_never_takes_a_bool_for_a_number(value):
    with pytest.raises(TypeError, match=r"f: x must be a real number, got .* \((bool|bool_)\)"):
        check_scalar(value, "x", "f")
    with pytest.raises(TypeError, match="f: x must be an integer"):
        check_scalar(value, "x", "f", kind=numbers.Integral)


@pytest.mark.parametrize("value", ["1", None, [1.0], torch.tensor(1.0), 1 + 2j])
def test_check_scalar_rejects_non_numbers_with_type_error(value):
    with pytest.raises(TypeError, match=f"f: x must be a real number, got .*\\({type(value).__name__}\\)"):
        check_scalar(value, "x", "f")


def test_check_scalar_integer_versus_real():
    assert check_scalar(np.int32(4), "n", "f", kind=numbers.Integral) == 4
    with pytest.raises(TypeError, match=r"f: n must be an integer, got 4.0 \(float\)"):
        check_scalar(4.0, "n", "f", kind=numbers.Integral)
    with pytest.raises(TypeError, match=r"f: n must be int, got 4.0 \(float\)"):
        check_scalar(4.0, "n", "f", kind=int)
    with pytest.raises(TypeError, match=r"f: n must be int, got .*4.* \(int64\)"):
        check_scalar(np.int64(4), "n", "f", kind=int)  # a concrete type is taken literally
    with pytest.raises(TypeError, match=r"f: lr must be int or float, got '1' \(str\)"):
        check_scalar("1", "lr", "f", kind=(int, float))


def test_check_scalar_bounds_inclusive_and_exclusive():
    assert check_scalar(0, "x", "f", minimum=0) == 0
    assert check_scalar(1.0, "x", "f", maximum=1) == 1.0
    assert (
        check_scalar(0.5, "x", "f", minimum=0, maximum=1, include_minimum=False, include_maximum=False) == 0.5
    )
    with pytest.raises(ValueError, match="f: x must be at least 0, got -1"):
        check_scalar(-1, "x", "f", minimum=0)
    with pytest.raises(ValueError, match="f: x must be greater than 0, got 0"):
        check_scalar(0, "x", "f", minimum=0, include_minimum=False)
    with pytest.raises(ValueError, match="f: x must be at most 1, got 1.5"):
        check_scalar(1.5, "x", "f", maximum=1)
    with pytest.raises(ValueError, match="f: x must be less than 1, got 1"):
        check_scalar(1, "x", "f", maximum=1, include_maximum=False)
    with pytest.raises(ValueError, match=r"f: x must be in \[0, 1\], got 2"):
        check_scalar(2, "x", "f", minimum=0, maximum=1)
    with pytest.raises(ValueError, match=r"f: x must be in \(0, 1\), got 1.0"):
        check_scalar(1.0, "x", "f", minimum=0, maximum=1, include_minimum=False, include_maximum=False)
    with pytest.raises(ValueError, match=r"f: x must be in \[0, 1\), got 1"):
        check_scalar(1, "x", "f", minimum=0, maximum=1, include_maximum=False)


def test_check_scalar_nan_and_infinity():
    for bad in (math.nan, math.inf, -math.inf, np.float32("nan")):
        with pytest.raises(ValueError, match="f: x must be a finite number, got"):
            check_scalar(bad, "x", "f")
    assert check_scalar(math.inf, "x", "f", minimum=0, finite=False) == math.inf  # "no limit"
    with pytest.raises(ValueError, match="f: x must be a finite number, got nan"):
        check_scalar(math.nan, "x", "f", finite=False)  # NaN never passes
    with pytest.raises(ValueError, match="f: x must be at least 0, got -inf"):
        check_scalar(-math.inf, "x", "f", minimum=0, finite=False)


# --- check_choice -------------------------------------------------------------------------------------------


def test_check_choice():
    assert check_choice("gru", "kind", "f", ("conv", "gru")) == "gru"
    with pytest.raises(ValueError, match="f: kind must be one of 'conv', 'gru', got 'rnn'"):
        check_choice("rnn", "kind", "f", ("conv", "gru"))
    with pytest.raises(ValueError, match="f: n must be one of 1, 2, got 3"):
        check_choice(3, "n", "f", (1, 2))


# --- check_tensor -------------------------------------------------------------------------------------------


def test_check_tensor_returns_the_same_tensor():
    x = torch.randn(2, 5, 3, requires_grad=True)
    assert check_tensor(x, "x", "f", trailing=(5, 3)) is x
    assert check_tensor(torch.zeros(0, 4), "x", "f", trailing=(4,)) is not None  # empty is fine


def test_check_tensor_type_and_dtype_are_type_errors():
    with pytest.raises(TypeError, match="f: x must be a torch.Tensor, got ndarray"):
        check_tensor(np.zeros(3), "x", "f")
    with pytest.raises(TypeError, match="f: x must be a torch.Tensor, got list"):
        check_tensor([1.0], "x", "f")
    with pytest.raises(TypeError, match="f: x must have a floating-point dtype, got torch.int64"):
        check_tensor(torch.zeros(3, dtype=torch.long), "x", "f")
    assert check_tensor(torch.zeros(3, dtype=torch.long), "x", "f", floating=False).dtype == torch.long


def test_check_tensor_ndim_and_trailing_shape():
    with pytest.raises(ValueError, match=r"f: x must be 3-dimensional, got shape \(2, 5\)"):
        check_tensor(torch.zeros(2, 5), "x", "f", ndim=3)
    with pytest.raises(ValueError, match=r"f: q must have shape \(\.\.\., 4\), got \(2, 3\)"):
        check_tensor(torch.zeros(2, 3), "q", "f", trailing=(4,))
    with pytest.raises(ValueError, match=r"f: m must have shape \(\.\.\., 3, 3\), got \(3,\)"):
        check_tensor(torch.zeros(3), "m", "f", trailing=(3, 3))


def test_check_tensor_trailing_none_accepts_any_size():
    for joints in (1, 22, 31):
        check_tensor(torch.zeros(4, joints, 3), "p", "f", trailing=(None, 3))
    with pytest.raises(ValueError, match=r"f: p must have shape \(\.\.\., \*, 3\), got \(4, 22, 2\)"):
        check_tensor(torch.zeros(4, 22, 2), "p", "f", trailing=(None, 3))
    # the flows' layout (batch, channels, time): a channel count in the middle
    with pytest.raises(ValueError, match=r"f: x must have shape \(\.\.\., 5, \*\), got \(2, 4, 3\)"):
        check_tensor(torch.zeros(2, 4, 3), "x", "f", ndim=3, trailing=(5, None))


def test_check_tensor_min_leading():
    check_tensor(torch.zeros(7, 3), "p", "f", trailing=(3,), min_leading=1)
    with pytest.raises(
        ValueError,
        match=r"f: p must have shape \(\.\.\., 3\) with at least 1 leading dimension\(s\), got \(3,\)",
    ):
        check_tensor(torch.zeros(3), "p", "f", trailing=(3,), min_leading=1)
    with pytest.raises(ValueError, match=r"with at least 2 leading dimension\(s\), got \(5, 22, 3\)"):
        check_tensor(torch.zeros(5, 22, 3), "p", "f", trailing=(None, 3), min_leading=2)


def test_check_tensor_names_the_first_bad_index():
    x = torch.zeros(3, 4)
    x[2, 1] = math.inf
    x[2, 3] = math.nan
    with pytest.raises(ValueError, match=r"f: x contains NaN or infinite values \(first at index \(2, 1\)\)"):
        check_tensor(x, "x", "f")
    assert check_tensor(x, "x", "f", finite=False) is x
    big = torch.full((4,), 3e38)  # finite entries whose sum overflows: scanned, and accepted
    assert check_tensor(big, "x", "f") is big


def test_check_finite_and_friends():
    check_finite(torch.zeros(0), "x", "f")
    y = torch.ones(2, 2, dtype=torch.float64)
    y[1, 0] = -math.inf
    with pytest.raises(ValueError, match=r"f: y contains NaN or infinite values \(first at index \(1, 0\)\)"):
        check_finite(y, "y", "f")
    with pytest.raises(
        ValueError, match=r"f: the norm of q is zero or not finite at index \(1,\) \(value 0.0\)"
    ):
        check_positive_finite(torch.tensor([1.0, 0.0, 2.0]), "the norm of q", "f")
    check_positive_finite(torch.tensor([1.0, 2.0]), "the norm of q", "f")
    with pytest.raises(ValueError, match=r"f: upside down at index \(0, 2\)"):
        check_none(torch.tensor([[False, False, True]]), "upside down", "f")


# --- the NumPy counterparts ---------------------------------------------------------------------------------


def test_as_array_accepts_arrays_tensors_and_lists():
    x = torch.arange(6.0, requires_grad=True).reshape(2, 3)
    np.testing.assert_array_equal(as_array(x, "x", "f"), x.detach().numpy())
    assert as_array([[1, 2], [3, 4]], "x", "f").dtype.kind == "i"
    with pytest.raises(ValueError, match=r"f: x is not a rectangular array"):
        as_array([[1.0, 2.0], [3.0]], "x", "f")


def test_as_float_array():
    values = as_float_array(torch.tensor([[1, 2]], dtype=torch.int32), "x", "f", ndim=2)
    assert values.dtype == np.float64 and values.tolist() == [[1.0, 2.0]]
    assert as_float_array(np.array([True, False]), "x", "f").tolist() == [1.0, 0.0]
    with pytest.raises(TypeError, match="f: x must hold real numbers, got dtype <U1"):
        as_float_array(["a", "b"], "x", "f")
    with pytest.raises(TypeError, match="f: x must hold real numbers, got dtype complex128"):
        as_float_array(np.ones(2, dtype=complex), "x", "f")
    with pytest.raises(ValueError, match=r"f: x must be 2-D \(N, D\), got shape \(3,\)"):
        as_float_array(np.zeros(3), "x", "f", ndim=2, layout="(N, D)")
    with pytest.raises(
        ValueError, match=r"f: x must have at least 3 dimensions \(K, T, D\), got shape \(2, 2\)"
    ):
        as_float_array(np.zeros((2, 2)), "x", "f", min_ndim=3, layout="(K, T, D)")
    with pytest.raises(ValueError, match=r"f: x is empty \(shape \(0, 2\)\)"):
        as_float_array(np.zeros((0, 2)), "x", "f")
    assert as_float_array(np.zeros((0, 2)), "x", "f", allow_empty=True).shape == (0, 2)
    bad = np.zeros((2, 3))
    bad[1, 2] = np.nan
    with pytest.raises(ValueError, match=r"f: x contains NaN or infinite values \(first at index \(1, 2\)\)"):
        as_float_array(bad, "x", "f")


def test_check_array_keeps_the_dtype():
    x = np.zeros((2, 5, 3), dtype=np.float32)
    assert check_array(x, "p", "f", trailing=(None, 3), min_leading=1) is x
    with pytest.raises(TypeError, match="f: p must have a floating-point dtype, got int64"):
        check_array(np.zeros((2, 3), dtype=np.int64), "p", "f")
    with pytest.raises(ValueError, match=r"f: p must have shape \(\.\.\., \*, 3\), got \(2, 5, 2\)"):
        check_array(np.zeros((2, 5, 2)), "p", "f", trailing=(None, 3))
    with pytest.raises(ValueError, match=r"with at least 1 leading dimension\(s\), got \(5, 3\)"):
        check_array(np.zeros((5, 3)), "p", "f", trailing=(None, 3), min_leading=1)
    x[1, 4, 0] = np.inf
    with pytest.raises(
        ValueError, match=r"f: p contains NaN or infinite values \(first at index \(1, 4, 0\)\)"
    ):
        check_array(x, "p", "f")
    with pytest.raises(ValueError, match=r"first at index \(0,\)"):
        check_finite_array(np.array([np.nan, 1.0]), "v", "f")


def test_as_labels():
    assert as_labels([2.0, 0.0], "y", "f").dtype == np.int64
    assert as_labels(np.array(["a", "b"]), "y", "f").tolist() == ["a", "b"]
    assert as_labels(torch.tensor([True, False]), "y", "f").dtype == bool
    with pytest.raises(ValueError, match=r"f: y must be 1-D \(N,\), got shape \(1, 2\)"):
        as_labels([[0, 1]], "y", "f")
    with pytest.raises(ValueError, match=r"f: y is empty"):
        as_labels([], "y", "f")
    with pytest.raises(ValueError, match="f: y must hold integer labels, got non-integer floats"):
        as_labels([0.5, 1.0], "y", "f")
    with pytest.raises(ValueError, match=r"f: y contains NaN or infinite values \(first at index \(1,\)\)"):
        as_labels([0.0, np.nan], "y", "f")
    with pytest.raises(TypeError, match="f: y must hold integer or string labels, got dtype complex128"):
        as_labels(np.ones(2, dtype=complex), "y", "f")
    with pytest.raises(ValueError, match=r"f: y must have one entry per item \(3\), got 2"):
        as_labels([0, 1], "y", "f", length=3)


def test_check_same_shape():
    check_same_shape(np.zeros((2, 3)), torch.zeros(2, 3), ("a", "b"), "f")
    with pytest.raises(
        ValueError, match=r"f: mu and logvar must have the same shape, got \(4, 3\) and \(4, 2\)"
    ):
        check_same_shape(torch.zeros(4, 3), torch.zeros(4, 2), ("mu", "logvar"), "f")


def test_as_rng():
    generator = np.random.default_rng(3)
    assert as_rng(generator, "f") is generator
    assert as_rng(np.int64(5), "f").integers(1000) == np.random.default_rng(5).integers(1000)
    with pytest.raises(ValueError, match="f: rng must be a non-negative integer seed, got -1"):
        as_rng(-1, "f")
    for bad in (True, 1.5, "3", None):
        with pytest.raises(
            TypeError, match="f: rng must be a numpy.random.Generator or a non-negative integer"
        ):
            as_rng(bad, "f")


def test_as_array_converts_bfloat16_exactly():
    x = torch.tensor([1.5, -2.25], dtype=torch.bfloat16)
    assert as_array(x, "x", "f").dtype == np.float32
    assert as_float_array(x, "x", "f").tolist() == [1.5, -2.25]
