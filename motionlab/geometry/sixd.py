"""The continuous 6D representation of Zhou et al. (CVPR 2019) and Gram–Schmidt orthonormalisation.

A rotation matrix is stored as its first two columns, ``(g1, g2)`` concatenated into shape ``(..., 6)``.
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

    ``m1 = g1 / |g1|``, ``m2 = normalize(g2 - (m1·g2) m1)``, ``m3 = m1 × m2``. A third input column is
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


def _orthonormal_frame(g1: torch.Tensor, g2: torch.Tensor, where: str) -> torch.Tensor:
    """The rotation whose first column is along ``g1`` and whose second lies in the ``g1, g2`` plane."""
    norm0 = torch.linalg.vector_norm(g1, dim=-1, keepdim=True)
    check_positive_finite(norm0[..., 0], "the norm of the first column", where)
    m1 = g1 / norm0
    u2 = g2 - (m1 * g2).sum(-1, keepdim=True) * m1
    # A second pass keeps m2 orthogonal to m1 to rounding even when g2 is nearly parallel to g1.
    u2 = u2 - (m1 * u2).sum(-1, keepdim=True) * m1
    norm1 = torch.linalg.vector_norm(u2, dim=-1, keepdim=True)
    parallel = norm1 <= 16 * torch.finfo(g2.dtype).eps * torch.linalg.vector_norm(g2, dim=-1, keepdim=True)
    check_none(parallel[..., 0], "the second column is parallel to the first (or zero)", where)
    m2 = u2 / norm1
    return torch.stack([m1, m2, torch.linalg.cross(m1, m2, dim=-1)], dim=-1)


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
