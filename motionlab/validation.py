"""Argument checks for the whole package: one scalar check, one tensor check, one exception policy.

Every public function checks its arguments through these, in the spirit of scikit-learn's ``check_scalar``;
every config dataclass declares its fields' limits where it defines them (:func:`integer`, :func:`real`,
:func:`flag`, :func:`choice`, :func:`instance`, :func:`tuple_of`; :class:`Checked` checks them when the
object is built) and keeps as code only the rules that tie several fields together. The policy:

* ``TypeError`` when an argument has the wrong *type* (not a number, not a tensor, a bool where a number is
  meant) or the wrong *dtype* (an integer tensor where a floating one is meant);
* ``ValueError`` when the type is right but the *value* or *shape* is not (out of range, NaN or infinite,
  a wrong trailing shape).

Messages name the function or class (``where``), the argument (``name``), what was expected and what came,
and for tensors the index of the first bad entry, e.g. ``quat_mul: q1 contains NaN or infinite values
(first at index (2, 0))``. All checks take their arguments in the order ``(value, name, where, ...)``.

The array part (:func:`as_float_array`, :func:`check_array`, :func:`as_labels`, :func:`check_same_shape`,
:func:`as_rng`) is the
NumPy counterpart of :func:`check_tensor` for code that computes in NumPy (the metrics, the plots): it
accepts NumPy arrays, torch tensors (any device, with or without grad) or nested lists, and follows the
same policy.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np
import torch

T = TypeVar("T")

ArrayLike = np.ndarray | torch.Tensor | Sequence
"""What the NumPy checks accept: a NumPy array, a torch tensor, or a (nested) list of numbers."""

RngLike = np.random.Generator | int
"""A NumPy generator, or a non-negative integer seed for one."""


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


# --- NumPy arrays -------------------------------------------------------------------------------------------


def as_array(x: ArrayLike, name: str, where: str) -> np.ndarray:
    """``x`` as a NumPy array, unconverted dtype (a tensor is detached and copied to the CPU; bfloat16, which
    NumPy lacks, becomes float32 exactly).

    Raises:
        ValueError: ``x`` is a ragged nested list (not a rectangular array).
    """
    if isinstance(x, torch.Tensor):
        x = x.detach().cpu()
        return (x.float() if x.dtype == torch.bfloat16 else x).numpy()
    try:
        return np.asarray(x)
    except ValueError as exc:  # ragged nested lists
        raise ValueError(f"{where}: {name} is not a rectangular array ({exc})") from exc


def as_float_array(
    x: ArrayLike,
    name: str,
    where: str,
    *,
    ndim: int | None = None,
    min_ndim: int | None = None,
    layout: str = "",
    allow_empty: bool = False,
) -> np.ndarray:
    """``x`` as a finite float64 array, checked for its number of dimensions and (unless ``allow_empty``)
    non-empty.

    Args:
        x: the input.
        name, where: the argument and the function, used in error messages.
        ndim: exact number of dimensions required (or ``None``).
        min_ndim: minimum number of dimensions required (or ``None``).
        layout: the expected layout for messages, e.g. ``"(N, D)"``.
        allow_empty: accept an array without entries.

    Raises:
        TypeError: ``x`` does not hold real numbers (booleans and integers are converted).
        ValueError: ragged, a wrong number of dimensions, empty, or a NaN or infinite entry (the message
            names the first one's index).
    """
    arr = as_array(x, name, where)
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"{where}: {name} must hold real numbers, got dtype {arr.dtype}")
    arr = arr.astype(np.float64, copy=False)
    hint = f" {layout}" if layout else ""
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{where}: {name} must be {ndim}-D{hint}, got shape {arr.shape}")
    if min_ndim is not None and arr.ndim < min_ndim:
        raise ValueError(
            f"{where}: {name} must have at least {min_ndim} dimensions{hint}, got shape {arr.shape}"
        )
    if not allow_empty and arr.size == 0:
        raise ValueError(f"{where}: {name} is empty (shape {arr.shape})")
    return check_finite_array(arr, name, where)


def check_array(
    x: ArrayLike,
    name: str,
    where: str,
    *,
    trailing: tuple[int | None, ...] = (),
    min_leading: int = 0,
    floating: bool = True,
    finite: bool = True,
) -> np.ndarray:
    """``x`` as a NumPy array of its own dtype (float32 stays float32), checked like :func:`check_tensor`.

    Args:
        x: the input.
        name, where: the argument and the function, used in error messages.
        trailing: the sizes its shape must end with (``None``: any size).
        min_leading: the least number of dimensions before ``trailing``.
        floating: require a floating-point dtype.
        finite: reject NaN and infinities (naming the first one's index).

    Raises:
        TypeError: the dtype is not floating while ``floating``.
        ValueError: ragged, too few dimensions, a wrong trailing shape, or a NaN or infinite entry.
    """
    arr = as_array(x, name, where)
    if floating and not np.issubdtype(arr.dtype, np.floating):
        raise TypeError(f"{where}: {name} must have a floating-point dtype, got {arr.dtype}")
    if arr.ndim < len(trailing) + min_leading:
        extra = f" with at least {min_leading} leading dimension(s)" if min_leading else ""
        raise ValueError(f"{where}: {name} must have shape {_layout(trailing)}{extra}, got {arr.shape}")
    if trailing:
        actual = arr.shape[arr.ndim - len(trailing) :]
        if any(want is not None and want != got for want, got in zip(trailing, actual)):
            raise ValueError(f"{where}: {name} must have shape {_layout(trailing)}, got {arr.shape}")
    if finite and arr.dtype.kind in "fc":
        check_finite_array(arr, name, where)
    return arr


def check_finite_array(arr: np.ndarray, name: str, where: str) -> np.ndarray:
    """Raise ``ValueError`` if ``arr`` holds a NaN or an infinity (naming the first one's index); return
    ``arr``."""
    finite = np.isfinite(arr)
    if not finite.all():
        index = tuple(int(i) for i in np.argwhere(~finite)[0])
        raise ValueError(f"{where}: {name} contains NaN or infinite values (first at index {index})")
    return arr


def as_labels(x: ArrayLike, name: str, where: str, *, length: int | None = None) -> np.ndarray:
    """``x`` as a non-empty 1-D array of labels (integers, booleans or strings; integral floats become
    ``int64``), optionally of a given length.

    Raises:
        TypeError: the dtype holds neither integers, booleans, strings nor floats.
        ValueError: not 1-D, empty, NaN or infinite, non-integral floats, or the wrong length.
    """
    arr = as_array(x, name, where)
    if arr.ndim != 1:
        raise ValueError(f"{where}: {name} must be 1-D (N,), got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{where}: {name} is empty (shape {arr.shape})")
    if arr.dtype.kind == "f":
        check_finite_array(arr, name, where)
        if not np.array_equal(arr, np.round(arr)):
            raise ValueError(f"{where}: {name} must hold integer labels, got non-integer floats")
        arr = arr.astype(np.int64)
    elif arr.dtype.kind not in "biuUS":
        raise TypeError(f"{where}: {name} must hold integer or string labels, got dtype {arr.dtype}")
    if length is not None and arr.shape[0] != length:
        raise ValueError(f"{where}: {name} must have one entry per item ({length}), got {arr.shape[0]}")
    return arr


def check_same_shape(a: Any, b: Any, names: tuple[str, str], where: str) -> None:
    """Raise ``ValueError`` when two arrays (or tensors) differ in shape."""
    if a.shape != b.shape:
        raise ValueError(
            f"{where}: {names[0]} and {names[1]} must have the same shape, "
            f"got {tuple(a.shape)} and {tuple(b.shape)}"
        )


def as_rng(rng: RngLike, where: str) -> np.random.Generator:
    """A NumPy generator from a generator or a non-negative integer seed.

    Raises:
        TypeError: ``rng`` is neither a generator nor an integer (a bool is not a seed).
        ValueError: a negative seed.
    """
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, bool) or not isinstance(rng, (int, np.integer)):
        raise TypeError(
            f"{where}: rng must be a numpy.random.Generator or a non-negative integer seed, got {rng!r}"
        )
    if rng < 0:
        raise ValueError(f"{where}: rng must be a non-negative integer seed, got {rng!r}")
    return np.random.default_rng(int(rng))


# --- Declared constraints of config dataclasses -------------------------------------------------------------
#
# A config dataclass declares each field's limits where the field is defined, and one function checks them
# all (in the spirit of scikit-learn's ``_parameter_constraints``)::
#
#     @dataclass(frozen=True)
#     class GlowConfig(Checked):
#         channels: int = integer(minimum=1)
#         dropout: float = real(0.0, minimum=0, below=1)
#         kind: str = choice(("conv", "gru"), "gru")
#
#         def __post_init__(self) -> None:
#             super().__post_init__()  # the declared limits; then the rules that tie fields together
#             ...
#
# The limits ride in the field's metadata (key :data:`CHECK`), so they survive inheritance and
# ``dataclasses.replace`` (which builds a new object, checked again) and leave the fields' values, and so
# the configs' hashes, untouched.

CHECK = "check"
"""The key of a field's declared constraint in ``dataclasses.Field.metadata``."""


@dataclass(frozen=True)
class Number:
    """A number: :func:`check_scalar`'s ``kind``, bounds and ``finite``."""

    kind: type | tuple[type, ...] = numbers.Real
    minimum: float | None = None
    maximum: float | None = None
    include_minimum: bool = True
    include_maximum: bool = True
    finite: bool = True

    def check(self, value: Any, name: str, where: str) -> None:
        check_scalar(value, name, where, **vars(self))  # the fields are check_scalar's keywords


@dataclass(frozen=True)
class OneOf:
    """One of a few values (:func:`check_choice`)."""

    choices: tuple[Any, ...]

    def check(self, value: Any, name: str, where: str) -> None:
        check_choice(value, name, where, self.choices)


@dataclass(frozen=True)
class InstanceOf:
    """An instance of a type (a bool switch, a string, a nested config); ``TypeError`` otherwise."""

    kind: type

    def check(self, value: Any, name: str, where: str) -> None:
        if not isinstance(value, self.kind):
            article = "an" if self.kind.__name__[0] in "AEIOU" else "a"
            raise TypeError(
                f"{where}: {name} must be {article} {self.kind.__name__}, "
                f"got {value!r} ({type(value).__name__})"
            )


@dataclass(frozen=True)
class TupleOf:
    """A tuple whose every entry meets ``each`` (entries named ``name[i]`` in messages), optionally non-empty
    or of a fixed length."""

    each: Number | OneOf | InstanceOf
    nonempty: bool = False
    length: int | None = None

    def check(self, value: Any, name: str, where: str) -> None:
        if not isinstance(value, tuple):
            raise TypeError(f"{where}: {name} must be a tuple, got {value!r} ({type(value).__name__})")
        if self.nonempty and not value:
            raise ValueError(f"{where}: {name} must be a non-empty tuple, got ()")
        if self.length is not None and len(value) != self.length:
            raise ValueError(f"{where}: {name} must be a tuple of {self.length} entries, got {value!r}")
        for index, entry in enumerate(value):
            self.each.check(entry, f"{name}[{index}]", where)


Constraint = Number | OneOf | InstanceOf | TupleOf
"""What a field may declare."""


def declared(
    constraint: Constraint,
    default: Any = dataclasses.MISSING,
    *,
    default_factory: Any = dataclasses.MISSING,
    optional: bool = False,
    note: str | None = None,
) -> Any:
    """A dataclass field carrying ``constraint`` (checked by :func:`check_fields`).

    Args:
        constraint: what the value must be.
        default, default_factory: as for ``dataclasses.field`` (neither: a required field).
        optional: ``None`` passes too (e.g. "no limit", "not set").
        note: a few words the messages add after the field's name, e.g. ``"a coupling splits it"``.
    """
    return dataclasses.field(
        default=default,
        default_factory=default_factory,
        metadata={CHECK: constraint, "optional": optional, "note": note},
    )


def _number(
    kind: type | tuple[type, ...],
    minimum: float | None,
    maximum: float | None,
    above: float | None,
    below: float | None,
    finite: bool = True,
) -> Number:
    if (minimum is not None and above is not None) or (maximum is not None and below is not None):
        raise ValueError(
            "a bound is either inclusive (minimum, maximum) or exclusive (above, below), not both"
        )
    return Number(
        kind,
        minimum if above is None else above,
        maximum if below is None else below,
        include_minimum=above is None,
        include_maximum=below is None,
        finite=finite,
    )


def integer(
    default: Any = dataclasses.MISSING,
    *,
    minimum: int | None = None,
    maximum: int | None = None,
    kind: type | tuple[type, ...] = numbers.Integral,
    optional: bool = False,
    note: str | None = None,
    default_factory: Any = dataclasses.MISSING,
) -> Any:
    """A field holding an integer within the inclusive bounds ``[minimum, maximum]`` (``None``: no bound).
    ``kind=int`` refuses NumPy integers (for fields that go into a JSON cache key)."""
    return declared(
        _number(kind, minimum, maximum, None, None),
        default,
        default_factory=default_factory,
        optional=optional,
        note=note,
    )


def real(
    default: Any = dataclasses.MISSING,
    *,
    minimum: float | None = None,
    maximum: float | None = None,
    above: float | None = None,
    below: float | None = None,
    finite: bool = True,
    kind: type | tuple[type, ...] = numbers.Real,
    optional: bool = False,
    note: str | None = None,
) -> Any:
    """A field holding a real number: at least ``minimum`` / at most ``maximum`` (inclusive bounds), greater
    than ``above`` / less than ``below`` (exclusive ones); finite unless ``finite=False`` (NaN never passes).
    ``kind=(int, float)`` refuses NumPy numbers."""
    return declared(
        _number(kind, minimum, maximum, above, below, finite), default, optional=optional, note=note
    )


def flag(default: Any = dataclasses.MISSING) -> Any:
    """A field holding a bool (a switch: ``1`` is not ``True``)."""
    return declared(InstanceOf(bool), default)


def choice(choices: Collection[Any], default: Any = dataclasses.MISSING, *, note: str | None = None) -> Any:
    """A field holding one of ``choices``."""
    return declared(OneOf(tuple(choices)), default, note=note)


def instance(
    kind: type,
    default: Any = dataclasses.MISSING,
    *,
    default_factory: Any = dataclasses.MISSING,
    optional: bool = False,
) -> Any:
    """A field holding an instance of ``kind`` (e.g. a nested config)."""
    return declared(InstanceOf(kind), default, default_factory=default_factory, optional=optional)


def tuple_of(
    default: Any = dataclasses.MISSING,
    *,
    kind: type | tuple[type, ...] = numbers.Real,
    minimum: float | None = None,
    maximum: float | None = None,
    above: float | None = None,
    below: float | None = None,
    choices: Collection[Any] | None = None,
    nonempty: bool = False,
    length: int | None = None,
) -> Any:
    """A field holding a tuple. Its entries are ``choices`` when given, else numbers of ``kind`` within the
    bounds (as in :func:`real`) when ``kind`` is numeric, else instances of ``kind`` (e.g. ``str``)."""
    each: Number | OneOf | InstanceOf
    if choices is not None:
        each = OneOf(tuple(choices))
    elif kind in (numbers.Real, numbers.Integral) or isinstance(kind, tuple):
        each = _number(kind, minimum, maximum, above, below)
    else:
        each = InstanceOf(kind)
    return declared(TupleOf(each, nonempty=nonempty, length=length), default)


def _declaring_field(cls: type, name: str) -> dataclasses.Field | None:
    """The field ``name`` as defined by the nearest class in ``cls``'s MRO that declares its constraint."""
    for klass in cls.__mro__:
        spec = getattr(klass, "__dataclass_fields__", {}).get(name)
        if spec is not None and CHECK in spec.metadata:
            return spec
    return None


def check_fields(obj: Any) -> None:
    """Check every field of the dataclass instance ``obj`` that declares a constraint, in field order.

    Messages name the class, the field (with its note) and the value, e.g. ``GlowConfig: levels must be at
    least 1, got 0``; ``TypeError`` for a wrong type, ``ValueError`` for a wrong value. A subclass that
    gives a field a new plain default (``steps: int = 200``) keeps the limit its base class declared.
    """
    where = type(obj).__name__
    for own in dataclasses.fields(obj):
        spec = _declaring_field(type(obj), own.name)
        if spec is None:
            continue
        constraint = spec.metadata[CHECK]
        value = getattr(obj, spec.name)
        if value is None and spec.metadata["optional"]:
            continue
        note = spec.metadata["note"]
        constraint.check(value, spec.name if note is None else f"{spec.name} ({note})", where)


class Checked:
    """Base of a config dataclass with declared field constraints: checks them when the object is built.

    A subclass with rules that tie several fields together overrides ``__post_init__``, calls
    ``super().__post_init__()`` first, then states those rules as code.
    """

    def __post_init__(self) -> None:
        check_fields(self)
