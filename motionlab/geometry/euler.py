"""Euler angles for all 12 axis orders, with scipy's naming.

``order`` is three letters: upper case ``"XYZ"`` is intrinsic (rotate about the body's x, then its new
y, then its new z: ``R = Rx(a) Ry(b) Rz(c)``), lower case ``"xyz"`` is extrinsic (about the fixed
world x, then y, then z: ``R = Rz(c) Ry(b) Rx(a)``). Tait–Bryan orders use three different axes
(``"XYZ"``, ``"ZYX"``, ...), proper Euler orders repeat the first (``"ZXZ"``, ``"xyx"``, ...).
Angles are radians, shape ``(..., 3)``, in the order the letters are written.

Extracting angles (:func:`quat_to_euler`) works on the quaternion directly. For a proper order
``(i, j, i)`` with third axis ``k`` and parity ``ε = ±1`` of the permutation ``(i, j, k)``,
``q = q_i(a) ⊗ q_j(b) ⊗ q_i(c)`` multiplies out to

``w = cos(b/2) cos((a+c)/2)``, ``q_i = cos(b/2) sin((a+c)/2)``,
``q_j = sin(b/2) cos((a-c)/2)``, ``ε q_k = sin(b/2) sin((a-c)/2)``,

that is ``w + i q_i = cos(b/2) e^{i(a+c)/2}`` and ``q_j + i ε q_k = sin(b/2) e^{i(a-c)/2}``. So
``b = 2 atan2(|q_j + i ε q_k|, |w + i q_i|)``, and the outer angles are the arguments of the products
``(w + i q_i)(q_j ± i ε q_k)``: one ``atan2`` each, already in ``[-pi, pi]`` (adding two half-angle
``atan2`` and wrapping the sum back into range with a rounded ``2π`` doubles the float32 error).
A Tait–Bryan order ``(i, j, k)`` becomes the proper order ``(i, j, i)`` after rotating by a quarter
turn about ``j`` (``R_k(c) = P R_i(c) Pᵀ`` with ``P = R_j(-ε π/2)``), which is a fixed linear map of the
quaternion's components.

In gimbal lock (middle angle ``0`` or ``π`` for proper orders, ``±π/2`` for Tait–Bryan ones) only the sum
or the difference of the outer angles is defined; like scipy we then set the third angle to zero. The lock
is declared where ``sin(b/2)`` (or ``cos(b/2)``) is at most ``2 eps`` of the quaternion's norm, with ``eps``
the dtype's machine epsilon: there the rounding errors of the components (1 to 2 ``eps`` for quaternions
computed from angles or matrices) leave the other combination of the outer angles undetermined, and zeroing
the third angle moves the rotation by at most about ``8 eps`` (1e-6 rad in float32). A middle angle further
from the lock keeps both outer angles, which are then determined to rounding level.
"""

from __future__ import annotations

import math

import torch

from motionlab.geometry._numerics import safe_hypot
from motionlab.geometry.quaternion import hamilton_product, safely_scaled
from motionlab.validation import check_finite, check_tensor

_AXES = {"x": 0, "y": 1, "z": 2}
_EVEN_PERMUTATIONS = ((0, 1, 2), (1, 2, 0), (2, 0, 1))


def _parse_order(order: object, where: str) -> tuple[tuple[int, int, int], bool]:
    """``"XYZ"`` → ``((0, 1, 2), True)``: axis indices and whether the order is intrinsic."""
    valid = (
        isinstance(order, str)
        and len(order) == 3
        and (order.isupper() or order.islower())
        and set(order.lower()) <= set(_AXES)
    )
    if not valid:
        raise ValueError(
            f"{where}: order must be three letters from x, y, z, all upper case (intrinsic) or all lower "
            f"case (extrinsic), e.g. 'XYZ' or 'zxz'; got {order!r}"
        )
    axes = tuple(_AXES[letter] for letter in order.lower())
    if axes[0] == axes[1] or axes[1] == axes[2]:
        raise ValueError(f"{where}: consecutive axes of an Euler order must differ, got {order!r}")
    return axes, order.isupper()


def _elementary(angle: torch.Tensor, axis: int) -> torch.Tensor:
    """Quaternions ``(..., 4)`` of rotations by ``angle`` ``(...)`` about coordinate axis ``axis``."""
    zero = torch.zeros_like(angle)
    parts = [torch.cos(angle / 2), zero, zero, zero]
    parts[1 + axis] = torch.sin(angle / 2)
    return torch.stack(parts, dim=-1)


def euler_to_quat(angles: torch.Tensor, order: str) -> torch.Tensor:
    """Unit quaternions ``(..., 4)`` of Euler angles ``(..., 3)`` (radians) in ``order`` (e.g. ``"XYZ"``,
    ``"zxz"``)."""
    axes, intrinsic = _parse_order(order, "euler_to_quat")
    check_tensor(angles, "angles", "euler_to_quat", trailing=(3,), finite=False)
    check_finite(angles, "angles", "euler_to_quat")
    first, second, third = (_elementary(angles[..., n], axis) for n, axis in enumerate(axes))
    if intrinsic:
        return hamilton_product(hamilton_product(first, second), third)
    return hamilton_product(hamilton_product(third, second), first)


def quat_to_euler(q: torch.Tensor, order: str) -> torch.Tensor:
    """Euler angles ``(..., 3)`` in ``order`` of quaternions ``(..., 4)`` (any non-zero ``q``).

    Ranges as in scipy: outer angles in ``[-pi, pi]``; the middle angle in ``[0, pi]`` for proper
    orders and in ``[-pi/2, pi/2]`` for Tait–Bryan orders. In gimbal lock the third angle is 0.
    Differentiable, with finite gradients everywhere (also in gimbal lock).
    """
    axes, intrinsic = _parse_order(order, "quat_to_euler")
    check_tensor(q, "q", "quat_to_euler", trailing=(4,), finite=False)
    # An extrinsic order is the intrinsic order of the reversed axes, with the angles reversed.
    i, j, k = axes if intrinsic else axes[::-1]
    proper = i == k
    if proper:
        k = 3 - i - j
    parity = 1 if (i, j, k) in _EVEN_PERMUTATIONS else -1

    q, norm_sq = safely_scaled(q, "quat_to_euler", "the squared norm of q")
    w, q_i, q_j, q_k = q[..., 0], q[..., 1 + i], q[..., 1 + j], q[..., 1 + k]
    if proper:
        p0, p1, p2, p3 = w, q_i, q_j, parity * q_k
    else:  # components of q ⊗ q_j(-ε π/2), up to a factor 1/√2 and signs that fold the angle range
        p0, p1, p2, p3 = w + parity * q_j, q_i + q_k, w - parity * q_j, q_i - q_k

    outer, inner = safe_hypot(p0, p1), safe_hypot(p2, p3)
    half_middle = torch.atan2(inner, outer)  # in [0, pi/2]
    middle = 2 * half_middle if proper else parity * (math.pi / 2 - 2 * half_middle)

    p_norm = torch.sqrt(norm_sq if proper else 2 * norm_sq)  # |(p0, p1, p2, p3)|
    tolerance = 2 * torch.finfo(q.dtype).eps * p_norm
    sum_only = inner <= tolerance  # sin(half middle) = 0: only a + c is defined
    diff_only = (outer <= tolerance) & ~sum_only  # cos(half middle) = 0: only a - c is defined
    twice_sum = torch.atan2(2 * p0 * p1, p0 * p0 - p1 * p1)  # arg((p0 + i p1)^2) = a + c
    twice_diff = torch.atan2(2 * p2 * p3, p2 * p2 - p3 * p3)  # arg((p2 + i p3)^2) = a - c
    locked_angle = torch.where(sum_only, twice_sum, twice_diff)
    locked = sum_only | diff_only
    zero = torch.zeros_like(twice_sum)
    first = torch.atan2(p0 * p3 + p1 * p2, p0 * p2 - p1 * p3)  # arg((p0 + i p1)(p2 + i p3))
    last = torch.atan2(p1 * p2 - p0 * p3, p0 * p2 + p1 * p3)  # arg((p0 + i p1)(p2 - i p3))
    if intrinsic:  # the third angle of the order is `last`
        first = torch.where(locked, locked_angle, first)
        last = torch.where(locked, zero, last)
        angles = (first, middle, last)
    else:  # reversed: the third angle of the order is `first`
        last = torch.where(sum_only, locked_angle, torch.where(diff_only, -locked_angle, last))
        first = torch.where(locked, zero, first)
        angles = (last, middle, first)
    return torch.stack(angles, dim=-1)
