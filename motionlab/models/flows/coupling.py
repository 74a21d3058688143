"""The affine coupling layer (RealNVP, Glow) and the affine transform it is built on.

The channels are split into two halves ``x = (x_a, x_b)``. The first half passes unchanged and, together
with the conditioning input, drives a network that outputs a shift ``t`` and a raw scale ``r`` for the
second half::

    y_a = x_a
    y_b = (x_b + t) * sigmoid(r + offset)        t, r = NN(x_a, cond)

Because ``y_a`` does not depend on ``x_b`` the Jacobian is block triangular, so its log-determinant is
the sum of ``log sigmoid(r + offset)`` and the network itself never needs to be inverted:
``x_b = y_b / sigmoid(r + offset) - t`` with ``t, r`` recomputed from ``y_a = x_a``. The sigmoid bounds
every scale to ``(0, 1)`` (Glow's choice, with ``offset = 2`` so that it starts near ``0.88``), which keeps
training stable. The network's last layer starts at zero, so a fresh coupling is a fixed, gentle
contraction and a deep flow starts close to the identity.
"""

from __future__ import annotations

import numbers

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from motionlab.models.flows.base import FlowLayer, check_cond, check_sequence
from motionlab.validation import check_scalar

#: Glow's offset inside the sigmoid: a fresh coupling scales by sigmoid(2) = 0.88.
SCALE_OFFSET = 2.0


def affine_forward(x_b: Tensor, params: Tensor, scale_offset: float = SCALE_OFFSET) -> tuple[Tensor, Tensor]:
    """``y_b = (x_b + t) * sigmoid(r + offset)`` and its log-determinant ``(batch,)``.

    Args:
        x_b: the transformed half ``(batch, C_b, time)``.
        params: the network output ``(batch, 2 * C_b, time)``: shift ``t`` then raw scale ``r``.
    """
    shift, raw = params.chunk(2, dim=1)
    y_b = (x_b + shift) * torch.sigmoid(raw + scale_offset)
    logdet = F.logsigmoid(raw + scale_offset).sum(dim=(1, 2))
    return y_b, logdet


def affine_inverse(y_b: Tensor, params: Tensor, scale_offset: float = SCALE_OFFSET) -> Tensor:
    """Undo :func:`affine_forward`: ``x_b = y_b / sigmoid(r + offset) - t``."""
    shift, raw = params.chunk(2, dim=1)
    return y_b / torch.sigmoid(raw + scale_offset) - shift


def zero_init(layer: nn.Module) -> nn.Module:
    """Set a layer's weight and bias to zero (the last layer of a coupling network); return it."""
    nn.init.zeros_(layer.weight)
    nn.init.zeros_(layer.bias)
    return layer


class CouplingLayer(FlowLayer):
    """What every affine coupling on ``(batch, channels, time)`` shares: ``x_a``, the first ``n_a`` channels,
    passes unchanged, and ``x_b``, the rest, moves by :func:`affine_forward` with the shift and raw scale
    ``(B, 2 C_b, T)`` that the subclass's network ``_params(x_a, cond)`` reads off ``x_a`` and the
    conditioning. A subclass sets ``channels``, ``cond_channels``, ``n_a`` and ``scale_offset``."""

    channels: int
    cond_channels: int
    n_a: int
    scale_offset: float

    def _params(self, x_a: Tensor, cond: Tensor | None) -> Tensor:
        raise NotImplementedError(f"{type(self).__name__} does not define _params")

    def forward(self, x: Tensor, cond: Tensor | None = None) -> tuple[Tensor, Tensor]:
        where = f"{type(self).__name__}.forward"
        check_sequence(x, "x", where, self.channels)
        cond = check_cond(cond, x, self.cond_channels, where)
        x_a, x_b = x[:, : self.n_a], x[:, self.n_a :]
        y_b, logdet = affine_forward(x_b, self._params(x_a, cond), self.scale_offset)
        return torch.cat([x_a, y_b], dim=1), logdet

    def inverse(self, y: Tensor, cond: Tensor | None = None) -> Tensor:
        where = f"{type(self).__name__}.inverse"
        check_sequence(y, "y", where, self.channels)
        cond = check_cond(cond, y, self.cond_channels, where)
        y_a, y_b = y[:, : self.n_a], y[:, self.n_a :]
        return torch.cat([y_a, affine_inverse(y_b, self._params(y_a, cond), self.scale_offset)], dim=1)


class AffineCoupling(CouplingLayer):
    """Affine coupling with a convolutional network over time, optionally conditioned.

    Args:
        channels: channels ``C >= 2``; ``x_a`` is the first ``C // 2``, ``x_b`` the rest.
        cond_channels: channels of the conditioning sequence (0: unconditional).
        hidden: width of the network.
        kernel_size: odd temporal kernel of the first and last convolution (1 makes it a per-frame MLP).
        scale_offset: the ``offset`` inside the sigmoid.

    The network is Conv1d(k) -> ReLU -> Conv1d(1) -> ReLU -> Conv1d(k) with the last one zero-initialised;
    it reads ``x_a`` and ``cond`` stacked along channels.
    """

    def __init__(
        self,
        channels: int,
        cond_channels: int = 0,
        hidden: int = 64,
        kernel_size: int = 3,
        scale_offset: float = SCALE_OFFSET,
    ) -> None:
        super().__init__()
        where = "AffineCoupling"
        check_scalar(channels, "channels", where, kind=numbers.Integral, minimum=2)
        check_scalar(cond_channels, "cond_channels", where, kind=numbers.Integral, minimum=0)
        check_scalar(hidden, "hidden", where, kind=numbers.Integral, minimum=1)
        check_scalar(kernel_size, "kernel_size", where, kind=numbers.Integral, minimum=1)
        if kernel_size % 2 == 0:
            raise ValueError(f"{where}: kernel_size must be odd, got {kernel_size!r}")
        self.channels, self.cond_channels = channels, cond_channels
        self.n_a = channels // 2
        self.n_b = channels - self.n_a
        self.scale_offset = float(scale_offset)
        pad = kernel_size // 2
        self.net = nn.Sequential(
            nn.Conv1d(self.n_a + cond_channels, hidden, kernel_size, padding=pad),
            nn.ReLU(),
            nn.Conv1d(hidden, hidden, 1),
            nn.ReLU(),
            zero_init(nn.Conv1d(hidden, 2 * self.n_b, kernel_size, padding=pad)),
        )

    def extra_repr(self) -> str:
        return (
            f"channels={self.channels}, cond_channels={self.cond_channels}, scale_offset={self.scale_offset}"
        )

    def _params(self, x_a: Tensor, cond: Tensor | None) -> Tensor:
        return self.net(x_a if cond is None else torch.cat([x_a, cond], dim=1))
