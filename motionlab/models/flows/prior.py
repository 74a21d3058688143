"""The base distribution of the flows: a standard normal, sampled at a temperature.

``log N(z; 0, I) = -0.5 * sum(z**2) - 0.5 * D * log(2 pi)`` for ``D`` numbers. Sampling at temperature
``tau`` draws ``z = tau * eps`` with ``eps ~ N(0, I)``: ``tau < 1`` concentrates samples where the model is
most confident (cleaner, less varied motion), ``tau = 1`` is the model's own distribution.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

from motionlab.validation import check_scalar, check_tensor

LOG_2PI = math.log(2.0 * math.pi)


def check_temperature(temperature: float, where: str) -> float:
    """``temperature`` as a float, checked by :func:`motionlab.validation.check_scalar` (finite, ``>= 0``)."""
    return float(check_scalar(temperature, "temperature", where, minimum=0))


class StandardNormal:
    """``N(0, I)`` over tensors ``(batch, ...)``; log-densities are summed over everything but the batch."""

    def log_prob(self, z: Tensor) -> Tensor:
        """``log N(z; 0, I)`` per batch element, ``(batch,)``."""
        check_tensor(z, "z", "StandardNormal.log_prob", min_leading=1, finite=False)
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
