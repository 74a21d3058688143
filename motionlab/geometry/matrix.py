"""Quaternions to rotation matrices and back.

Rotation matrices have shape ``(..., 3, 3)`` and act on column vectors: ``v' = R @ v``.
"""

from __future__ import annotations

import torch

from motionlab.geometry.quaternion import safely_scaled
from motionlab.validation import check_finite, check_tensor


def quat_to_matrix(q: torch.Tensor) -> torch.Tensor:
    """Rotation matrices ``(..., 3, 3)`` of quaternions ``(..., 4)`` (any non-zero ``q``; uses ``q/|q|``).

    With ``s = 2 / |q|^2`` the matrix is

    ``[[1 - s(y²+z²), s(xy - wz),   s(xz + wy)],``
    `` [s(xy + wz),   1 - s(x²+z²), s(yz - wx)],``
    `` [s(xz - wy),   s(yz + wx),   1 - s(x²+y²)]]``.

    A tiny or huge ``q``, whose ``|q|^2`` would underflow or overflow, is rescaled first
    (:func:`~motionlab.geometry.quaternion.safely_scaled`). Raises ``ValueError`` for a zero or non-finite
    quaternion (checked on ``|q|^2``, which is needed anyway).
    """
    check_tensor(q, "q", "quat_to_matrix", trailing=(4,), finite=False)
    q, norm_sq = safely_scaled(q, "quat_to_matrix", "the squared norm of q")
    w, x, y, z = q.unbind(-1)
    s = 2.0 / norm_sq
    xs, ys, zs = x * s, y * s, z * s
    wx, wy, wz = w * xs, w * ys, w * zs
    xx, xy, xz = x * xs, x * ys, x * zs
    yy, yz, zz = y * ys, y * zs, z * zs
    entries = [
        1 - (yy + zz), xy - wz, xz + wy,
        xy + wz, 1 - (xx + zz), yz - wx,
        xz - wy, yz + wx, 1 - (xx + yy),
    ]  # fmt: skip
    return torch.stack(entries, dim=-1).unflatten(-1, (3, 3))


def matrix_to_quat(matrix: torch.Tensor) -> torch.Tensor:
    """Unit quaternions ``(..., 4)`` with ``w >= 0`` of rotation matrices ``(..., 3, 3)``.

    Shepperd's method, written without square roots: for a rotation, the symmetric matrix

    ``K = [[1+tr, m21-m12, m02-m20, m10-m01], [·, 1+m00-m11-m22, m10+m01, m02+m20],``
    ``     [·, ·, 1-m00+m11-m22, m21+m12], [·, ·, ·, 1-m00-m11+m22]]``

    equals ``4 q qᵀ``, so each row is ``q`` scaled by ``4 q_i``. We take the row with the largest
    diagonal entry (its diagonal entries sum to 4, so that one is >= 1 and the row norm is >= 1 for any
    matrix) and normalise it: no division by a small number and no square root of a negative, so the
    result is differentiable wherever the chosen row does not switch. For a slightly non-orthogonal
    input the result is still a unit quaternion.
    """
    check_tensor(matrix, "matrix", "matrix_to_quat", trailing=(3, 3), finite=False)
    check_finite(matrix, "matrix", "matrix_to_quat")
    m00, m01, m02, m10, m11, m12, m20, m21, m22 = matrix.flatten(-2).unbind(-1)
    d_x, d_y, d_z = m21 - m12, m02 - m20, m10 - m01
    s_xy, s_xz, s_yz = m10 + m01, m02 + m20, m21 + m12
    diagonal = (1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22)
    rows = (
        (diagonal[0], d_x, d_y, d_z),
        (d_x, diagonal[1], s_xy, s_xz),
        (d_y, s_xy, diagonal[2], s_yz),
        (d_z, s_xz, s_yz, diagonal[3]),
    )
    # Keep the row with the largest diagonal entry, selecting component by component (1-D ``where`` on
    # contiguous tensors is much faster than ``argmax`` over a dimension of size 4 and a gather).
    row, largest = rows[0], diagonal[0]
    for candidate, value in zip(rows[1:], diagonal[1:]):
        better = value > largest
        row = tuple(torch.where(better, new, old) for new, old in zip(candidate, row))
        largest = torch.maximum(largest, value)
    w, x, y, z = row
    # normalise, and flip the sign so that w >= 0
    scale = torch.where(w < 0, -1.0, 1.0).to(w.dtype) / torch.sqrt(w * w + x * x + y * y + z * z)
    return torch.stack([w * scale, x * scale, y * scale, z * scale], dim=-1)
