"""Worked solutions to chapter 01's "your turn" exercises (checked by tests/test_exercises.py)."""

from __future__ import annotations

import math

import torch


def my_quat_mul(q1: torch.Tensor, q2: torch.Tensor) -> torch.Tensor:
    """Hamilton product q1 ⊗ q2 of (..., 4) quaternions, w first; leading dimensions broadcast.

    With q = (w, v): q1 ⊗ q2 = (w1 w2 - v1·v2, w1 v2 + w2 v1 + v1 × v2).
    """
    q1, q2 = torch.broadcast_tensors(q1, q2)
    w1, v1 = q1[..., :1], q1[..., 1:]
    w2, v2 = q2[..., :1], q2[..., 1:]
    w = w1 * w2 - (v1 * v2).sum(-1, keepdim=True)
    v = w1 * v2 + w2 * v1 + torch.linalg.cross(v1, v2, dim=-1)
    return torch.cat([w, v], dim=-1)


def _sin_ratio(a: torch.Tensor, omega: torch.Tensor) -> torch.Tensor:
    """sin(a Ω) / sin(Ω) written as a · sinc(a Ω) / sinc(Ω), exact as Ω → 0 (torch.sinc(x) = sin(πx)/(πx))."""
    return a * torch.sinc(a * omega / math.pi) / torch.sinc(omega / math.pi)


def my_slerp(q0: torch.Tensor, q1: torch.Tensor, w: torch.Tensor | float) -> torch.Tensor:
    """Spherical linear interpolation of unit quaternions (..., 4) along the shorter arc.

    w: the interpolation weight (0 at q0, 1 at q1), a number or a tensor that broadcasts against the leading
    dimensions (w of shape (n,) with single quaternions gives (n, 4)).
    """
    w = torch.as_tensor(w, dtype=q0.dtype).unsqueeze(-1)
    q1 = torch.where((q0 * q1).sum(-1, keepdim=True) < 0, -q1, q1)  # the shorter arc
    omega = torch.acos((q0 * q1).sum(-1, keepdim=True).clamp(-1.0, 1.0))
    return _sin_ratio(1 - w, omega) * q0 + _sin_ratio(w, omega) * q1
