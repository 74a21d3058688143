"""Input checks shared by the geometry functions.

They are cheap (metadata, or one reduction over a tensor the function computes anyway), never touch
autograd, and raise with a message that names the function, the argument and the first bad index.
"""

from __future__ import annotations

import math

import torch


def _shape_text(trailing: tuple[int, ...]) -> str:
    return "(..., " + ", ".join(str(size) for size in trailing) + ")"


def check_shape(x: object, trailing: tuple[int, ...], where: str, name: str) -> None:
    """Require a floating-point tensor whose shape ends with ``trailing``.

    Raises ``TypeError`` for a non-tensor or a non-floating dtype and ``ValueError`` for a wrong shape,
    e.g. ``quat_mul: q1 must have shape (..., 4), got (5, 3)``.
    """
    if not isinstance(x, torch.Tensor):
        raise TypeError(f"{where}: {name} must be a torch.Tensor, got {type(x).__name__}")
    if not x.is_floating_point():
        raise TypeError(f"{where}: {name} must have a floating-point dtype, got {x.dtype}")
    if x.dim() < len(trailing) or tuple(x.shape[-len(trailing) :]) != trailing:
        raise ValueError(f"{where}: {name} must have shape {_shape_text(trailing)}, got {tuple(x.shape)}")


def promote_and_broadcast(a: torch.Tensor, b: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """``a`` and ``b`` in their common dtype (as element-wise torch ops would promote) and broadcast shape.

    Needed before ``torch.linalg.cross``, which neither promotes dtypes nor broadcasts different ranks.
    """
    dtype = torch.promote_types(a.dtype, b.dtype)
    return torch.broadcast_tensors(a.to(dtype), b.to(dtype))


def _first_index(mask: torch.Tensor) -> tuple[int, ...]:
    return tuple(int(i) for i in mask.nonzero()[0])


def check_finite(x: torch.Tensor, where: str, name: str) -> None:
    """Raise ``ValueError`` if ``x`` holds a NaN or an infinity (reports the first one's index).

    Fast path: one sum, which is finite whenever every entry is (NaN and ±inf propagate; ``inf - inf``
    is NaN). Only when the sum is not finite (bad entries, or an overflowing sum) is ``x`` scanned.
    """
    if x.numel() == 0 or bool(torch.isfinite(x.detach().sum())):
        return
    bad = ~torch.isfinite(x.detach())
    if bool(bad.any()):
        raise ValueError(
            f"{where}: {name} contains NaN or infinite values (first at index {_first_index(bad)})"
        )


def check_positive_finite(values: torch.Tensor, where: str, what: str) -> None:
    """Raise ``ValueError`` unless every entry of ``values`` is positive and finite.

    Used on squared norms (or norms) that a function divides by: a zero norm, a NaN or an infinity in
    any input component all show up here, so one reduction checks the whole input.
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


def check_none(bad: torch.Tensor, where: str, what: str) -> None:
    """Raise ``ValueError`` ``"{where}: {what} at index ..."`` if any entry of the boolean mask ``bad`` is
    set."""
    if bool(bad.any()):
        raise ValueError(f"{where}: {what} at index {_first_index(bad)}")
