"""Elementary functions with finite gradients at their singular points, and angle wrapping."""

from __future__ import annotations

import math

import torch


def safe_hypot(x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
    """``sqrt(x**2 + y**2)`` whose gradient at ``x = y = 0`` is zero instead of NaN (``torch.hypot``'s)."""
    origin = (x == 0) & (y == 0)
    one = torch.ones_like(x)
    value = torch.hypot(torch.where(origin, one, x), torch.where(origin, one, y))
    return torch.where(origin, torch.zeros_like(value), value)


def wrap_angle(angle: torch.Tensor) -> torch.Tensor:
    """Wrap angles (radians) into ``[-pi, pi]``; the gradient passes through unchanged."""
    return angle - (2 * math.pi) * torch.round(angle / (2 * math.pi))
