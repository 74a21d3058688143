"""Argument checks for the whole package: one scalar check, one tensor check, one exception policy.

Every public function and every config's ``__post_init__`` checks its arguments through these, in the spirit
of scikit-learn's ``check_scalar``. The policy:

* ``TypeError`` when an argument has the wrong *type* (not a number, not a tensor, a bool where a number is
  meant) or the wrong *dtype* (an integer tensor where a floating one is meant);
* ``ValueError`` when the type is right but the *value* or *shape* is not (out of range, NaN or infinite,
  a wrong trailing shape).

Messages name the function or class (``where``), the argument (``name``), what was expected and what came,
and for tensors the index of the first bad entry, e.g. ``quat_mul: q1 contains NaN or infinite values
(first at index (2, 0))``. All checks take their arguments in the order ``(value, name, where, ...)``.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Collection
from typing import Any, TypeVar

import torch

T = TypeVar("T")


def _first_index(mask: torch.Tensor) -> tuple[int, ...]:
    return tuple(int(i) for i in mask.nonzero()[0])


def check_scalar(
    value: Any,
    name: str,
    where: str,
    *,
    kind: type | tuple[type, ...] = numbers.Real,
    minimum: float | None = None,
    maximum: float | None = None,
    include_minimum: bool = True,
    include_maximum: bool = True,
    finite: bool = True,
) -> Any:
    """Check one number and return it.

    Args:
        value: the number. ``bool`` is never accepted as a number (``True`` is not a step count).
        name, where: the argument's name and the function or class that checks it (for the message).
        kind: accepted types, ``numbers.Real`` (any real number, the default) or ``numbers.Integral``.
        minimum, maximum: bounds, inclusive unless ``include_minimum`` / ``include_maximum`` is ``False``.
        finite: reject NaN and infinities (``False`` allows ``inf``, e.g. for "no limit"; NaN never passes).

    Raises:
        TypeError: ``value`` is not of ``kind`` (or is a bool).
        ValueError: ``value`` is NaN, infinite while ``finite``, or outside the bounds.
    """
    if isinstance(value, bool) or not isinstance(value, kind):
        expected = "an integer" if kind is numbers.Integral else "a real number"
        if kind not in (numbers.Integral, numbers.Real):
            names = kind if isinstance(kind, tuple) else (kind,)
            expected = " or ".join(k.__name__ for k in names)
        raise TypeError(f"{where}: {name} must be {expected}, got {value!r} ({type(value).__name__})")
    number = float(value)
    if math.isnan(number) or (finite and math.isinf(number)):
        raise ValueError(f"{where}: {name} must be a finite number, got {value!r}")
    low_ok = minimum is None or (number >= minimum if include_minimum else number > minimum)
    high_ok = maximum is None or (number <= maximum if include_maximum else number < maximum)
    if not (low_ok and high_ok):
        left = "" if minimum is None else f"{'[' if include_minimum else '('}{minimum:g}"
        right = "" if maximum is None else f"{maximum:g}{']' if include_maximum else ')'}"
        if minimum is None:
            bound = f"at most {maximum:g}" if include_maximum else f"less than {maximum:g}"
        elif maximum is None:
            bound = f"at least {minimum:g}" if include_minimum else f"greater than {minimum:g}"
        else:
            bound = f"in {left}, {right}"
        raise ValueError(f"{where}: {name} must be {bound}, got {value!r}")
    return value


def check_choice(value: T, name: str, where: str, choices: Collection[T]) -> T:
    """Check that ``value`` is one of ``choices`` and return it (``ValueError`` naming the choices if not)."""
    if value not in choices:
        listed = ", ".join(repr(choice) for choice in choices)
        raise ValueError(f"{where}: {name} must be one of {listed}, got {value!r}")
    return value


def _layout(trailing: tuple[int | None, ...]) -> str:
    return "(" + ", ".join(["..."] + ["*" if size is None else str(size) for size in trailing]) + ")"


def check_tensor(
    x: Any,
    name: str,
    where: str,
    *,
    trailing: tuple[int | None, ...] = (),
    ndim: int | None = None,
    min_leading: int = 0,
    floating: bool = True,
    finite: bool = True,
) -> torch.Tensor:
    """Check a tensor argument and return it.

    Args:
        x: the tensor.
        name, where: the argument's name and the function or class that checks it.
        trailing: the sizes its shape must end with (``None``: any size), e.g. ``(4,)`` for quaternions
            ``(..., 4)`` or ``(None, 3)`` for ``(..., J, 3)`` positions.
        ndim: the exact number of dimensions, if fixed (e.g. 3 for ``(B, T, D)``).
        min_leading: the least number of dimensions before ``trailing`` (e.g. 1 for a frame axis).
        floating: require a floating-point dtype.
        finite: reject NaN and infinities (one reduction; the entries are scanned only when it is not
            finite, to report the first bad index).

    Raises:
        TypeError: ``x`` is not a tensor, or its dtype is not floating while ``floating``.
        ValueError: a wrong number of dimensions or trailing shape, or a NaN or infinite entry.
    """
    if not isinstance(x, torch.Tensor):
        raise TypeError(f"{where}: {name} must be a torch.Tensor, got {type(x).__name__}")
    if floating and not x.is_floating_point():
        raise TypeError(f"{where}: {name} must have a floating-point dtype, got {x.dtype}")
    if ndim is not None and x.dim() != ndim:
        raise ValueError(f"{where}: {name} must be {ndim}-dimensional, got shape {tuple(x.shape)}")
    if x.dim() < len(trailing) + min_leading:
        extra = f" with at least {min_leading} leading dimension(s)" if min_leading else ""
        raise ValueError(f"{where}: {name} must have shape {_layout(trailing)}{extra}, got {tuple(x.shape)}")
    if trailing:
        actual = tuple(x.shape[x.dim() - len(trailing) :])
        if any(want is not None and want != got for want, got in zip(trailing, actual)):
            raise ValueError(f"{where}: {name} must have shape {_layout(trailing)}, got {tuple(x.shape)}")
    if finite and x.is_floating_point():
        check_finite(x, name, where)
    return x


def check_finite(x: torch.Tensor, name: str, where: str) -> torch.Tensor:
    """Raise ``ValueError`` if ``x`` holds a NaN or an infinity (naming the first one's index); return ``x``.

    Fast path: one sum, which is finite whenever every entry is (NaN and ±inf propagate; ``inf - inf`` is
    NaN). Only when the sum is not finite (bad entries, or an overflowing sum) are the entries scanned.
    """
    detached = x.detach()
    if detached.numel() == 0 or bool(torch.isfinite(detached.sum())):
        return x
    bad = ~torch.isfinite(detached)
    if bool(bad.any()):
        raise ValueError(
            f"{where}: {name} contains NaN or infinite values (first at index {_first_index(bad)})"
        )
    return x


def check_positive_finite(values: torch.Tensor, what: str, where: str) -> None:
    """Raise ``ValueError`` unless every entry of ``values`` is positive and finite.

    Meant for norms (or squared norms) that a function divides by: a zero norm and a NaN or infinity in any
    input component all show up here, so one reduction checks the whole input.
    """
    values = values.detach()
    if values.numel() == 0:
        return
    smallest, largest = torch.aminmax(values)
    if bool(smallest > 0) and bool(largest < math.inf):  # NaN fails both comparisons
        return
    bad = ~((values > 0) & (values < math.inf))
    if bool(bad.any()):
        index = _first_index(bad)
        raise ValueError(
            f"{where}: {what} is zero or not finite at index {index} (value {values[index].item()})"
        )


def check_none(bad: torch.Tensor, what: str, where: str) -> None:
    """Raise ``ValueError`` ``"{where}: {what} at index ..."`` if any entry of the boolean mask ``bad`` is
    set."""
    if bool(bad.any()):
        raise ValueError(f"{where}: {what} at index {_first_index(bad)}")
