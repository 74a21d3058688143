"""Worked solutions to chapter 05's "your turn" exercises (checked by tests/test_exercises.py)."""

from __future__ import annotations

from collections.abc import Callable

import torch
import torch.nn.functional as F


def my_coupling_forward(
    x: torch.Tensor, mask: torch.Tensor, net: Callable[[torch.Tensor], torch.Tensor]
) -> tuple[torch.Tensor, torch.Tensor]:
    """An affine coupling on points x (N, D): the coordinates where mask (D,) is 1 pass unchanged and feed
    net, whose output (N, 2D) is the shift u and the raw scale r; the others become (x + u) * sigmoid(r + 2).
    Returns y (N, D) and the log-determinant (N,), the sum of log sigmoid(r + 2) over the transformed
    coordinates."""
    shift, raw = net(x * mask).chunk(2, dim=-1)
    y = mask * x + (1 - mask) * (x + shift) * torch.sigmoid(raw + 2.0)
    logdet = ((1 - mask) * F.logsigmoid(raw + 2.0)).sum(dim=-1)
    return y, logdet


def my_coupling_inverse(
    y: torch.Tensor, mask: torch.Tensor, net: Callable[[torch.Tensor], torch.Tensor]
) -> torch.Tensor:
    """x (N, D) from y (N, D): u and r are recomputed from the passed half (y = x there), then the transform's
    steps are undone in reverse order, x = y / sigmoid(r + 2) - u."""
    shift, raw = net(y * mask).chunk(2, dim=-1)
    return mask * y + (1 - mask) * (y / torch.sigmoid(raw + 2.0) - shift)
