"""Penalties that measure how far a raw network output is from a valid rotation.

A network that outputs 4 numbers per joint is not forced to output unit quaternions, and one that
outputs 9 numbers is not forced to output rotation matrices. Either project the output
(:func:`~motionlab.geometry.quat_normalize`, :func:`~motionlab.geometry.gram_schmidt`) or add
these soft penalties to the loss, or both, as the Motion Cell paper does for quaternion norms
(its eq. 26). Each returns one non-negative value per rotation, ``(...)``, zero exactly on valid input.
"""

from __future__ import annotations

import torch

from motionlab.validation import check_finite, check_tensor


def orthogonality_penalty(matrix: torch.Tensor) -> torch.Tensor:
    """``|Mᵀ M - I|²_F`` for ``(..., 3, 3)`` matrices: zero iff the columns are orthonormal."""
    check_tensor(matrix, "matrix", "orthogonality_penalty", trailing=(3, 3), finite=False)
    gram = matrix.transpose(-1, -2) @ matrix
    eye = torch.eye(3, dtype=matrix.dtype, device=matrix.device)
    penalty = ((gram - eye) ** 2).sum((-2, -1))
    check_finite(penalty, "matrix", "orthogonality_penalty")
    return penalty


def determinant_penalty(matrix: torch.Tensor) -> torch.Tensor:
    """``(det M - 1)²`` for ``(..., 3, 3)`` matrices, with ``det M = c0 · (c1 × c2)`` (columns ``c``).

    Orthogonality alone allows reflections (``det = -1``); this term rules them out.
    """
    check_tensor(matrix, "matrix", "determinant_penalty", trailing=(3, 3), finite=False)
    det = (matrix[..., :, 0] * torch.linalg.cross(matrix[..., :, 1], matrix[..., :, 2], dim=-1)).sum(-1)
    check_finite(det, "matrix", "determinant_penalty")
    return (det - 1) ** 2


def quat_norm_penalty(q: torch.Tensor) -> torch.Tensor:
    """``(|q| - 1)²`` for ``(..., 4)`` quaternions (the Motion Cell eq. 26 style norm constraint).

    Its gradient ``2 (|q| - 1) q / |q|`` points along ``q``: exactly the direction that
    normalisation ignores. At ``q = 0`` the gradient is 0 (a subgradient), not NaN.
    """
    check_tensor(q, "q", "quat_norm_penalty", trailing=(4,), finite=False)
    norm = torch.linalg.vector_norm(q, dim=-1)
    check_finite(norm, "q", "quat_norm_penalty")
    return (norm - 1) ** 2
