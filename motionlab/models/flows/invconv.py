"""The invertible 1x1 convolution (Glow), LU-parameterised.

At every time step the channels are mixed by one learned matrix, ``y_t = W x_t``. Written as
``W = P L (U + diag(s))`` with a fixed permutation ``P``, a unit lower-triangular ``L``, a strictly upper
triangular ``U`` and ``s = sign * exp(log_s)``, the determinant is the product of the diagonal, so
``log |det W| = sum(log_s)`` costs nothing, and ``W`` stays invertible whatever values the
parameters take. ``W`` starts as a random rotation (orthogonal, determinant +-1). Inverting it is the one
step where float32 round-off grows with depth, so the inverse matrix is computed in float64.
"""

from __future__ import annotations

import numbers

import torch
from torch import Tensor, nn

from motionlab.models.flows.base import FlowLayer, check_sequence
from motionlab.validation import check_scalar


def random_rotation(channels: int) -> Tensor:
    """A random orthogonal matrix ``(channels, channels)`` in float64 from torch's global generator.

    The QR decomposition of a Gaussian matrix, with the signs fixed so that the result is uniformly
    distributed over the orthogonal group (Haar measure).
    """
    gaussian = torch.randn(channels, channels, dtype=torch.float64)
    q, r = torch.linalg.qr(gaussian)
    return q * torch.sign(torch.diagonal(r))[None, :]


class InvertibleConv1x1(FlowLayer):
    """``y_t = W x_t`` for every time step, ``W = P L (U + diag(sign * exp(log_s)))``.

    Args:
        channels: number of channels ``C``; the initial random rotation comes from torch's global generator
            (seed it, e.g. with :func:`motionlab.config.setup`, for reproducible models).

    Without autograd (``torch.no_grad``/``inference_mode``, e.g. while sampling) ``W`` and its float64
    inverse are computed once and reused until a parameter changes (tracked by the parameters' version
    counters, which every in-place update such as an optimiser step or ``load_state_dict`` increments, and
    by their storage, which ``.to()`` replaces).
    """

    permutation: Tensor
    sign_s: Tensor
    lower_mask: Tensor
    eye: Tensor

    def __init__(self, channels: int) -> None:
        super().__init__()
        check_scalar(channels, "channels", "InvertibleConv1x1", kind=numbers.Integral, minimum=1)
        self.channels = channels
        p, lower, upper = torch.linalg.lu(random_rotation(channels))
        s = torch.diagonal(upper)
        self.register_buffer("permutation", p.float())
        self.register_buffer("sign_s", torch.sign(s).float())
        self.register_buffer("lower_mask", torch.tril(torch.ones(channels, channels), diagonal=-1))
        self.register_buffer("eye", torch.eye(channels))
        self.lower = nn.Parameter(torch.tril(lower, diagonal=-1).float())
        self.upper = nn.Parameter(torch.triu(upper, diagonal=1).float())
        self.log_s = nn.Parameter(torch.log(torch.abs(s)).float())
        self._cache: tuple[tuple[int, ...], Tensor, Tensor] | None = None

    def extra_repr(self) -> str:
        return f"channels={self.channels}"

    def weight(self, dtype: torch.dtype | None = None) -> Tensor:
        """``W`` ``(C, C)`` built from the LU factors (in ``dtype``, default the parameters')."""
        dtype = dtype or self.log_s.dtype
        lower = self.lower.to(dtype) * self.lower_mask.to(dtype) + self.eye.to(dtype)
        upper = self.upper.to(dtype) * self.lower_mask.T.to(dtype)
        diagonal = torch.diag(self.sign_s.to(dtype) * torch.exp(self.log_s.to(dtype)))
        return self.permutation.to(dtype) @ lower @ (upper + diagonal)

    def inverse_weight(self) -> Tensor:
        """``W^{-1}`` ``(C, C)``, computed in float64 and returned in the parameters' dtype."""
        return torch.linalg.inv(self.weight(torch.float64)).to(self.log_s.dtype)

    def matrices(self) -> tuple[Tensor, Tensor | None]:
        """``(W, W^{-1})``, both ``(C, C)``: cached while the parameters are unchanged when autograd is off
        (the inverse costs an LU solve in float64); with autograd on, ``(W, None)`` freshly built."""
        if torch.is_grad_enabled():
            self._cache = None
            return self.weight(), None
        key = tuple(p._version for p in (self.lower, self.upper, self.log_s)) + tuple(
            p.data_ptr() for p in (self.lower, self.upper, self.log_s)
        )
        if self._cache is None or self._cache[0] != key:
            self._cache = (key, self.weight().detach(), self.inverse_weight().detach())
        return self._cache[1], self._cache[2]

    def forward(self, x: Tensor, cond: Tensor | None = None) -> tuple[Tensor, Tensor]:
        check_sequence(x, "x", "InvertibleConv1x1.forward", self.channels)
        weight, _ = self.matrices()
        y = torch.einsum("ij,bjt->bit", weight.to(x.dtype), x)
        logdet = (x.shape[2] * self.log_s.sum()).to(x.dtype).expand(x.shape[0])
        return y, logdet

    def inverse(self, y: Tensor, cond: Tensor | None = None) -> Tensor:
        check_sequence(y, "y", "InvertibleConv1x1.inverse", self.channels)
        _, inverse = self.matrices()
        if inverse is None:
            inverse = self.inverse_weight()
        return torch.einsum("ij,bjt->bit", inverse.to(y.dtype), y)
