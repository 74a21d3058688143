"""Glow steps, squeezing along time, and the multi-scale, fixed-length conditional Glow of MoGlow §3.4.

**Glow step** (Kingma & Dhariwal): ActNorm -> invertible 1x1 convolution -> affine coupling.

**Squeeze along time**: ``(batch, C, T) -> (batch, 2C, T/2)``; each pair of neighbouring frames becomes
one frame with twice the channels (channel ``2c`` holds channel ``c`` of the even frame, ``2c + 1`` of the
odd one). A pure reshuffle: log-determinant 0. After it, a coupling's kernel sees twice as far in time.

**Multi-scale** (RealNVP): a level squeezes, runs ``K`` Glow steps, then *splits*: half of its channels are
final latents (they go straight to the prior), the other half continue into the next level, which
squeezes again. Coarse levels thus model slow structure over long spans on a fraction of the numbers. The
conditioning sequence (for example the control signal) is squeezed alongside, so every level sees it at
its own time resolution. Here the factored-out latents are put back where they came from, so the whole
flow maps ``(batch, C, T)`` to a latent of the same shape and is itself a :class:`FlowLayer`.

For a fixed clip length ``T`` divisible by ``2**levels`` this is the fixed-length, control-conditioned
motion model of MoGlow's §3.4: one flow over a whole clip, with exact log-likelihood.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from motionlab.models.flows.actnorm import ActNorm
from motionlab.models.flows.base import FlowLayer, FlowSequence, check_cond, check_sequence
from motionlab.models.flows.coupling import AffineCoupling
from motionlab.models.flows.invconv import InvertibleConv1x1
from motionlab.models.flows.prior import StandardNormal, check_temperature
from motionlab.validation import Checked, integer


def squeeze_time(x: Tensor) -> Tensor:
    """``(batch, C, T) -> (batch, 2C, T/2)``: frames ``2t, 2t+1`` of channel ``c`` become channels ``2c,
    2c+1``."""
    batch, channels, time = x.shape
    if time % 2:
        raise ValueError(f"squeeze_time: the time axis must have even length, got shape {tuple(x.shape)}")
    return x.reshape(batch, channels, time // 2, 2).transpose(2, 3).reshape(batch, 2 * channels, time // 2)


def unsqueeze_time(x: Tensor) -> Tensor:
    """Undo :func:`squeeze_time`: ``(batch, 2C, T/2) -> (batch, C, T)``."""
    batch, channels, time = x.shape
    if channels % 2:
        raise ValueError(
            f"unsqueeze_time: the channel axis must have even length, got shape {tuple(x.shape)}"
        )
    return x.reshape(batch, channels // 2, 2, time).transpose(2, 3).reshape(batch, channels // 2, 2 * time)


class Squeeze(FlowLayer):
    """:func:`squeeze_time` as a flow layer (log-determinant 0)."""

    def forward(self, x: Tensor, cond: Tensor | None = None) -> tuple[Tensor, Tensor]:
        check_sequence(x, "x", "Squeeze.forward")
        return squeeze_time(x), x.new_zeros(x.shape[0])

    def inverse(self, y: Tensor, cond: Tensor | None = None) -> Tensor:
        check_sequence(y, "y", "Squeeze.inverse")
        return unsqueeze_time(y)


class GlowStep(FlowSequence):
    """ActNorm -> InvertibleConv1x1 -> AffineCoupling on ``channels`` channels.

    Args:
        channels: channels ``C >= 2``.
        cond_channels, hidden, kernel_size: passed to :class:`AffineCoupling`.
    """

    def __init__(self, channels: int, cond_channels: int = 0, hidden: int = 64, kernel_size: int = 3) -> None:
        super().__init__(
            [
                ActNorm(channels),
                InvertibleConv1x1(channels),
                AffineCoupling(channels, cond_channels, hidden, kernel_size),
            ]
        )


class GlowLevel(FlowLayer):
    """One scale: squeeze along time, ``n_steps`` Glow steps, then split off half the channels.

    Args:
        channels: channels ``C`` of the input ``(batch, C, T)``; the steps work on ``2C``.
        cond_channels: channels of the conditioning input at this level's input resolution (0: none).
        n_steps, hidden, kernel_size: the Glow steps.
        inner: the next (coarser) level, applied to the kept ``C`` channels at time ``T/2`` with the squeezed
            conditioning; ``None`` for the last level, which keeps all channels.
    """

    def __init__(
        self,
        channels: int,
        cond_channels: int,
        n_steps: int,
        hidden: int,
        kernel_size: int,
        inner: GlowLevel | None = None,
    ) -> None:
        super().__init__()
        if inner is not None and (inner.channels != channels or inner.cond_channels != 2 * cond_channels):
            raise ValueError(
                f"GlowLevel: inner level must take {channels} channels and {2 * cond_channels} "
                f"cond channels, got {inner.channels} and {inner.cond_channels}"
            )
        self.channels, self.cond_channels = channels, cond_channels
        self.steps = FlowSequence(
            GlowStep(2 * channels, 2 * cond_channels, hidden, kernel_size) for _ in range(n_steps)
        )
        self.inner = inner

    def forward(self, x: Tensor, cond: Tensor | None = None) -> tuple[Tensor, Tensor]:
        check_sequence(x, "x", "GlowLevel.forward", self.channels)
        cond = check_cond(cond, x, self.cond_channels, "GlowLevel.forward")
        cond = None if cond is None else squeeze_time(cond)
        h, logdet = self.steps(squeeze_time(x), cond)
        if self.inner is not None:
            kept, inner_logdet = self.inner(h[:, self.channels :], cond)
            h = torch.cat([h[:, : self.channels], kept], dim=1)
            logdet = logdet + inner_logdet
        return unsqueeze_time(h), logdet

    def inverse(self, y: Tensor, cond: Tensor | None = None) -> Tensor:
        check_sequence(y, "y", "GlowLevel.inverse", self.channels)
        cond = check_cond(cond, y, self.cond_channels, "GlowLevel.inverse")
        cond = None if cond is None else squeeze_time(cond)
        h = squeeze_time(y)
        if self.inner is not None:
            h = torch.cat([h[:, : self.channels], self.inner.inverse(h[:, self.channels :], cond)], dim=1)
        return unsqueeze_time(self.steps.inverse(h, cond))


@dataclass(frozen=True)
class GlowConfig(Checked):
    """A multi-scale conditional Glow over fixed-length sequences.

    Attributes:
        channels: features per frame ``C`` (even, since the last level's coupling splits ``2C``).
        length: frames per sequence ``T``, divisible by ``2**levels``.
        cond_channels: conditioning features per frame (0: unconditional).
        levels: number of scales.
        steps_per_level: Glow steps ``K`` per scale.
        hidden: coupling network width.
        kernel_size: odd temporal kernel of the coupling networks.
    """

    channels: int = integer(minimum=1)
    length: int = integer(minimum=1)
    cond_channels: int = integer(0, minimum=0)
    levels: int = integer(2, minimum=1)
    steps_per_level: int = integer(4, minimum=1)
    hidden: int = integer(64, minimum=1)
    kernel_size: int = integer(3, minimum=1)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.length % 2**self.levels:
            raise ValueError(
                f"GlowConfig: length {self.length} must be divisible by 2**levels = {2**self.levels}"
            )
        if self.kernel_size % 2 == 0:
            raise ValueError(f"GlowConfig.kernel_size must be odd, got {self.kernel_size}")


class Glow(FlowLayer):
    """The multi-scale conditional Glow of :class:`GlowConfig` with a standard-normal prior.

    ``forward(x, cond) -> (z, logdet)`` and ``inverse(z, cond) -> x`` map sequences ``(batch, C, T)`` to
    latents of the same shape; :meth:`log_prob` and :meth:`sample` add the prior.
    """

    def __init__(self, cfg: GlowConfig) -> None:
        super().__init__()
        self.cfg = cfg
        level: GlowLevel | None = None
        for depth in reversed(range(cfg.levels)):
            level = GlowLevel(
                cfg.channels,
                cfg.cond_channels * 2**depth,
                cfg.steps_per_level,
                cfg.hidden,
                cfg.kernel_size,
                inner=level,
            )
        self.flow = level
        self.prior = StandardNormal()

    def _check(self, x: Tensor, cond: Tensor | None, where: str) -> Tensor | None:
        check_sequence(x, "x", where, self.cfg.channels)
        if x.shape[2] != self.cfg.length:
            raise ValueError(
                f"{where}: sequences must have {self.cfg.length} frames, got shape {tuple(x.shape)}"
            )
        return check_cond(cond, x, self.cfg.cond_channels, where)

    def forward(self, x: Tensor, cond: Tensor | None = None) -> tuple[Tensor, Tensor]:
        cond = self._check(x, cond, "Glow.forward")
        return self.flow(x, cond)

    def inverse(self, y: Tensor, cond: Tensor | None = None) -> Tensor:
        cond = self._check(y, cond, "Glow.inverse")
        return self.flow.inverse(y, cond)

    def log_prob(self, x: Tensor, cond: Tensor | None = None) -> Tensor:
        """Exact ``log p(x | cond)`` per sequence ``(batch,)``, in nats."""
        z, logdet = self(x, cond)
        return self.prior.log_prob(z) + logdet

    @torch.no_grad()
    def sample(
        self,
        cond: Tensor | None = None,
        n: int | None = None,
        temperature: float = 1.0,
        generator: torch.Generator | None = None,
    ) -> Tensor:
        """Sequences ``(batch, C, T)`` drawn at ``temperature``: one per row of ``cond``, or ``n`` without
        it."""
        temperature = check_temperature(temperature, "Glow.sample")
        if cond is not None:
            check_sequence(cond, "cond", "Glow.sample", self.cfg.cond_channels)
            n = cond.shape[0]
        if n is None or n < 1:
            raise ValueError(
                f"Glow.sample: give cond (batch, {self.cfg.cond_channels}, {self.cfg.length}) or n >= 1"
            )
        dtype = next(self.parameters()).dtype
        z = self.prior.sample((n, self.cfg.channels, self.cfg.length), temperature, generator, dtype)
        return self.inverse(z, cond)
