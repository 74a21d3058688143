"""Bringing two tensor arguments of a geometry function to one dtype and one shape."""

from __future__ import annotations

import torch


def promote_and_broadcast(a: torch.Tensor, b: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """``a`` and ``b`` in their common dtype (as element-wise torch ops would promote) and broadcast shape.

    Needed before ``torch.linalg.cross``, which neither promotes dtypes nor broadcasts different ranks.
    """
    dtype = torch.promote_types(a.dtype, b.dtype)
    return torch.broadcast_tensors(a.to(dtype), b.to(dtype))
