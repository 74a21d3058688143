"""Distances between rotations: the quaternion distances d1, d2, d3 of the Motion Cell paper and the
geodesic distance of rotation matrices.

All are invariant under ``q ↦ -q`` and have finite gradients everywhere, including identical and
opposite (``q' = -q``) inputs. The quaternion distances take ``(..., 4)`` tensors (leading dims
broadcast) and return ``(...)``.

- d1, the geodesic distance: ``2 arccos |<q, q'>|`` ``= θ``, the rotation angle in ``[0, π]`` (radians);
  computed as ``2 atan2(|vec r|, |w_r|)`` with the relative rotation ``r = q* ⊗ q'``.
- d2: ``1 - |<q, q'>|`` ``= 1 - cos(θ/2)``, in ``[0, 1]``.
- d3: ``min(|q - q'|², |q + q'|²)`` ``= 2 - 2 cos(θ/2) = 2 d2``, in ``[0, 2]``; computed as ``|q - s q'|²``
  with ``s = sign<q, q'>``.

``arccos`` has an infinite derivative at 1, i.e. at identical rotations, and loses half the digits
there (``arccos(1 - ε) ≈ sqrt(2ε)``); the ``atan2`` form is exact and has a finite gradient. d1 is
also exact for non-unit quaternions (it is scale invariant); d2 and d3 are the paper's formulas and
expect unit quaternions.
"""

from __future__ import annotations

import torch

from motionlab.geometry.broadcast import promote_and_broadcast
from motionlab.geometry.quaternion import safely_scaled
from motionlab.validation import check_finite, check_positive_finite, check_tensor


def _check_pair(q: torch.Tensor, r: torch.Tensor, where: str) -> torch.Tensor:
    """Check shapes and return the dot product ``<q, r>`` ``(...)`` (finite iff all inputs are finite)."""
    check_tensor(q, "q", where, trailing=(4,), finite=False)
    check_tensor(r, "r", where, trailing=(4,), finite=False)
    dot = (q * r).sum(-1)
    check_finite(dot, "<q, r> (so q or r)", where)
    return dot


def quat_geodesic(q: torch.Tensor, r: torch.Tensor) -> torch.Tensor:
    """d1: the angle (radians, ``[0, π]``) of the rotation taking ``q`` to ``r``; any non-zero quaternions.

    With the relative rotation ``q* ⊗ r = (<q, r>, w_q vec(r) - w_r vec(q) - vec(q) × vec(r))``,
    ``d1 = 2 atan2(|vec|, |<q, r>|)``. Raises ``ValueError`` for zero or non-finite inputs; tiny or huge
    ones are rescaled first (:func:`~motionlab.geometry.quaternion.safely_scaled`), so that the products
    neither underflow nor overflow.
    """
    _check_pair(q, r, "quat_geodesic")
    q, _ = safely_scaled(q, "quat_geodesic", "|q|")
    r, _ = safely_scaled(r, "quat_geodesic", "|r|")
    dot = (q * r).sum(-1)
    q, r = promote_and_broadcast(q, r)
    vec = (
        q[..., :1] * r[..., 1:] - r[..., :1] * q[..., 1:] - torch.linalg.cross(q[..., 1:], r[..., 1:], dim=-1)
    )
    sin_part = torch.linalg.vector_norm(vec, dim=-1)
    # |q* ⊗ r|^2 = |q|^2 |r|^2: zero exactly when q or r is zero
    check_positive_finite(dot * dot + sin_part * sin_part, "|q| |r|", "quat_geodesic")
    return 2 * torch.atan2(sin_part, dot.abs())


def quat_d2(q: torch.Tensor, r: torch.Tensor) -> torch.Tensor:
    """d2 ``= 1 - |<q, r>|`` for unit quaternions; in ``[0, 1]``, equal to ``1 - cos(θ/2)``.

    Near θ = 0 it behaves like ``θ²/8``: in float32 it is exactly 0 below θ ≈ 3e-4 rad.
    """
    return 1 - _check_pair(q, r, "quat_d2").abs()


def quat_d3(q: torch.Tensor, r: torch.Tensor) -> torch.Tensor:
    """d3 ``= min(|q - r|², |q + r|²)`` for unit quaternions; in ``[0, 2]``, equal to ``2 - 2 cos(θ/2)``.

    Computed as ``|q - s r|²`` with ``s = +1`` if ``<q, r> >= 0`` else ``-1`` (the smaller branch),
    which keeps full relative precision near θ = 0.
    """
    dot = _check_pair(q, r, "quat_d3")
    sign = torch.where(dot < 0, -1.0, 1.0).to(q.dtype).unsqueeze(-1)
    diff = q - sign * r
    return (diff * diff).sum(-1)


def matrix_geodesic(m1: torch.Tensor, m2: torch.Tensor) -> torch.Tensor:
    """Angle (radians, ``[0, π]``) of the rotation ``m1ᵀ m2`` between rotation matrices ``(..., 3, 3)``.

    This is the norm of the log map, ``|log(m1ᵀ m2)|``. With ``M = m1ᵀ m2``, ``2 cos θ = tr M - 1`` and
    ``2 sin θ = |(M21 - M12, M02 - M20, M10 - M01)|``, so ``θ = atan2(|skew|, tr M - 1)``: accurate at
    every angle, with finite gradients at 0 and π (``arccos((tr - 1)/2)`` has neither). ``M`` is never
    formed: ``tr M = Σ m1 ∘ m2`` and the skew vector is ``Σ_rows m2_row × m1_row``.
    """
    check_tensor(m1, "m1", "matrix_geodesic", trailing=(3, 3), finite=False)
    check_tensor(m2, "m2", "matrix_geodesic", trailing=(3, 3), finite=False)
    trace = (m1 * m2).sum((-2, -1))
    check_finite(trace, "tr(m1ᵀ m2) (so m1 or m2)", "matrix_geodesic")
    m1, m2 = promote_and_broadcast(m1, m2)
    skew = torch.linalg.cross(m2, m1, dim=-1).sum(-2)
    return torch.atan2(torch.linalg.vector_norm(skew, dim=-1), trace - 1)
