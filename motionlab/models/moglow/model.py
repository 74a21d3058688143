"""MoGlow (Henter, Alexanderson & Beskow, arXiv:1905.06598, 2019, §4): an autoregressive, causal,
controllable flow.

Each frame's pose ``x_t`` ``(P,)`` is the image of a standard-normal ``z_t`` under an invertible map that
depends on the conditioning ``c_t`` (previous poses and controls, :mod:`.conditioning`) and on the
LSTM states inside the coupling networks, which summarise everything before ``t``::

    x_t = f^{-1}(z_t; c_t, h_{t-1}),      log p(x_t | past) = log N(f(x_t); 0, I) + log |det df/dx_t|

``f`` is ``K`` Glow steps (ActNorm, 1x1 convolution, :class:`~.coupling.LSTMAffineCoupling`) acting on
one frame at a time, so a clip's exact log-likelihood is the sum over frames, computed for all frames
in one pass. Generation runs frame by frame, carrying the LSTM states (:mod:`.sampling`).

Two additions to the paper's model, for training on a CPU in about a minute: the first layer (data side)
subtracts a least-squares linear prediction of ``x_t`` from ``c_t`` and divides by the residual scale
(:mod:`.linear`), and the couplings read one shared linear projection of ``c_t`` (``cfg.cond_features``
numbers) instead of ``c_t`` itself (:class:`MoGlowConfig`).

Everything here is in standard units (see :mod:`.data`); :mod:`.sampling` converts to and from metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor, nn

from motionlab.models.flows.actnorm import ActNorm
from motionlab.models.flows.base import FlowSequence
from motionlab.models.flows.invconv import InvertibleConv1x1
from motionlab.models.flows.prior import StandardNormal
from motionlab.models.moglow.conditioning import (
    HistoryConfig,
    autoregressive_conditioning,
    check_pose_control,
    history_keep_mask,
)
from motionlab.models.moglow.coupling import LSTMAffineCoupling
from motionlab.models.moglow.data import POSE_DIM
from motionlab.models.moglow.linear import LinearPredictor
from motionlab.models.moglow.sampling import (
    AutoregressiveModel,
    GenerationPlan,
    InverseStep,
    check_generated,
    sample_frames,
)
from motionlab.validation import flag, integer, real


@dataclass(frozen=True)
class MoGlowConfig(HistoryConfig):
    """MoGlow (§4.2 of the 2019 preprint, eqs. 16-18): a next-frame Glow whose couplings are LSTMs over time.

    Attributes:
        pose_dim, control_dim, history: as in :class:`~.conditioning.HistoryConfig` (the previous poses and
            control frames fed to every coupling); a coupling splits the pose, so ``pose_dim`` is at least 2.
        steps: Glow steps ``K`` (ActNorm, 1x1 convolution, LSTM affine coupling).
        hidden: LSTM units in each coupling network.
        cond_features: size of the shared linear projection of the conditioning that every coupling reads
            (our deviation from the paper, where each coupling reads the raw conditioning: on a CPU the
            first LSTM layer's input weights dominate both training and generation time; sharing one
            projection makes them ``K`` times cheaper).
        dropout: probability of zeroing each previous pose in the conditioning, in training only (the
            paper's §5.3 and Fig. 3): in eval mode (held-out likelihood) and when generating, the model
            sees the full history.
        dropout_rescale: scale the kept previous poses by ``1 / (1 - dropout)`` in training (standard
            "inverted" dropout, the default), so that linear maps of the history see in expectation the
            full-history input of generation; ``False`` zeroes without rescaling (the authors' code).
    """

    pose_dim: int = integer(POSE_DIM, minimum=2, note="a coupling splits it")
    steps: int = integer(8, minimum=1)
    hidden: int = integer(64, minimum=1)
    cond_features: int = integer(64, minimum=1)
    dropout: float = real(0.95, minimum=0, below=1)
    dropout_rescale: bool = flag(True)


class MoGlow(AutoregressiveModel):
    """The MoGlow model of :class:`MoGlowConfig` (see the module notes)."""

    def __init__(self, cfg: MoGlowConfig) -> None:
        super().__init__()
        self.cfg = cfg
        layers: list[nn.Module] = []
        for _ in range(cfg.steps):
            layers += [
                ActNorm(cfg.pose_dim),
                InvertibleConv1x1(cfg.pose_dim),
                LSTMAffineCoupling(cfg.pose_dim, cfg.cond_features, cfg.hidden),
            ]
        self.cond_encoder = nn.Linear(cfg.cond_dim, cfg.cond_features)
        self.linear = LinearPredictor(cfg.pose_dim, cfg.cond_dim)
        self.flow = FlowSequence(layers)
        self.prior = StandardNormal()

    def initialize(self, pose: Tensor, control: Tensor, seed: int = 0, solve: bool = True) -> float:
        """Fit the linear predictor (:mod:`.linear`) to training windows; returns its RMS residual, kept as
        ``self.linear.fit_rms``. With ``solve=False`` (a model loaded from the cache) the predictor stays as
        loaded and only its residual on the windows is measured."""
        return self.linear.fit(
            pose,
            control,
            self.cfg.history,
            self.cfg.dropout,
            seed,
            rescale=self.cfg.dropout_rescale,
            solve=solve,
        )

    def latents(
        self, pose: Tensor, control: Tensor, generator: torch.Generator | None = None
    ) -> tuple[Tensor, Tensor]:
        """The flow's latents ``z`` ``(B, T - H, P)`` of frames ``H .. T-1`` and the log-determinant
        ``(B,)``.

        Args:
            pose: ``(B, T, P)``; frames ``0 .. H-1`` only serve as history.
            control: ``(B, T, C)``.
            generator: draws the history dropout flags in training mode (probability ``cfg.dropout`` per
                frame and lag); ``None`` uses torch's global generator, which the training loop seeds. In
                eval mode nothing is dropped: the latents and log-determinant are the model's, exactly.
        """
        cfg = self.cfg
        check_pose_control(pose, control, cfg.pose_dim, cfg.control_dim, cfg.history + 1, "MoGlow", True)
        batch, frames, _ = pose.shape
        keep = self.keep_mask(batch, frames - cfg.history, generator) if self.training else None
        cond = autoregressive_conditioning(pose, control, self.cfg.history, keep).transpose(1, 2)
        u, linear_logdet = self.linear(pose[:, self.cfg.history :].transpose(1, 2), cond)
        z, logdet = self.flow(u, self.cond_encoder(cond.transpose(1, 2)).transpose(1, 2))
        return z.transpose(1, 2), logdet + linear_logdet

    def keep_mask(self, batch: int, frames: int, generator: torch.Generator | None = None) -> Tensor | None:
        """The training-time history dropout: keep flags ``(batch, frames, H)`` (:func:`history_keep_mask`
        with ``cfg.dropout`` and ``cfg.dropout_rescale``), or ``None`` when nothing is dropped.

        A subclass may override it to drop the history differently (e.g. whole windows at once); it is never
        called in eval mode, nor when generating.
        """
        if self.cfg.dropout == 0:
            return None
        return history_keep_mask(
            batch, frames, self.cfg.history, self.cfg.dropout, generator, rescale=self.cfg.dropout_rescale
        )

    def forward(self, pose: Tensor, control: Tensor, generator: torch.Generator | None = None) -> Tensor:
        """Log-likelihood ``(B,)`` (nats) of frames ``H .. T-1`` of ``pose`` ``(B, T, P)`` given ``control``
        ``(B, T, C)`` (see :meth:`latents`)."""
        z, logdet = self.latents(pose, control, generator)
        return self.prior.log_prob(z) + logdet

    @torch.no_grad()
    def generation_plan(self) -> GenerationPlan:
        """The weights arranged for generating one frame at a time (:mod:`.sampling`), steps in inverse order.

        Each step's ActNorm and 1x1 convolution are folded into one matrix; the couplings' weights are split
        by what they read, and the conditioning features' parts of all couplings are stacked side by side.
        """
        cfg = self.cfg
        past = cfg.history * cfg.pose_dim
        layers = list(self.flow.layers)
        steps, feature_weights = [], []
        for k in reversed(range(cfg.steps)):
            actnorm, conv, coupling = layers[3 * k : 3 * k + 3]
            matrix = conv.matrices()[1].T * torch.exp(-actnorm.log_scale)[None, :]
            weights = coupling.frame_weights()
            steps.append(InverseStep(weights, matrix[: coupling.n_a], matrix[coupling.n_a :], -actnorm.bias))
            feature_weights += [weights.lstm_input_cond.T, weights.out_input_cond]
        weight = torch.cat([self.cond_encoder.weight, self.linear.weight]).T  # (cond_dim, F + P)
        return GenerationPlan(
            weight[:past].contiguous(),
            weight[past:].contiguous(),
            torch.cat([self.cond_encoder.bias, self.linear.bias]),
            torch.cat(feature_weights, dim=1).contiguous(),
            torch.exp(self.linear.log_scale),
            steps,
        )

    def draw(self, control: Tensor, seed_pose: Tensor, latents: Tensor) -> Tensor:
        """Poses ``(B, N, P)`` generated frame by frame with the fused loop (:func:`.sampling.sample_frames`);
        a ``ValueError`` names the first frame whose generated pose is not finite."""
        generated = sample_frames(self.generation_plan(), control, seed_pose, None, latents)
        return check_generated(generated, "MoGlow.sample")
