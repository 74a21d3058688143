"""The Gaussian autoregressive baseline: an LSTM that predicts a mean and a diagonal variance per frame.

It reads exactly MoGlow's conditioning ``c_t`` (:mod:`.conditioning`) and outputs
``x_t ~ N(mu_t, diag(sigma_t**2))``. It is the natural "deterministic network plus noise" model that
MoGlow is compared with: the same inputs and memory, but a unimodal, axis-aligned output distribution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import Tensor, nn

from motionlab.models.flows.coupling import zero_init
from motionlab.models.moglow.conditioning import (
    HistoryConfig,
    autoregressive_conditioning,
    check_pose_control,
    history_keep_mask,
)
from motionlab.models.moglow.linear import LinearPredictor
from motionlab.models.moglow.sampling import AutoregressiveModel, autoregressive_sample
from motionlab.validation import integer, real

#: Bounds on the predicted log standard deviation (standard units), to keep the likelihood finite.
LOG_STD_RANGE = (-15.0, 5.0)


@dataclass(frozen=True)
class GaussianARConfig(HistoryConfig):
    """The baseline: an LSTM over MoGlow's conditioning that outputs a diagonal Gaussian for the next pose.

    Attributes: the conditioning of :class:`~.conditioning.HistoryConfig`; ``hidden`` is the LSTM width,
    ``layers`` its depth, ``dropout`` the history dropout (as in :class:`~.model.MoGlowConfig`).
    """

    hidden: int = integer(256, minimum=1)
    layers: int = integer(1, minimum=1)
    dropout: float = real(0.0, minimum=0, below=1)


class GaussianAR(AutoregressiveModel):
    """``x_t ~ N(mu(h_t), diag(sigma(h_t)**2))`` with ``h_t = LSTM(c_1 .. c_t)``."""

    def __init__(self, cfg: GaussianARConfig) -> None:
        super().__init__()
        self.cfg = cfg
        self.lstm = nn.LSTM(cfg.cond_dim, cfg.hidden, num_layers=cfg.layers, batch_first=True)
        self.out = zero_init(nn.Linear(cfg.hidden, 2 * cfg.pose_dim))
        self.linear = LinearPredictor(cfg.pose_dim, cfg.cond_dim)

    def _distribution(self, cond: Tensor, hidden: Tensor) -> tuple[Tensor, Tensor]:
        """Mean and log-std ``(..., P)``: the linear prediction and its residual scale, corrected by the LSTM.

        The mean's correction is in units of the linear fit's residual scale (like MoGlow's residual
        ``u_t``), so the first optimiser steps do not throw the mean off by many residual widths.
        """
        correction, raw = self.out(hidden).chunk(2, dim=-1)
        scale = torch.exp(self.linear.log_scale)
        return self.linear.mean(cond) + scale * correction, (self.linear.log_scale + raw).clamp(
            *LOG_STD_RANGE
        )

    def initialize(self, pose: Tensor, control: Tensor, seed: int = 0, solve: bool = True) -> float:
        """Fit the linear predictor (:mod:`.linear`) to training windows; returns its RMS residual (kept as
        ``self.linear.fit_rms``). ``solve=False``: measure the residual of the predictor as loaded."""
        return self.linear.fit(
            pose, control, self.cfg.history, self.cfg.dropout, seed, rescale=True, solve=solve
        )

    def forward(self, pose: Tensor, control: Tensor, generator: torch.Generator | None = None) -> Tensor:
        """Log-likelihood ``(B,)`` (nats) of frames ``H .. T-1``, as :meth:`MoGlow.forward` (history dropout
        flags drawn from ``generator`` in training mode only)."""
        cfg = self.cfg
        check_pose_control(
            pose, control, cfg.pose_dim, cfg.control_dim, cfg.history + 1, "GaussianAR.forward", True
        )
        batch, frames, _ = pose.shape
        keep = None
        if self.training and self.cfg.dropout > 0:
            keep = history_keep_mask(
                batch, frames - self.cfg.history, self.cfg.history, self.cfg.dropout, generator, rescale=True
            )
        cond = autoregressive_conditioning(pose, control, self.cfg.history, keep)
        hidden, _ = self.lstm(cond)
        mean, log_std = self._distribution(cond, hidden)
        target = pose[:, self.cfg.history :]
        per_value = (
            -0.5 * ((target - mean) * torch.exp(-log_std)).pow(2) - log_std - 0.5 * math.log(2 * math.pi)
        )
        return per_value.sum(dim=(1, 2))

    def draw(self, control: Tensor, seed_pose: Tensor, noise: Tensor) -> Tensor:
        """Poses ``(B, N, P)`` generated frame by frame, each the predicted mean plus its standard deviation
        times that frame's ``noise``."""

        def step(
            t: int, cond: Tensor, state: tuple[Tensor, Tensor] | None
        ) -> tuple[Tensor, tuple[Tensor, Tensor]]:
            hidden, state = self.lstm(cond[:, None], state)
            mean, log_std = self._distribution(cond, hidden[:, 0])
            return mean + torch.exp(log_std) * noise[:, t], state

        return autoregressive_sample(step, control, seed_pose)
