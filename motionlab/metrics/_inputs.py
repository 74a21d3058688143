"""Input checks shared by the metrics: NumPy-or-torch coercion and errors that say what is wrong.

Every metric accepts NumPy arrays, torch tensors (any device, with or without grad) or nested lists,
computes in float64 NumPy and returns plain Python floats. Bad input raises ``ValueError`` naming the
function and the argument, for example ``fid: a must be 2-D (N, D), got shape (5,)``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch

ArrayLike = np.ndarray | torch.Tensor | Sequence
"""What the metrics accept: a NumPy array, a torch tensor, or a (nested) list of numbers."""

RngLike = np.random.Generator | int
"""A NumPy generator, or a non-negative integer seed for one."""


def _to_numpy(x: ArrayLike, name: str, func: str) -> np.ndarray:
    if isinstance(x, torch.Tensor):
        return x.detach().cpu().numpy()
    try:
        return np.asarray(x)
    except ValueError as exc:  # ragged nested lists
        raise ValueError(f"{func}: {name} is not a rectangular array ({exc})") from exc


def _check_not_empty(arr: np.ndarray, name: str, func: str) -> None:
    if arr.size == 0:
        raise ValueError(f"{func}: {name} is empty (shape {arr.shape})")


def as_float_array(
    x: ArrayLike,
    name: str,
    func: str,
    *,
    ndim: int | None = None,
    min_ndim: int | None = None,
    layout: str = "",
) -> np.ndarray:
    """``x`` as a finite, non-empty float64 array, checked for its number of dimensions.

    Args:
        x: the input.
        name, func: the argument and the function, used in error messages.
        ndim: exact number of dimensions required (or ``None``).
        min_ndim: minimum number of dimensions required (or ``None``).
        layout: the expected layout for messages, e.g. ``"(N, D)"``.
    """
    arr = _to_numpy(x, name, func)
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{func}: {name} must hold real numbers, got dtype {arr.dtype}")
    arr = arr.astype(np.float64, copy=False)
    hint = f" {layout}" if layout else ""
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{func}: {name} must be {ndim}-D{hint}, got shape {arr.shape}")
    if min_ndim is not None and arr.ndim < min_ndim:
        raise ValueError(
            f"{func}: {name} must have at least {min_ndim} dimensions{hint}, got shape {arr.shape}"
        )
    _check_not_empty(arr, name, func)
    finite = np.isfinite(arr)
    if not finite.all():
        where = tuple(int(i) for i in np.argwhere(~finite)[0])
        raise ValueError(f"{func}: {name} contains NaN or inf (first at index {where})")
    return arr


def as_labels(x: ArrayLike, name: str, func: str, *, length: int | None = None) -> np.ndarray:
    """``x`` as a non-empty 1-D array of labels (integers, booleans or strings), optionally of a given
    length."""
    arr = _to_numpy(x, name, func)
    if arr.ndim != 1:
        raise ValueError(f"{func}: {name} must be 1-D (N,), got shape {arr.shape}")
    _check_not_empty(arr, name, func)
    if arr.dtype.kind == "f":
        if not np.isfinite(arr).all():
            raise ValueError(f"{func}: {name} contains NaN or inf")
        if not np.array_equal(arr, np.round(arr)):
            raise ValueError(f"{func}: {name} must hold integer labels, got non-integer floats")
        arr = arr.astype(np.int64)
    elif arr.dtype.kind not in "biuUS":
        raise ValueError(f"{func}: {name} must hold integer or string labels, got dtype {arr.dtype}")
    if length is not None and arr.shape[0] != length:
        raise ValueError(f"{func}: {name} must have one entry per item ({length}), got {arr.shape[0]}")
    return arr


def check_same_shape(a: np.ndarray, b: np.ndarray, names: tuple[str, str], func: str) -> None:
    """Raise when two arrays differ in shape."""
    if a.shape != b.shape:
        raise ValueError(
            f"{func}: {names[0]} and {names[1]} must have the same shape, got {a.shape} and {b.shape}"
        )


def check_count(value: int, name: str, func: str, minimum: int = 1) -> int:
    """``value`` as an ``int`` of at least ``minimum`` (booleans and floats are refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{func}: {name} must be an integer, got {value!r}")
    if value < minimum:
        raise ValueError(f"{func}: {name} must be at least {minimum}, got {value}")
    return int(value)


def check_positive(value: float, name: str, func: str) -> float:
    """``value`` as a finite float > 0."""
    number = float(value)
    if not np.isfinite(number) or number <= 0:
        raise ValueError(f"{func}: {name} must be a finite positive number, got {value!r}")
    return number


def as_rng(rng: RngLike, func: str) -> np.random.Generator:
    """A NumPy generator from a generator or an integer seed."""
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool) and rng >= 0:
        return np.random.default_rng(int(rng))
    raise ValueError(
        f"{func}: rng must be a numpy.random.Generator or a non-negative integer seed, got {rng!r}"
    )
