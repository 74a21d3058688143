"""What chapter 03 measures: how a VAE uses its latent space, how plausible its poses are, and the
benchmark metrics of its clips.

* Latent use: :func:`unit_activity` and :func:`active_units` (Burda et al., 2016), :func:`kl_per_dimension`,
  all summarised by :func:`latent_summary`; :func:`encode_all` gives the posteriors of a whole data set.
* Poses: :func:`plausibility`, the bone-length error against the closer body type.
* Clips: :func:`sample_clip_metrics` (accuracy, FID, Diversity, Multimodality and IS of CVAE samples) and
  :func:`real_window_metrics` (the same row for held-out real windows), each a mean ± 95% CI over repeated
  sample sets.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import torch
from torch import Tensor

from motionlab.evaluation.benchmark import sample_metrics
from motionlab.evaluation.evaluator import Evaluator
from motionlab.metrics import bone_length_error
from motionlab.metrics.intervals import Interval, repeat_metric
from motionlab.models.gaussian import gaussian_kl
from motionlab.models.vae.data import ClipCodec
from motionlab.models.vae.model import MLPVAE, LatentVariableModel
from motionlab.models.vae.sampling import sample_clips
from motionlab.validation import check_scalar, check_tensor


class SampleSizes(Protocol):
    """The sizes of the sample sets (the chapter's :class:`~.experiment.ExperimentConfig` has them):
    ``per_action`` clips of every action per set, ``n_repeats`` sets."""

    per_action: int
    n_repeats: int


@torch.no_grad()
def encode_all(
    model: LatentVariableModel, x: Tensor, label: Tensor | None = None, chunk: int = 1024
) -> tuple[Tensor, Tensor | None]:
    """Posterior parameters of a whole data set, in eval mode and in chunks: ``mu``, ``logvar`` ``(N,
    latent_dim)`` (``logvar`` is ``None`` for an autoencoder)."""
    check_scalar(chunk, "chunk", "encode_all", kind=numbers.Integral, minimum=1)
    was_training = model.training
    model.eval()
    try:
        parts = [
            model.encode(x[i : i + chunk], None if label is None else label[i : i + chunk])
            for i in range(0, x.shape[0], chunk)
        ]
    finally:
        model.train(was_training)
    mu = torch.cat([p[0] for p in parts])
    logvar = None if parts[0][1] is None else torch.cat([p[1] for p in parts])
    return mu, logvar


def kl_per_dimension(
    mu: Tensor,
    logvar: Tensor,
    prior_mu: Tensor | float | None = None,
    prior_logvar: Tensor | float | None = None,
) -> Tensor:
    """KL of each latent dimension averaged over the data: ``(N, D)`` posteriors -> ``(D,)`` nats.

    A dimension whose average KL is near zero carries no information about x: its posterior equals the
    prior for every input (posterior collapse of that unit).
    """
    check_tensor(mu, "mu", "kl_per_dimension", ndim=2)
    return gaussian_kl(mu, logvar, prior_mu, prior_logvar).mean(dim=0)


def unit_activity(mu: Tensor) -> Tensor:
    """Variance over the data of the posterior mean E_q[z | x], per dimension: ``(N, D)`` -> ``(D,)``.

    Burda et al. (2016), "Importance Weighted Autoencoders": a unit whose posterior mean does not move
    with x is inactive, whatever its posterior variance.
    """
    check_tensor(mu, "mu", "unit_activity", ndim=2)
    if mu.shape[0] < 2:
        raise ValueError(f"unit_activity: mu must hold at least 2 rows (N, D), got shape {tuple(mu.shape)}")
    return mu.detach().var(dim=0, unbiased=True)


def active_units(mu: Tensor, threshold: float = 0.01) -> int:
    """Number of latent dimensions whose :func:`unit_activity` exceeds ``threshold`` (Burda et al.: 0.01).

    Args:
        mu: ``(N, D)`` posterior means of N data points.
        threshold: activity above which a unit counts as active (positive).
    """
    check_scalar(threshold, "threshold", "active_units", minimum=0.0, include_minimum=False)
    return int((unit_activity(mu) > threshold).sum())


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
    check_scalar(prior_logvar, "prior_logvar", "latent_summary")
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
    cfg: SampleSizes,
    seed: int,
    latent_std: float | None = None,
) -> dict[str, Interval]:
    """Accuracy, FID, Diversity, Multimodality and IS of CVAE samples: mean ± 95% CI over repeated sample
    sets.

    Each of ``cfg.n_repeats`` repeats draws ``cfg.per_action`` clips of every action with codes
    z ~ N(0, σ² I) (:func:`~motionlab.models.vae.sampling.sample_clips`), where σ is the prior's standard
    deviation σ_p, or ``latent_std`` when given (to show what sampling from the wrong prior does).
    """
    n_actions = model.cfg.n_classes
    if n_actions == 0:
        raise ValueError("sample_clip_metrics: model must be conditional (n_classes > 0), got n_classes=0")
    check_scalar(seed, "seed", "sample_clip_metrics", kind=numbers.Integral, minimum=0)
    labels = torch.arange(n_actions).repeat_interleave(cfg.per_action)

    def draw(generator: torch.Generator) -> tuple[Tensor, np.random.Generator]:
        positions = sample_clips(model, codec, labels, generator, latent_std)
        return positions, np.random.default_rng(generator.initial_seed())

    def measure(sample: tuple[Tensor, np.random.Generator]) -> dict[str, float]:
        positions, rng = sample
        return sample_metrics(evaluator, positions, labels.numpy(), reference_features, rng)

    return repeat_metric(measure, draw, cfg.n_repeats, seed)


def real_window_metrics(
    test_positions: Tensor,
    test_action: Tensor,
    evaluator: Evaluator,
    reference_features: Tensor,
    cfg: SampleSizes,
    seed: int,
) -> dict[str, Interval]:
    """The real-data row for 2-second windows: random held-out windows ``(W, L, 22, 3)``, ``cfg.per_action``
    of each action ``(W,)`` per repeat."""
    check_tensor(test_positions, "test_positions", "real_window_metrics", ndim=4, trailing=(22, 3))
    check_scalar(seed, "seed", "real_window_metrics", kind=numbers.Integral, minimum=0)
    test_action = torch.as_tensor(test_action)
    if test_action.shape != test_positions.shape[:1]:
        raise ValueError(
            f"real_window_metrics: test_action must have shape ({test_positions.shape[0]},), "
            f"got {tuple(test_action.shape)}"
        )
    by_action = [torch.nonzero(test_action == a)[:, 0] for a in range(int(test_action.max()) + 1)]

    def draw(generator: torch.Generator) -> tuple[Tensor, np.random.Generator]:
        index = torch.cat(
            [rows[torch.randperm(rows.numel(), generator=generator)[: cfg.per_action]] for rows in by_action]
        )
        return index, np.random.default_rng(generator.initial_seed())

    def measure(sample: tuple[Tensor, np.random.Generator]) -> dict[str, float]:
        index, rng = sample
        return sample_metrics(
            evaluator, test_positions[index], test_action[index].numpy(), reference_features, rng
        )

    return repeat_metric(measure, draw, cfg.n_repeats, seed)
