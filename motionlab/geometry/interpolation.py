"""Interpolating rotations: slerp (constant angular speed) and nlerp (normalised linear blend).

Both take the shorter of the two arcs: when ``<q0, q1> < 0`` they use ``-q1``, the same rotation,
so that the path turns by at most half a turn. The interpolation weight ``w`` runs from 0 (at ``q0``)
to 1 (at ``q1``); chapter 01 writes it :math:`w`, not :math:`t`, which is the course's frame index.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import torch

from motionlab.geometry.quaternion import normalized
from motionlab.validation import check_finite, check_tensor


def _endpoints(q0: torch.Tensor, q1: torch.Tensor, w: torch.Tensor | float, where: str):
    check_tensor(q0, "q0", where, trailing=(4,), finite=False)
    check_tensor(q1, "q1", where, trailing=(4,), finite=False)
    w = torch.as_tensor(w, dtype=q0.dtype, device=q0.device)
    check_finite(w, "w", where)
    q0, q1 = normalized(q0, where, "q0"), normalized(q1, where, "q1")
    q1 = torch.where((q0 * q1).sum(-1, keepdim=True) < 0, -q1, q1)
    return q0, q1, w.unsqueeze(-1)


def quat_slerp(q0: torch.Tensor, q1: torch.Tensor, w: torch.Tensor | float) -> torch.Tensor:
    """Spherical linear interpolation along the shortest arc from ``q0`` (``w = 0``) to ``q1`` (``w = 1``).

    ``q0, q1``: ``(..., 4)``, any non-zero quaternions (normalised here). ``w``: the interpolation
    weight, a number or a tensor broadcastable against the leading dims, e.g. ``w`` of shape ``(n,)``
    with single quaternions of shape ``(4,)`` gives a path of shape ``(n, 4)``. With ``Ω`` the angle
    between the unit quaternions,

    ``slerp = sin((1 - w) Ω) / sin Ω · q0 + sin(w Ω) / sin Ω · q1``,

    written with ``sinc`` so that ``Ω → 0`` is exact and differentiable. ``Ω`` comes from
    ``2 atan2(|q0 - q1|, |q0 + q1|)``, accurate at every angle (unlike ``arccos <q0, q1>``).
    """
    q0, q1, w = _endpoints(q0, q1, w, "quat_slerp")
    omega = 2 * torch.atan2(
        torch.linalg.vector_norm(q0 - q1, dim=-1, keepdim=True),
        torch.linalg.vector_norm(q0 + q1, dim=-1, keepdim=True),
    )
    sinc_omega = torch.sinc(omega / math.pi)  # >= 2/pi because omega <= pi/2
    weight0 = (1 - w) * torch.sinc((1 - w) * omega / math.pi) / sinc_omega
    weight1 = w * torch.sinc(w * omega / math.pi) / sinc_omega
    return weight0 * q0 + weight1 * q1


def quat_nlerp(q0: torch.Tensor, q1: torch.Tensor, w: torch.Tensor | float) -> torch.Tensor:
    """Normalised linear interpolation ``normalize((1 - w) q0 + w q1)`` along the shortest arc.

    Same shapes as :func:`quat_slerp`. It follows the same great circle as slerp but not at constant
    speed: it is fastest in the middle. The blend is never zero: after the sign flip the endpoints
    are two different points of the same hemisphere, or the same point.
    """
    q0, q1, w = _endpoints(q0, q1, w, "quat_nlerp")
    return normalized((1 - w) * q0 + w * q1, "quat_nlerp", "the blend")


class InterpolationPaths(NamedTuple):
    """Both interpolations sampled at the same weights."""

    w: torch.Tensor  #: ``(n,)`` interpolation weights from 0 to 1
    slerp: torch.Tensor  #: ``(n, ..., 4)`` slerp quaternions
    nlerp: torch.Tensor  #: ``(n, ..., 4)`` nlerp quaternions


def interpolation_paths(q0: torch.Tensor, q1: torch.Tensor, n: int = 50) -> InterpolationPaths:
    """Sample slerp and nlerp from ``q0`` to ``q1`` at ``n`` evenly spaced weights ``w`` in ``[0, 1]``.

    ``q0, q1``: ``(..., 4)``; the paths have shape ``(n, ..., 4)`` (path index first).
    """
    if not isinstance(n, int) or n < 2:
        raise ValueError(f"interpolation_paths: n must be an integer >= 2, got {n!r}")
    check_tensor(q0, "q0", "interpolation_paths", trailing=(4,), finite=False)
    w = torch.linspace(0, 1, n, dtype=q0.dtype, device=q0.device)
    w_batched = w.reshape((n,) + (1,) * (q0.dim() - 1))
    return InterpolationPaths(w, quat_slerp(q0, q1, w_batched), quat_nlerp(q0, q1, w_batched))
