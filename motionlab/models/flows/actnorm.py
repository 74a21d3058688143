"""ActNorm (Glow): a per-channel affine map whose initial values standardise the first batch it sees.

``y = (x + bias) * exp(log_scale)`` per channel, shared over time. On the first ``forward`` in training
mode the parameters are set so that this batch leaves with zero mean and unit variance per channel
(data-dependent initialisation); from then on they are ordinary trainable parameters. The Jacobian is
diagonal, so ``log |det J| = time * sum(log_scale)`` for every sequence.
"""

from __future__ import annotations

import numbers

import torch
from torch import Tensor, nn

from motionlab.models.flows.base import FlowLayer, check_sequence
from motionlab.validation import check_scalar


class ActNorm(FlowLayer):
    """Per-channel scale and bias with data-dependent initialisation on the first training batch.

    Args:
        channels: number of channels ``C`` of the ``(batch, C, time)`` input.
        eps: added to the standard deviation at initialisation (a constant channel gets scale ``1 / eps``
            only up to this floor).

    Before initialisation (a fresh layer in eval mode) the map is the identity. The flag ``initialized``
    is a buffer, so a loaded checkpoint is never re-initialised.
    """

    initialized: Tensor

    def __init__(self, channels: int, eps: float = 1e-6) -> None:
        super().__init__()
        check_scalar(channels, "channels", "ActNorm", kind=numbers.Integral, minimum=1)
        self.channels = channels
        self.eps = float(eps)
        self.bias = nn.Parameter(torch.zeros(channels))
        self.log_scale = nn.Parameter(torch.zeros(channels))
        self.register_buffer("initialized", torch.tensor(False))

    def extra_repr(self) -> str:
        return f"channels={self.channels}, initialized={bool(self.initialized)}"

    @torch.no_grad()
    def initialize(self, x: Tensor) -> None:
        """Set bias and scale so that ``x`` ``(batch, C, time)`` maps to zero mean, unit variance per
        channel."""
        check_sequence(x, "x", "ActNorm.initialize", self.channels)
        if x.shape[0] * x.shape[2] < 2:
            raise ValueError(
                f"ActNorm.initialize: needs at least 2 values per channel, got shape {tuple(x.shape)}"
            )
        flat = x.transpose(0, 1).reshape(self.channels, -1).double()
        self.bias.copy_(-flat.mean(dim=1))
        self.log_scale.copy_(-torch.log(flat.std(dim=1, correction=0) + self.eps))
        self.initialized.fill_(True)

    def forward(self, x: Tensor, cond: Tensor | None = None) -> tuple[Tensor, Tensor]:
        check_sequence(x, "x", "ActNorm.forward", self.channels)
        if self.training and not bool(self.initialized):
            self.initialize(x)
        y = (x + self.bias[:, None]) * torch.exp(self.log_scale)[:, None]
        logdet = (x.shape[2] * self.log_scale.sum()).expand(x.shape[0])
        return y, logdet

    def inverse(self, y: Tensor, cond: Tensor | None = None) -> Tensor:
        check_sequence(y, "y", "ActNorm.inverse", self.channels)
        return y * torch.exp(-self.log_scale)[:, None] - self.bias[:, None]
