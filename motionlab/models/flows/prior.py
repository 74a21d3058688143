"""The base distribution of the flows: a standard normal, sampled at a temperature.

``log N(z; 0, I) = -0.5 * sum(z**2) - 0.5 * D * log(2 pi)`` for ``D`` numbers. Sampling at temperature
``tau`` draws ``z = tau * eps`` with ``eps ~ N(0, I)``: ``tau < 1`` concentrates samples where the model is
most confident (cleaner, less varied motion), ``tau = 1`` is the model's own distribution.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

LOG_2PI = math.log(2.0 * math.pi)


def check_temperature(temperature: float, where: str) -> float:
    """``temperature`` as a float, or ``ValueError`` unless it is finite and ``>= 0``."""
    try:
        value = float(temperature)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{where}: temperature must be a number, got {type(temperature).__name__}") from exc
    if not math.isfinite(value) or value < 0:
        raise ValueError(f"{where}: temperature must be finite and >= 0, got {temperature!r}")
    return value


class StandardNormal:
    """``N(0, I)`` over tensors ``(batch, ...)``; log-densities are summed over everything but the batch."""

    def log_prob(self, z: Tensor) -> Tensor:
        """``log N(z; 0, I)`` per batch element, ``(batch,)``."""
        if not isinstance(z, Tensor) or not z.is_floating_point() or z.dim() < 1:
            raise ValueError(
                f"StandardNormal.log_prob: z must be a floating tensor (batch, ...), got {z!r:.60}"
            )
        flat = z.reshape(z.shape[0], -1)
        return -0.5 * (flat.pow(2).sum(dim=1) + flat.shape[1] * LOG_2PI)

    def sample(
        self,
        shape: tuple[int, ...],
        temperature: float = 1.0,
        generator: torch.Generator | None = None,
        dtype: torch.dtype = torch.float32,
    ) -> Tensor:
        """``temperature * eps`` with ``eps ~ N(0, I)`` of ``shape``, drawn from ``generator``."""
        temperature = check_temperature(temperature, "StandardNormal.sample")
        return temperature * torch.randn(shape, generator=generator, dtype=dtype)
