"""Axis-angle (rotation vector) representation: ``r = angle · axis``, shape ``(..., 3)``, radians.

The zero vector is the identity. ``|r|`` is the rotation angle; :func:`quat_to_axis_angle` returns
angles in ``[0, pi]``, so the representation jumps from ``pi · n`` to ``-pi · n`` when a rotation
passes through a half turn.
"""

from __future__ import annotations

import math

import torch

from motionlab.geometry.quaternion import safely_scaled
from motionlab.validation import check_finite, check_tensor


def axis_angle_to_quat(rotvec: torch.Tensor) -> torch.Tensor:
    """Unit quaternions ``(..., 4)`` of rotation vectors ``(..., 3)``.

    ``q = (cos(θ/2), sin(θ/2)/θ · r)`` with ``θ = |r|``; ``sin(θ/2)/θ = sinc(θ / 2π) / 2`` (``torch.sinc``
    is the normalised sinc), exact and differentiable at ``θ = 0``.
    """
    check_tensor(rotvec, "rotvec", "axis_angle_to_quat", trailing=(3,), finite=False)
    angle = torch.linalg.vector_norm(rotvec, dim=-1, keepdim=True)
    check_finite(angle[..., 0], "rotvec", "axis_angle_to_quat")
    return torch.cat([torch.cos(angle / 2), rotvec * (0.5 * torch.sinc(angle / (2 * math.pi)))], dim=-1)


def quat_to_axis_angle(q: torch.Tensor) -> torch.Tensor:
    """Rotation vectors ``(..., 3)`` with angle in ``[0, pi]`` of quaternions ``(..., 4)`` (any non-zero
    ``q``).

    With ``q`` flipped to ``w >= 0`` and ``s = |vec(q)|``: ``θ = 2 atan2(s, w)`` and ``r = θ / s · vec(q)``.
    At ``s = 0`` the factor ``θ / s`` is replaced by its limit ``2 / w``, so the identity has a finite
    gradient too.
    """
    check_tensor(q, "q", "quat_to_axis_angle", trailing=(4,), finite=False)
    q, _ = safely_scaled(q, "quat_to_axis_angle", "the squared norm of q")
    q = torch.where(q[..., :1] < 0, -q, q)
    w, vec = q[..., :1], q[..., 1:]
    sin_part = torch.linalg.vector_norm(vec, dim=-1, keepdim=True)
    identity = sin_part == 0
    safe_sin = torch.where(identity, torch.ones_like(sin_part), sin_part)
    safe_w = torch.where(identity, w, torch.ones_like(w))
    factor = torch.where(identity, 2 / safe_w, 2 * torch.atan2(sin_part, w) / safe_sin)
    return factor * vec
