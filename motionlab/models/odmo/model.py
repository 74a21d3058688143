r"""ODMO: the LMP encoder, the trajectory generator and the motion generator, and the joint objective (eq. 5).

A clip ``x`` (local movement profile and root trajectory, see :mod:`.data`, standardised per channel) of
action ``c`` is encoded to ``q(z | x) = N(μ, s²)``; a code ``z = μ + s ε``, the class and the end point
``r_e`` of ``x`` give the trajectory ``τ̂``, and ``τ̂``, ``z`` and ``c`` give the motion ``x̂``. With ``E(a,
b)`` the squared error averaged over channels and summed over frames, the joint objective is

.. math::
    L = \underbrace{E(\hat x, x)}_{L_{motion}}
        + \underbrace{E(\hat\tau, \tau)}_{L_{traj}}
        + \underbrace{E(\hat x_{traj}, \hat\tau)}_{L_{cons}}
        + \lambda_c \underbrace{L_c}_{\text{eq. 1}} + \lambda_p\, L_{prior}

where ``τ`` is the real trajectory and ``x̂_traj`` the trajectory channels of the generated motion;
``L_c + L_prior`` is the embedding loss ``L_es`` (:mod:`.contrastive`). The ablations switch terms off
through the config (:data:`~motionlab.models.odmo.config.VARIANTS`); every term is still logged.
"""

from __future__ import annotations

from typing import NamedTuple

import torch
from torch import Tensor, nn

from motionlab.data.datasets import Standardizer
from motionlab.data.representations import check_tensor
from motionlab.models.gaussian import reparameterize
from motionlab.models.odmo.config import ODMOConfig
from motionlab.models.odmo.contrastive import balanced_pairs, contrastive_loss, prior_term
from motionlab.models.odmo.encoder import LMPEncoder
from motionlab.models.odmo.generator import MotionGenerator
from motionlab.models.odmo.trajectory import TrajectoryGenerator


class ODMOOutput(NamedTuple):
    """What one pass through ODMO gives: ``mu``, ``logvar``, ``code`` ``(B, D)``; the standardised
    ``trajectory`` ``(B, T, 3)`` and ``motion`` ``(B, T, F)``."""

    mu: Tensor
    logvar: Tensor
    code: Tensor
    trajectory: Tensor
    motion: Tensor


class ODMO(nn.Module):
    """The three networks of ODMO, built from an :class:`~motionlab.models.odmo.config.ODMOConfig`.

    The networks work on standardised features: ``standardizer`` (fitted on the training clips with
    :meth:`fit_standardizer` before training, saved with the weights) maps metres to zero mean and unit
    variance per channel, so every joint and the root's height count in the losses, not just the long
    horizontal paths of the runs. The trajectory generator accumulates velocities in units of each
    trajectory channel's standard deviation, from the standardised origin. :meth:`encode` takes and
    :meth:`generate` returns metres.
    """

    def __init__(self, cfg: ODMOConfig) -> None:
        super().__init__()
        self.cfg = cfg
        self.standardizer = Standardizer(cfg.feature_dim)
        self.encoder = LMPEncoder(cfg)
        self.trajectory_generator = TrajectoryGenerator(cfg)
        self.motion_generator = MotionGenerator(cfg)

    def fit_standardizer(self, features: Tensor) -> ODMO:
        """Fit the standardiser on training clips ``(N, T, F)`` in metres; returns self."""
        self._check_features(features, "ODMO.fit_standardizer")
        self.standardizer.fit(features)
        return self

    def _check_features(self, features: Tensor, func: str) -> None:
        cfg = self.cfg
        check_tensor(features, "features", func, (cfg.n_frames, cfg.feature_dim), min_leading=1)
        if features.dim() != 3:
            raise ValueError(
                f"{func}: features must be (B, {cfg.n_frames}, {cfg.feature_dim}), got "
                f"{tuple(features.shape)}"
            )

    def encode(self, features: Tensor) -> tuple[Tensor, Tensor]:
        """``μ`` and ``log s²`` ``(B, D)`` of clips ``(B, T, F)`` in metres (only the local movement profile
        is read)."""
        self._check_features(features, "ODMO.encode")
        return self._encode(self.standardizer.transform(features))

    def _encode(self, standardized: Tensor) -> tuple[Tensor, Tensor]:
        return self.encoder(standardized[..., : self.cfg.lmp_dim])

    def decode(
        self,
        code: Tensor,
        action: Tensor,
        end_point: Tensor,
        target: Tensor | None = None,
        teacher_forcing: float = 0.0,
    ) -> tuple[Tensor, Tensor]:
        """Standardised trajectory ``(B, T, 3)`` and motion ``(B, T, F)`` from codes ``(B, D)``, actions
        ``(B,)`` and end points ``(B, 3)`` in metres; ``target`` is the standardised clip for teacher
        forcing."""
        check_tensor(code, "code", "ODMO.generate", (self.cfg.code_dim,), min_leading=1)
        check_tensor(end_point, "end_point", "ODMO.generate", (3,), min_leading=1)
        mean, std = self.standardizer.mean[-3:].to(code), self.standardizer.std[-3:].to(code)
        steps = self.trajectory_generator(code, action, (end_point - mean) / std)
        trajectory = steps - mean / std
        motion = self.motion_generator(trajectory, code, action, target, teacher_forcing)
        return trajectory, motion

    def forward(self, features: Tensor, action: Tensor, teacher_forcing: float = 0.0) -> ODMOOutput:
        """Encode clips ``(B, T, F)`` (metres) of actions ``(B,)``, draw their codes and reconstruct them."""
        self._check_features(features, "ODMO.forward")
        standardized = self.standardizer.transform(features)
        mu, logvar = self._encode(standardized)
        code = reparameterize(mu, logvar)
        trajectory, motion = self.decode(code, action, features[:, -1, -3:], standardized, teacher_forcing)
        return ODMOOutput(mu, logvar, code, trajectory, motion)

    @torch.no_grad()
    def generate(self, code: Tensor, action: Tensor, end_point: Tensor) -> tuple[Tensor, Tensor]:
        """Motion features ``(B, T, F)`` and the trajectory generator's root trajectory ``(B, T, 3)``, both in
        metres, for codes ``(B, D)``, actions ``(B,)`` and end points ``(B, 3)``."""
        trajectory, motion = self.decode(code, action, end_point)
        std = self.standardizer.std[-3:].to(code)
        return self.standardizer.inverse(motion), trajectory * std + self.standardizer.mean[-3:].to(code)


def sequence_error(prediction: Tensor, target: Tensor) -> Tensor:
    """``E(a, b)`` of each clip ``(B,)``: squared error averaged over channels, summed over frames ``(B, T,
    C)``."""
    if prediction.shape != target.shape or prediction.dim() != 3:
        raise ValueError(
            f"sequence_error: prediction and target must both be (B, T, C), got "
            f"{tuple(prediction.shape)} and {tuple(target.shape)}"
        )
    return (prediction - target).pow(2).mean(dim=-1).sum(dim=-1)


def joint_objective(
    model: ODMO, batch: tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    """Eq. 5 on one class-balanced batch ``(features (B, T, F), action (B,))`` for the training loop.

    ``coeffs["teacher_forcing"]`` is the decoder's teacher-forcing probability at this step. Returns the
    total as ``"loss"`` and every term (batch means), switched on or not.
    """
    features, action = batch
    cfg = model.cfg
    out = model(features, action, teacher_forcing=coeffs["teacher_forcing"])
    target = model.standardizer.transform(features)
    first, second, same = balanced_pairs(action)
    terms = {
        "motion": sequence_error(out.motion, target).mean(),
        "trajectory": sequence_error(out.trajectory, target[..., -3:]).mean(),
        "consistency": sequence_error(out.motion[..., -3:], out.trajectory).mean(),
        "contrastive": contrastive_loss(
            out.mu[first], out.mu[second], same, cfg.margin, cfg.same_class_slack
        ).mean(),
        "prior": prior_term(out.mu, out.logvar, cfg.prior_variance, cfg.prior_target).mean(),
    }
    total = terms["motion"] + cfg.prior_weight * terms["prior"]
    if cfg.use_trajectory_loss:
        total = total + terms["trajectory"]
    if cfg.use_consistency:
        total = total + terms["consistency"]
    if cfg.use_contrastive:
        total = total + cfg.contrastive_weight * terms["contrastive"]
    return {"loss": total, **terms}
