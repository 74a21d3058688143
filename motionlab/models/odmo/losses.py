r"""ODMO's training loss: the joint objective (eq. 5) with its embedding loss ``L_es`` (eq. 1 and the prior).

With ``E(a, b)`` the squared error averaged over channels and summed over frames (:func:`sequence_error`),
the joint objective on standardised clips is

.. math::
    L = \underbrace{E(\hat x, x)}_{L_{motion}}
        + \underbrace{E(\hat r, r)}_{L_{traj}}
        + \underbrace{E(\hat x_{traj}, \hat r)}_{L_{cons}}
        + \lambda_c \underbrace{L_c}_{\text{eq. 1}} + \lambda_p\, L_{prior}

where ``r`` is the real root trajectory (the paper's τ), ``r̂`` the trajectory generator's and ``x̂_traj``
the trajectory channels of the generated motion; ``L_c + L_prior`` is the embedding loss ``L_es``. ``L_traj``
compares trajectories, positions accumulated from the origin, as the reference implementation does; the
paper's eq. 2 compares the per-frame velocities ``r̂_t - r̂_{t-1}`` with ``r_t - r_{t-1}``. Like the
reference, every term averages over channels where eqs. 2-4 sum. The ablations switch terms off through the
config (:data:`~motionlab.models.odmo.experiment.VARIANTS`); every term is still logged.

**Contrastive term** (eq. 1's first two lines, halved: see *Weights*). For a pair of clips with code means
:math:`\mu, \mu'` at distance :math:`d = \lVert\mu - \mu'\rVert_2` and :math:`y = 1` when both clips
show the same action:

.. math:: L_c = \tfrac12\Big[\,y\,d^2 + (1 - y)\,\max(0,\ \alpha - d)^2\Big]

Same-class codes are tied by a spring of rest length 0; codes of different classes push each other
apart until they are ``α`` apart (the margin, 5 in the paper), and then stop interacting. With a
``slack`` (``ODMOConfig.same_class_slack``, not in the paper) the same-class term becomes
:math:`\max(0, d^2 - \text{slack}^2)`.

**Prior term** (eq. 1's last two lines). The encoder gives :math:`q(z \mid x) = \mathcal N(\mu,
\Sigma)` with :math:`\Sigma = \mathrm{diag}\, \sigma^2`; the paper regularises only the covariance, per clip,

.. math:: L_{prior} = -\ln\det\Sigma + \frac{1}{\sigma_0^2}\operatorname{Tr}\Sigma
          = \sum_i \Big(\frac{\sigma_i^2}{\sigma_0^2} - \ln \sigma_i^2\Big),

over the coordinates :math:`i` of the code: the negative log of a Gamma prior on each
:math:`\sigma_i^2` whose mode is :math:`\sigma_0^2` (supplement §3.1); we subtract its minimum,
:math:`D(1 - \ln\sigma_0^2)`, so that it is 0 at :math:`\sigma^2 = \sigma_0^2` (a constant, no change to
any gradient). :math:`\sigma_0^2` is a variance, 0.05 in the paper. There is no term on
:math:`\mu`: the supplement replaces the standard VAE's Gaussian prior on :math:`\mu` by the contrastive
springs. The three choices of ``ODMOConfig.prior`` (:data:`~motionlab.models.odmo.model.PRIOR_TERMS`):

* ``"covariance"``, the paper's term above (equal to
  :math:`2\,\mathrm{KL}(\mathcal N(0, \sigma^2)\,\Vert\,\mathcal N(0, \sigma_0^2 I))`; the reference
  implementation adds that KL once, i.e. half of it);
* ``"covariance_and_mean"``, an extension: the same plus :math:`\lVert\mu\rVert^2/\sigma_0^2`, i.e.
  :math:`2\,\mathrm{KL}(\mathcal N(\mu, \sigma^2)\,\Vert\,\mathcal N(0, \sigma_0^2 I))`, a spring of stiffness
  :math:`2/\sigma_0^2 = 40` pulling every code mean to the origin;
* ``"standard"``, a standard VAE: :math:`\mathrm{KL}(\mathcal N(\mu, \sigma^2)\,\Vert\,\mathcal N(0, I))`.

**Weights.** Eq. 1 is written for one pair: the contrastive term of the pair plus both clips' covariance
terms, and eq. 5 adds each clip's reconstruction terms. Per clip that is :math:`\tfrac12 L_c(\text{pair})
+ L_{prior}(\text{clip})` beside the clip's reconstruction (``L_c`` above carries the :math:`\tfrac12`).
:func:`joint_objective` weighs the prior term with ``prior_weight`` (0.5 by default: the reference
implementation's balance, see :class:`~motionlab.models.odmo.model.ODMOConfig`).

**Class-balanced pairs.** Batches hold the same number of clips of every class
(:class:`~motionlab.models.odmo.data.BalancedBatches`), and :func:`balanced_pairs` gives every clip of the
batch one partner of its own class and one of another class, so the two kinds of pairs are equally many.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

from motionlab.models.gaussian import gaussian_kl
from motionlab.models.odmo.model import ODMO, PRIOR_TERMS
from motionlab.validation import check_choice, check_scalar, check_tensor


def sequence_error(prediction: Tensor, target: Tensor) -> Tensor:
    """``E(a, b)`` of each clip ``(B,)``: squared error averaged over channels, summed over frames ``(B, T,
    C)``."""
    check_tensor(prediction, "prediction", "sequence_error", ndim=3, finite=False)
    if prediction.shape != target.shape:
        raise ValueError(
            f"sequence_error: prediction and target must both be (B, T, C), got "
            f"{tuple(prediction.shape)} and {tuple(target.shape)}"
        )
    return (prediction - target).pow(2).mean(dim=-1).sum(dim=-1)


def contrastive_loss(mu_a: Tensor, mu_b: Tensor, same: Tensor, margin: float, slack: float = 0.0) -> Tensor:
    """Eq. 1 for each pair: codes ``(P, D)`` and ``(P, D)``, ``same`` ``(P,)`` bool -> losses ``(P,)``.

    ``slack`` > 0 replaces the same-class term by ``max(0, d² - slack²)``: same-class codes move freely
    within ``slack`` of each other (the reference implementation uses 0.5).
    """
    where = "contrastive_loss"
    check_tensor(mu_a, "mu_a", where, ndim=2, finite=False)
    if mu_b.shape != mu_a.shape:
        raise ValueError(
            f"{where}: mu_a and mu_b must both be (P, D), got {tuple(mu_a.shape)} and {tuple(mu_b.shape)}"
        )
    if not isinstance(same, Tensor) or same.dtype != torch.bool:
        raise TypeError(f"{where}: same must be a bool tensor, got {getattr(same, 'dtype', type(same))}")
    if same.shape != mu_a.shape[:1]:
        raise ValueError(f"{where}: same must be ({mu_a.shape[0]},), got {tuple(same.shape)}")
    check_scalar(margin, "margin", where, minimum=0, include_minimum=False)
    check_scalar(slack, "slack", where, minimum=0)
    squared = (mu_a - mu_b).pow(2).sum(dim=-1)
    # the square root's gradient is infinite at 0: keep a floor under it (it only matters for d < 1e-6)
    distance = squared.clamp_min(1e-12).sqrt()
    apart = torch.relu(margin - distance).pow(2)
    together = torch.relu(squared - slack**2) if slack > 0 else squared
    return 0.5 * torch.where(same, together, apart)


def prior_term(mu: Tensor, logvar: Tensor, prior_variance: float, kind: str) -> Tensor:
    """The prior term of each clip ``(B,)`` from ``mu``, ``logvar`` ``(B, D)``, summed over the ``D`` code
    dimensions; ``kind`` is one of :data:`~motionlab.models.odmo.model.PRIOR_TERMS`, ``prior_variance`` the
    variance ``σ₀²`` (see the module notes)."""
    check_choice(kind, "kind", "prior_term", PRIOR_TERMS)
    check_scalar(prior_variance, "prior_variance", "prior_term", minimum=0, include_minimum=False)
    if kind == "standard":
        return gaussian_kl(mu, logvar).sum(dim=-1)
    mean = mu if kind == "covariance_and_mean" else torch.zeros_like(mu)
    return 2.0 * gaussian_kl(mean, logvar, prior_logvar=math.log(prior_variance)).sum(dim=-1)


def balanced_pairs(labels: Tensor, generator: torch.Generator | None = None) -> tuple[Tensor, Tensor, Tensor]:
    """One same-class and one different-class partner for every clip of a batch.

    Args:
        labels: ``(B,)`` class of each clip; every class present needs at least 2 clips, and there must be
            at least 2 classes.
        generator: draws the partners (the global generator when ``None``).

    Returns:
        ``(first, second, same)``, each ``(2B,)``: pair ``k`` joins clips ``first[k]`` and ``second[k]``;
        ``same[k]`` says whether they share a class. The first ``B`` pairs are the same-class ones.
    """
    where = "balanced_pairs"
    check_tensor(labels, "labels", where, ndim=1, floating=False)
    if labels.is_floating_point():
        raise TypeError(f"{where}: labels must be an integer tensor, got dtype {labels.dtype}")
    classes, counts = labels.unique(return_counts=True)
    if classes.numel() < 2:
        raise ValueError(f"{where}: a batch needs clips of at least 2 classes for different-class pairs")
    if bool((counts < 2).any()):
        raise ValueError(
            f"{where}: classes {classes[counts < 2].tolist()} have a single clip in the batch; "
            "every class needs 2 for a same-class pair"
        )
    n = labels.shape[0]
    same_class = labels[:, None] == labels[None, :]
    anchor = torch.arange(n)
    # a uniformly random admissible partner per row: the argmax of random scores over the allowed entries
    scores = torch.rand(2, n, n, generator=generator)
    partner_same = torch.where(same_class & (anchor[:, None] != anchor[None, :]), scores[0], -1.0).argmax(
        dim=1
    )
    partner_other = torch.where(~same_class, scores[1], -1.0).argmax(dim=1)
    first = torch.cat([anchor, anchor])
    second = torch.cat([partner_same, partner_other])
    same = torch.cat([torch.ones(n, dtype=torch.bool), torch.zeros(n, dtype=torch.bool)])
    return first, second, same


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
        "prior": prior_term(out.mu, out.logvar, cfg.prior_variance, cfg.prior).mean(),
    }
    total = terms["motion"] + cfg.prior_weight * terms["prior"]
    if cfg.use_trajectory_loss:
        total = total + terms["trajectory"]
    if cfg.use_consistency:
        total = total + terms["consistency"]
    if cfg.use_contrastive:
        total = total + cfg.contrastive_weight * terms["contrastive"]
    return {"loss": total, **terms}
