"""The continuous 6D representation of Zhou et al. (CVPR 2019) and Gram–Schmidt orthonormalisation.

A rotation matrix is stored as its first two columns, ``(c0, c1)`` concatenated into shape ``(..., 6)``.
Going back, Gram–Schmidt turns any two non-parallel 3-vectors into the first two columns of a rotation
and the cross product supplies the third. Unlike quaternions (double cover) or Euler angles and rotation
vectors (wrap-arounds), this map from rotations to ``R^6`` is continuous, which is why networks that
regress rotations often output 6D.
"""

from __future__ import annotations

import torch

from motionlab.validation import check_finite, check_none, check_positive_finite, check_tensor


def gram_schmidt(columns: torch.Tensor) -> torch.Tensor:
    """Rotation matrices ``(..., 3, 3)`` from the first two columns of ``columns`` (``(..., 3, 2)`` or ``(...,
    3, 3)``).

    ``b0 = c0 / |c0|``, ``b1 = normalize(c1 - (b0·c1) b0)``, ``b2 = b0 × b1``. A third input column is
    ignored: the result is always a proper rotation (``det = +1``), and equals classical Gram–Schmidt on
    all three columns whenever ``det(columns) > 0``. Raises ``ValueError`` when the first column is zero,
    the second is zero or parallel to it (to rounding: then its direction is meaningless), or the input
    is not finite.
    """
    if isinstance(columns, torch.Tensor) and tuple(columns.shape[-2:]) == (3, 3):
        check_tensor(columns, "columns", "gram_schmidt", trailing=(3, 3), finite=False)
    else:
        check_tensor(
            columns, "columns (or a (..., 3, 3) matrix)", "gram_schmidt", trailing=(3, 2), finite=False
        )
    check_finite(columns, "columns", "gram_schmidt")
    return _orthonormal_frame(columns[..., :, 0], columns[..., :, 1], "gram_schmidt")


def _orthonormal_frame(c0: torch.Tensor, c1: torch.Tensor, where: str) -> torch.Tensor:
    """The rotation whose first column is along ``c0`` and whose second lies in the ``c0, c1`` plane."""
    norm0 = torch.linalg.vector_norm(c0, dim=-1, keepdim=True)
    check_positive_finite(norm0[..., 0], "the norm of the first column", where)
    b0 = c0 / norm0
    u1 = c1 - (b0 * c1).sum(-1, keepdim=True) * b0
    # A second pass keeps b1 orthogonal to b0 to rounding even when c1 is nearly parallel to c0.
    u1 = u1 - (b0 * u1).sum(-1, keepdim=True) * b0
    norm1 = torch.linalg.vector_norm(u1, dim=-1, keepdim=True)
    parallel = norm1 <= 16 * torch.finfo(c1.dtype).eps * torch.linalg.vector_norm(c1, dim=-1, keepdim=True)
    check_none(parallel[..., 0], "the second column is parallel to the first (or zero)", where)
    b1 = u1 / norm1
    return torch.stack([b0, b1, torch.linalg.cross(b0, b1, dim=-1)], dim=-1)


def matrix_to_sixd(matrix: torch.Tensor) -> torch.Tensor:
    """The 6D representation ``(..., 6)``: first column, then second column of ``matrix`` ``(..., 3, 3)``."""
    check_tensor(matrix, "matrix", "matrix_to_sixd", trailing=(3, 3), finite=False)
    check_finite(matrix, "matrix", "matrix_to_sixd")
    return matrix[..., :, :2].transpose(-1, -2).flatten(-2)


def sixd_to_matrix(sixd: torch.Tensor) -> torch.Tensor:
    """Rotation matrices ``(..., 3, 3)`` from 6D vectors ``(..., 6)`` by Gram–Schmidt (see
    :func:`gram_schmidt`)."""
    check_tensor(sixd, "sixd", "sixd_to_matrix", trailing=(6,), finite=False)
    check_finite(sixd, "sixd", "sixd_to_matrix")
    return _orthonormal_frame(sixd[..., :3], sixd[..., 3:], "sixd_to_matrix")
