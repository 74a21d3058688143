"""Elementary functions with finite gradients at their singular points."""

from __future__ import annotations

import torch


def safe_hypot(x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
    """``sqrt(x**2 + y**2)`` whose gradient at ``x = y = 0`` is zero instead of NaN (``torch.hypot``'s)."""
    origin = (x == 0) & (y == 0)
    one = torch.ones_like(x)
    value = torch.hypot(torch.where(origin, one, x), torch.where(origin, one, y))
    return torch.where(origin, torch.zeros_like(value), value)
