"""Chapter 03's runs: settings per profile, training through the cache, and the measurements the chapter
reports.

Every model trains through :func:`motionlab.train.train_or_load` with the same optimiser settings; the
pose models on standardised pose vectors, the clip CVAEs on standardised 2-second MoGlow windows.

The likelihood variance of the clip CVAE is ODMO's weighting in disguise: ODMO minimises, per clip, the
squared error averaged over the D features of a frame and summed over frames, plus the KL with weight 1.
That equals the Gaussian negative log-likelihood with sigma_x^2 = D / 2 (up to a constant), which is what
:func:`clip_cvae_config` uses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from motionlab import config
from motionlab.evaluation.benchmark import sample_metrics
from motionlab.evaluation.evaluator import Evaluator, data_fingerprint
from motionlab.metrics import bone_length_error
from motionlab.metrics.intervals import Interval, repeat_metric
from motionlab.models.gaussian import active_units, kl_per_dimension, unit_activity
from motionlab.models.vae import MLPVAE, VAEConfig, elbo_loss
from motionlab.models.vae_data import POSE_FEATURES, ClipCodec
from motionlab.train import Constant, KLAnneal, TensorBatches, TrainConfig, TrainResult, train_or_load

#: Features per frame of the clip windows (MoGlow, 22 joints).
CLIP_FEATURES = 67


@dataclass(frozen=True)
class ChapterSettings:
    """The chapter's sizes and budgets for one profile (see :func:`chapter_settings`).

    Attributes:
        pose_every: take every this many frames of a clip as a pose.
        pose_latent, pose_hidden, pose_steps: the pose models' latent size, width and training steps.
        pose_obs_var: sigma_x^2 of the pose VAEs' likelihood (standardised units).
        clip_length, clip_stride: window length and hop in frames (30 fps).
        clip_latent, clip_hidden, clip_steps: the clip CVAEs' latent size, width and training steps.
        batch_size, lr: for every run.
        per_action, n_repeats: evaluation sample sets (clips per action) and how many of them.
    """

    pose_every: int
    pose_latent: int
    pose_hidden: int
    pose_steps: int
    pose_obs_var: float
    clip_length: int
    clip_stride: int
    clip_latent: int
    clip_hidden: int
    clip_steps: int
    batch_size: int
    lr: float
    per_action: int
    n_repeats: int


def chapter_settings() -> ChapterSettings:
    """The settings of the active profile (quick: every code path in seconds; full: the reported runs)."""
    return ChapterSettings(
        pose_every=config.choose(quick=20, full=10),
        pose_latent=8,
        pose_hidden=config.choose(quick=32, full=128),
        pose_steps=config.choose(quick=30, full=800),
        pose_obs_var=0.1,
        clip_length=60,
        clip_stride=15,
        clip_latent=16,
        clip_hidden=config.choose(quick=32, full=128),
        clip_steps=config.choose(quick=30, full=600),
        batch_size=64,
        lr=2e-3,
        per_action=config.choose(quick=10, full=50),
        n_repeats=config.choose(quick=3, full=10),
    )


def pose_vae_config(settings: ChapterSettings, variational: bool = True, prior_var: float = 1.0) -> VAEConfig:
    """An unconditional pose (V)AE on 64-number pose vectors; ``prior_var`` is sigma_p^2."""
    return VAEConfig(
        (POSE_FEATURES,),
        latent_dim=settings.pose_latent,
        hidden=settings.pose_hidden,
        variational=variational,
        obs_logvar=math.log(settings.pose_obs_var),
        prior_logvar=math.log(prior_var),
    )


def clip_cvae_config(settings: ChapterSettings, n_actions: int, prior_var: float = 1.0) -> VAEConfig:
    """The action-conditioned clip VAE: windows ``(clip_length, 67)``, sigma_x^2 = 67 / 2 (ODMO's
    weighting)."""
    return VAEConfig(
        (settings.clip_length, CLIP_FEATURES),
        latent_dim=settings.clip_latent,
        hidden=settings.clip_hidden,
        n_classes=n_actions,
        obs_logvar=math.log(CLIP_FEATURES / 2),
        prior_logvar=math.log(prior_var),
    )


def kl_weight(steps: int, anneal: bool) -> KLAnneal | Constant:
    """The KL weight beta: a linear ramp from 0 to 1 over the first half of ``steps``, or 1 throughout."""
    return KLAnneal(max_value=1.0, warmup=0, anneal=max(1, steps // 2)) if anneal else Constant(1.0)


def train_vae(
    name: str,
    cfg: VAEConfig,
    x: Tensor,
    label: Tensor | None,
    steps: int,
    anneal: bool,
    settings: ChapterSettings,
    seed: int = 0,
    progress: bool | None = None,
) -> tuple[MLPVAE, TrainResult]:
    """Build an :class:`MLPVAE` from ``cfg`` (initialised from ``seed``) and train or load it.

    Args:
        x: standardised training inputs ``(N, *cfg.input_shape)``; label: ``(N,)`` classes for a CVAE.
        steps: optimiser steps; anneal: ramp the KL weight (see :func:`kl_weight`) or keep it at 1.
        progress: show a progress bar (default: in the full profile only).
    """
    torch.manual_seed(seed)
    model = MLPVAE(cfg)
    data = TensorBatches((x,) if label is None else (x, label))
    train_cfg = TrainConfig(
        steps=steps,
        batch_size=settings.batch_size,
        lr=settings.lr,
        grad_clip=1.0,
        seed=seed,
        schedules={"beta": kl_weight(steps, anneal)},
    )
    fingerprint = {
        "x": data_fingerprint(x),
        "label": None if label is None else data_fingerprint(label.float()),
    }
    result = train_or_load(
        name, cfg, model, elbo_loss, data, train_cfg, data_config=fingerprint, progress=progress
    )
    return model, result


@dataclass(frozen=True)
class LatentSummary:
    """How a trained VAE uses its latent space, measured on the training data.

    Attributes:
        kl_per_dim: ``(D,)`` average KL of each dimension (nats), against the model's own prior.
        activity: ``(D,)`` variance over the data of E_q[z], divided by the prior variance sigma_p^2.
        active: number of dimensions whose activity exceeds 0.01 (Burda et al.).
        posterior_var: ``(D,)`` average posterior variance sigma^2 of each dimension.
        mu_std: ``(D,)`` standard deviation over the data of the posterior mean.
    """

    kl_per_dim: Tensor
    activity: Tensor
    active: int
    posterior_var: Tensor
    mu_std: Tensor


def latent_summary(mu: Tensor, logvar: Tensor, prior_logvar: float = 0.0) -> LatentSummary:
    """:class:`LatentSummary` from posterior parameters ``(N, D)`` and the prior's log-variance.

    Activity is measured in units of the prior variance (z / sigma_p), so the 0.01 threshold means the same
    for every sigma_p^2; with the standard normal prior this is exactly Burda et al.'s definition.
    """
    scale = math.exp(-0.5 * prior_logvar)
    return LatentSummary(
        kl_per_dim=kl_per_dimension(mu, logvar, prior_logvar=prior_logvar),
        activity=unit_activity(mu * scale),
        active=active_units(mu * scale),
        posterior_var=logvar.exp().mean(0),
        mu_std=mu.std(0),
    )


def plausibility(positions: Tensor | np.ndarray, offsets: np.ndarray, parents: np.ndarray) -> float:
    """Mean bone-length error (m) of poses ``(N, 22, 3)``, each against the closer of the body types ``(K, 22,
    3)``."""
    positions = np.asarray(positions, dtype=np.float64)
    if positions.ndim != 3:
        raise ValueError(f"plausibility: positions must be poses (N, 22, 3), got shape {positions.shape}")
    errors = [[bone_length_error(pose, parents, body) for body in offsets] for pose in positions]
    return float(np.min(errors, axis=1).mean())


def sample_clip_metrics(
    model: MLPVAE,
    codec: ClipCodec,
    evaluator: Evaluator,
    reference_features: Tensor,
    settings: ChapterSettings,
    seed: int,
    latent_std: float | None = None,
) -> dict[str, Interval]:
    """Accuracy, FID, Diversity, Multimodality and IS of CVAE samples: mean ± 95% CI over repeated sample
    sets.

    Each repeat draws ``settings.per_action`` clips of every action with codes z ~ N(0, s^2 I), where s is the
    prior's standard deviation, or ``latent_std`` when given (to show what sampling from the wrong prior
    does).
    """
    n_actions = model.cfg.n_classes
    labels = torch.arange(n_actions).repeat_interleave(settings.per_action)
    std = math.exp(0.5 * model.cfg.prior_logvar) if latent_std is None else float(latent_std)

    @torch.no_grad()
    def draw(generator: torch.Generator) -> tuple[Tensor, np.random.Generator]:
        z = torch.randn(labels.shape[0], model.cfg.latent_dim, generator=generator) * std
        rng = np.random.default_rng(generator.initial_seed())
        return codec.to_positions(model.decode(z, labels)), rng

    def measure(sample: tuple[Tensor, np.random.Generator]) -> dict[str, float]:
        positions, rng = sample
        return sample_metrics(evaluator, positions, labels.numpy(), reference_features, rng)

    return repeat_metric(measure, draw, settings.n_repeats, seed)


def real_window_metrics(
    test_positions: Tensor,
    test_action: Tensor,
    evaluator: Evaluator,
    reference_features: Tensor,
    settings: ChapterSettings,
    seed: int,
) -> dict[str, Interval]:
    """The real-data row for 2-second windows: random held-out windows, ``per_action`` of each action per
    repeat."""
    test_action = torch.as_tensor(test_action)
    by_action = [torch.nonzero(test_action == a)[:, 0] for a in range(int(test_action.max()) + 1)]

    def draw(generator: torch.Generator) -> tuple[Tensor, np.random.Generator]:
        index = torch.cat(
            [
                rows[torch.randperm(rows.numel(), generator=generator)[: settings.per_action]]
                for rows in by_action
            ]
        )
        return index, np.random.default_rng(generator.initial_seed())

    def measure(sample: tuple[Tensor, np.random.Generator]) -> dict[str, float]:
        index, rng = sample
        return sample_metrics(
            evaluator, test_positions[index], test_action[index].numpy(), reference_features, rng
        )

    return repeat_metric(measure, draw, settings.n_repeats, seed)
