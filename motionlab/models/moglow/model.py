"""MoGlow (Henter, Alexanderson & Beskow, 2020, §4): an autoregressive, causal, controllable flow.

Each frame's pose ``x_t`` ``(P,)`` is the image of a standard-normal ``z_t`` under an invertible map that
depends on the conditioning ``c_t`` (previous poses and controls, :mod:`.autoregression`) and on the
LSTM states inside the coupling networks, which summarise everything before ``t``::

    x_t = f^{-1}(z_t; c_t, h_{t-1}),      log p(x_t | past) = log N(f(x_t); 0, I) + log |det df/dx_t|

``f`` is ``K`` Glow steps (ActNorm, 1x1 convolution, :class:`~.coupling.LSTMAffineCoupling`) acting on
one frame at a time, so a clip's exact log-likelihood is the sum over frames, computed for all frames
in one pass. Generation runs frame by frame, carrying the LSTM states.

Two additions to the paper's model, for training on a CPU in about a minute: the first layer (data side)
subtracts a least-squares linear prediction of ``x_t`` from ``c_t`` and divides by the residual scale
(:mod:`.linear`), and the couplings read one shared linear projection of ``c_t`` (``cfg.cond_features``
numbers) instead of ``c_t`` itself (:class:`~.config.MoGlowConfig`).

Everything here is in standard units (see :mod:`.data`); :mod:`.generate` converts to and from metres.
"""

from __future__ import annotations

from typing import NamedTuple

import torch
from torch import Tensor, nn

from motionlab.models.flows.actnorm import ActNorm
from motionlab.models.flows.base import FlowSequence
from motionlab.models.flows.invconv import InvertibleConv1x1
from motionlab.models.flows.prior import StandardNormal
from motionlab.models.moglow.autoregression import (
    autoregressive_conditioning,
    autoregressive_sample,
    check_pose_control,
    history_keep_mask,
    sampling_setup,
)
from motionlab.models.moglow.config import MoGlowConfig
from motionlab.models.moglow.coupling import FrameCoupling, LSTMAffineCoupling, LSTMState
from motionlab.models.moglow.linear import LinearPredictor


class InverseStep(NamedTuple):
    """One Glow step prepared for generation: its coupling, then ActNorm and 1x1 convolution folded into
    one affine map of row vectors, ``x = v @ matrix + shift``."""

    coupling: FrameCoupling
    matrix: Tensor
    shift: Tensor


class MoGlow(nn.Module):
    """The MoGlow model of :class:`MoGlowConfig` (see the module notes)."""

    def __init__(self, cfg: MoGlowConfig) -> None:
        super().__init__()
        self.cfg = cfg
        layers: list[nn.Module] = []
        for _ in range(cfg.steps):
            layers += [ActNorm(cfg.pose_dim), InvertibleConv1x1(cfg.pose_dim),
                       LSTMAffineCoupling(cfg.pose_dim, cfg.cond_features, cfg.hidden)]
        self.cond_encoder = nn.Linear(cfg.cond_dim, cfg.cond_features)
        self.linear = LinearPredictor(cfg.pose_dim, cfg.cond_dim)
        self.flow = FlowSequence(layers)
        self.prior = StandardNormal()

    def _check(self, pose: Tensor, control: Tensor, where: str) -> None:
        check_pose_control(pose, control, self.cfg.pose_dim, self.cfg.control_dim, self.cfg.history + 1, where)
        if control.shape[1] != pose.shape[1]:
            raise ValueError(f"{where}: pose and control must have the same frames, got {pose.shape[1]} and "
                             f"{control.shape[1]}")

    def initialize(self, pose: Tensor, control: Tensor, seed: int = 0) -> float:
        """Fit the linear predictor (:mod:`.linear`) to training windows; returns its RMS residual."""
        return self.linear.fit(pose, control, self.cfg.history, self.cfg.dropout, seed)

    def latents(self, pose: Tensor, control: Tensor, generator: torch.Generator | None = None) -> tuple[Tensor, Tensor]:
        """The flow's latents ``z`` ``(B, T - tau, P)`` of frames ``tau .. T-1`` and the log-determinant ``(B,)``.

        Args:
            pose: ``(B, T, P)``; frames ``0 .. tau-1`` only serve as history.
            control: ``(B, T, C)``.
            generator: draws the history dropout flags (probability ``cfg.dropout`` per frame and lag);
                ``None`` uses torch's global generator, which the training loop seeds.
        """
        self._check(pose, control, "MoGlow")
        batch, frames, _ = pose.shape
        keep = None
        if self.cfg.dropout > 0:
            keep = history_keep_mask(batch, frames - self.cfg.history, self.cfg.history, self.cfg.dropout, generator)
        cond = autoregressive_conditioning(pose, control, self.cfg.history, keep).transpose(1, 2)
        u, linear_logdet = self.linear(pose[:, self.cfg.history:].transpose(1, 2), cond)
        z, logdet = self.flow(u, self.cond_encoder(cond.transpose(1, 2)).transpose(1, 2))
        return z.transpose(1, 2), logdet + linear_logdet

    def forward(self, pose: Tensor, control: Tensor, generator: torch.Generator | None = None) -> Tensor:
        """Log-likelihood ``(B,)`` (nats) of frames ``tau .. T-1`` of ``pose`` ``(B, T, P)`` given ``control``
        ``(B, T, C)`` (see :meth:`latents`)."""
        z, logdet = self.latents(pose, control, generator)
        return self.prior.log_prob(z) + logdet

    def inverse_steps(self) -> list[InverseStep]:
        """The Glow steps in inverse order, each with its ActNorm and 1x1 convolution folded into one map."""
        steps = []
        layers = list(self.flow.layers)
        for k in reversed(range(self.cfg.steps)):
            actnorm, conv, coupling = layers[3 * k:3 * k + 3]
            matrix = conv.inverse_weight().T * torch.exp(-actnorm.log_scale)[None, :]
            steps.append(InverseStep(coupling.frame_inverse(), matrix.detach(), -actnorm.bias.detach()))
        return steps

    @torch.no_grad()
    def sample(self, control: Tensor, seed_pose: Tensor, temperature: float = 1.0,
               generator: torch.Generator | None = None) -> Tensor:
        """Generate poses ``(B, N, P)`` frame by frame.

        Args:
            control: ``(B, tau + N, C)``: the seed frames' controls, then those of the frames to generate.
            seed_pose: ``(B, tau, P)``, the poses that start the history.
            temperature: the prior's temperature (0 gives the model's mode-seeking path, 1 its distribution).
            generator: draws the history dropout flags of all frames, then their latents.
        """
        keep, latents = sampling_setup(self.cfg, control, seed_pose, temperature, generator, "MoGlow.sample")
        steps = self.inverse_steps()
        batch = control.shape[0]
        # the conditioning encoder and the linear predictor read the same vector: one matrix product for both
        weight = torch.cat([self.cond_encoder.weight, self.linear.weight]).detach().T
        bias = torch.cat([self.cond_encoder.bias, self.linear.bias]).detach()
        linear_scale = torch.exp(self.linear.log_scale.detach())
        features = self.cfg.cond_features

        def step(t: int, cond: Tensor, state: list[LSTMState]) -> tuple[Tensor, list[LSTMState]]:
            both = torch.addmm(bias, cond, weight)
            encoded, mean = both[:, :features], both[:, features:]
            x, new_state = latents[:, t], []
            for (coupling, matrix, shift), layer_state in zip(steps, state):
                x, layer_state = coupling.inverse(x, encoded, layer_state)
                x = torch.addmm(shift, x, matrix)
                new_state.append(layer_state)
            return mean.addcmul_(x, linear_scale), new_state

        initial = [s.coupling.zero_state(batch, control) for s in steps]
        return autoregressive_sample(step, control, seed_pose, initial, keep)
