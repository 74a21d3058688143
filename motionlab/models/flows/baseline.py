"""The simplest density baseline: an independent Gaussian per channel, fitted by maximum likelihood.

For sequences ``(batch, C, T)`` every number of channel ``c`` is modelled as ``N(mean_c, std_c**2)``
independently of all others (no correlation between joints, none over time). Its held-out negative
log-likelihood is the bar a flow has to clear to show that it captured any structure.
"""

from __future__ import annotations

import numbers

import torch
from torch import Tensor, nn

from motionlab.models.flows.base import check_sequence
from motionlab.models.flows.prior import LOG_2PI
from motionlab.validation import check_scalar


class DiagonalGaussian(nn.Module):
    """``x[:, c, t] ~ N(mean[c], std[c]**2)`` independently; :meth:`fit` sets the maximum-likelihood values.

    Args:
        channels: channels ``C``.
        min_std: floor on the fitted standard deviations.
    """

    mean: Tensor
    std: Tensor

    def __init__(self, channels: int, min_std: float = 1e-6) -> None:
        super().__init__()
        check_scalar(channels, "channels", "DiagonalGaussian", kind=numbers.Integral, minimum=1)
        self.channels, self.min_std = channels, float(min_std)
        self.register_buffer("mean", torch.zeros(channels))
        self.register_buffer("std", torch.ones(channels))

    @torch.no_grad()
    def fit(self, x: Tensor) -> DiagonalGaussian:
        """Maximum-likelihood mean and (population) std per channel from ``x`` ``(batch, C, T)``; returns
        self."""
        check_sequence(x, "x", "DiagonalGaussian.fit", self.channels)
        flat = x.transpose(0, 1).reshape(self.channels, -1).double()
        if flat.shape[1] < 2:
            raise ValueError(
                f"DiagonalGaussian.fit: needs at least 2 values per channel, got shape {tuple(x.shape)}"
            )
        self.mean.copy_(flat.mean(dim=1))
        self.std.copy_(flat.std(dim=1, correction=0).clamp(min=self.min_std))
        return self

    def log_prob(self, x: Tensor) -> Tensor:
        """``log p(x)`` per sequence ``(batch,)``, in nats."""
        check_sequence(x, "x", "DiagonalGaussian.log_prob", self.channels)
        z = (x - self.mean[:, None].to(x)) / self.std[:, None].to(x)
        per_value = -0.5 * (z.pow(2) + LOG_2PI) - torch.log(self.std[:, None].to(x))
        return per_value.sum(dim=(1, 2))
