"""Quaternion algebra: product, conjugate, normalisation, sign convention, rotating vectors.

Quaternions are tensors of shape ``(..., 4)`` ordered ``(w, x, y, z)`` (scalar first). ``q`` and ``-q``
are the same rotation. The product follows Hamilton's convention, so ``quat_mul(q1, q2)`` is the
rotation "first ``q2``, then ``q1``", matching ``quat_to_matrix(q1) @ quat_to_matrix(q2)``.

Functions that turn a quaternion into a rotation (:func:`quat_apply`, and the conversions and
distances in the sibling modules) accept any non-zero quaternion and use the rotation of ``q / |q|``;
those that need ``|q|`` divide a tiny or huge but finite ``q`` (float32 ``1e-20`` or ``1e20``) by its
largest ``|component|`` first (:func:`safely_scaled`), so that it gives the rotation of its unit version
instead of an underflowed or overflowed ``|q|^2``. The algebra here (:func:`quat_mul`,
:func:`quat_conjugate`) takes quaternions as they are.
"""

from __future__ import annotations

import torch

from motionlab.geometry.broadcast import promote_and_broadcast
from motionlab.validation import check_finite, check_positive_finite, check_tensor


def quat_identity(
    shape: tuple[int, ...] = (), dtype: torch.dtype | None = None, device: torch.device | str | None = None
) -> torch.Tensor:
    """Identity rotations ``(1, 0, 0, 0)`` of shape ``(*shape, 4)``."""
    q = torch.zeros(*shape, 4, dtype=dtype, device=device)
    q[..., 0] = 1
    return q


def hamilton_product(q1: torch.Tensor, q2: torch.Tensor) -> torch.Tensor:
    """Unchecked Hamilton product of broadcastable ``(..., 4)`` tensors (the kernel of :func:`quat_mul`)."""
    w1, x1, y1, z1 = q1.unbind(-1)
    w2, x2, y2, z2 = q2.unbind(-1)
    return torch.stack(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ],
        dim=-1,
    )


def quat_mul(q1: torch.Tensor, q2: torch.Tensor) -> torch.Tensor:
    """Hamilton product ``q1 ⊗ q2`` of ``(..., 4)`` quaternions (leading dims broadcast).

    As rotations: apply ``q2`` first, then ``q1``.
    """
    check_tensor(q1, "q1", "quat_mul", trailing=(4,), finite=False)
    check_tensor(q2, "q2", "quat_mul", trailing=(4,), finite=False)
    check_finite(q1, "q1", "quat_mul")
    check_finite(q2, "q2", "quat_mul")
    return hamilton_product(q1, q2)


def quat_conjugate(q: torch.Tensor) -> torch.Tensor:
    """Conjugate ``(w, -x, -y, -z)``; for a unit quaternion this is the inverse rotation."""
    check_tensor(q, "q", "quat_conjugate", trailing=(4,), finite=False)
    check_finite(q, "q", "quat_conjugate")
    return q * q.new_tensor([1.0, -1.0, -1.0, -1.0])


def quat_normalize(q: torch.Tensor) -> torch.Tensor:
    """``q / |q|`` for ``(..., 4)`` quaternions.

    Raises ``ValueError`` for a zero or non-finite quaternion instead of returning NaNs. The gradient
    of the result is orthogonal to ``q``: normalising says nothing about how long ``q`` should be.
    """
    check_tensor(q, "q", "quat_normalize", trailing=(4,), finite=False)
    return normalized(q, "quat_normalize", "q")


def safely_scaled(q: torch.Tensor, where: str, what: str) -> tuple[torch.Tensor, torch.Tensor]:
    """``(p, |p|^2)``: ``p`` ``(..., 4)`` a positive multiple of ``q`` whose squared norm ``(...)`` is safe to
    use.

    Squares of the components of a tiny or huge ``q`` underflow or overflow (in float32 ``|q|^2`` is 0 below
    ``|q| ≈ 5e-23`` and inf above ``≈ 2e19``, and ``2 / |q|^2`` is inf below ``≈ 8e-20``). When every
    ``|q|^2`` lies in ``[tiny / eps, eps / tiny]`` of the dtype (``|q|`` from about ``3e-16`` to ``3e15`` in
    float32, ``1e-146`` to ``1e146`` in float64), squaring the components and dividing by ``|q|^2`` lose
    nothing, and ``p = q``: the common case costs one reduction of ``|q|^2``, which the caller needs anyway.
    Otherwise ``p = q / max_i |q_i|``, with ``1 <= |p|^2 <= 4``.

    Raises ``ValueError`` ``"{where}: {what} is zero or not finite ..."`` for a zero ``q`` or one with a NaN
    or an infinity: exactly then the largest ``|component|`` is 0, inf or NaN, and so are ``|q|`` and
    ``|q|^2``, so the value the message shows is theirs too.

    Autograd treats the scale ``max_i |q_i|`` as a constant. That leaves the gradient of any function of
    the direction of ``q`` alone (``f(q / m) = f(q)`` for every ``m > 0``), and only such functions may use
    ``p``.
    """
    norm_sq = (q * q).sum(-1)
    if norm_sq.numel() == 0:
        return q, norm_sq
    info = torch.finfo(q.dtype)
    smallest, largest = torch.aminmax(norm_sq.detach())
    if bool(smallest >= info.tiny / info.eps) and bool(largest <= info.eps / info.tiny):  # NaN fails both
        return q, norm_sq
    largest_component = q.detach().abs().amax(dim=-1, keepdim=True)
    check_positive_finite(largest_component[..., 0], what, where)
    q = q / largest_component
    return q, (q * q).sum(-1)


def normalized(q: torch.Tensor, where: str, name: str) -> torch.Tensor:
    """``q / |q|`` along the last dimension, raising (as ``where``) for a zero or non-finite ``q``.

    ``|q|`` is ``torch.linalg.vector_norm``; a tiny or huge ``q`` is rescaled first (:func:`safely_scaled`),
    an ordinary one is left exactly as it is (so the result is bitwise that of ``q / vector_norm(q)``).
    """
    q, _ = safely_scaled(q, where, f"the norm of {name}")
    return q / torch.linalg.vector_norm(q, dim=-1, keepdim=True)


def quat_standardize(q: torch.Tensor) -> torch.Tensor:
    """Pick the representative with ``w >= 0`` (``q`` and ``-q`` are the same rotation)."""
    check_tensor(q, "q", "quat_standardize", trailing=(4,), finite=False)
    check_finite(q, "q", "quat_standardize")
    return torch.where(q[..., :1] < 0, -q, q)


def quat_apply(q: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """Rotate vectors ``v`` of shape ``(..., 3)`` by quaternions ``q`` of shape ``(..., 4)``.

    Leading dimensions broadcast. Equivalent to ``quat_to_matrix(q) @ v`` but cheaper: with
    ``s = 2 / |q|^2``, ``u = vec(q)`` and ``t = u × v``, the result is ``v + s (w t + u × t)`` (for a tiny
    or huge ``q``, of ``q`` rescaled by :func:`safely_scaled`).
    """
    check_tensor(q, "q", "quat_apply", trailing=(4,), finite=False)
    check_tensor(v, "v", "quat_apply", trailing=(3,), finite=False)
    check_finite(v, "v", "quat_apply")
    q, norm_sq = safely_scaled(q, "quat_apply", "the squared norm of q")
    w, u = q[..., :1], q[..., 1:]
    u, v = promote_and_broadcast(u, v)
    t = torch.linalg.cross(u, v, dim=-1)
    return v + (2.0 / norm_sq.unsqueeze(-1)) * (w * t + torch.linalg.cross(u, t, dim=-1))


def quat_from_two_vectors(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """The shortest-arc unit quaternion that turns the direction of ``a`` into the direction of ``b``.

    ``a`` and ``b`` have shape ``(..., 3)`` (broadcast) and must be non-zero. With unit vectors
    ``â, b̂`` and the half-way vector ``h = â + b̂``, the rotation is ``(â·h, â × h) / |h|``: the
    rotation by the angle between them about their common normal. For exactly opposite vectors
    (``|h|`` at rounding level) every axis orthogonal to ``a`` works; we take the half turn about
    ``â × e``, with ``e`` the coordinate axis least aligned with ``a``.
    """
    check_tensor(a, "a", "quat_from_two_vectors", trailing=(3,), finite=False)
    check_tensor(b, "b", "quat_from_two_vectors", trailing=(3,), finite=False)
    norm_a = torch.linalg.vector_norm(a, dim=-1, keepdim=True)
    norm_b = torch.linalg.vector_norm(b, dim=-1, keepdim=True)
    check_positive_finite(norm_a[..., 0], "the norm of a", "quat_from_two_vectors")
    check_positive_finite(norm_b[..., 0], "the norm of b", "quat_from_two_vectors")
    unit_a, unit_b = promote_and_broadcast(a / norm_a, b / norm_b)
    halfway = unit_a + unit_b
    turned = torch.cat(
        [(unit_a * halfway).sum(-1, keepdim=True), torch.linalg.cross(unit_a, halfway, dim=-1)], -1
    )

    least_aligned = torch.nn.functional.one_hot(unit_a.abs().argmin(-1), 3).to(unit_a.dtype)
    axis = torch.linalg.cross(unit_a, least_aligned, dim=-1)
    half_turn = torch.cat([torch.zeros_like(axis[..., :1]), axis], -1)

    opposite = torch.linalg.vector_norm(halfway, dim=-1, keepdim=True) <= 8 * torch.finfo(unit_a.dtype).eps
    q = torch.where(opposite, half_turn, turned)
    return q / torch.linalg.vector_norm(q, dim=-1, keepdim=True)
