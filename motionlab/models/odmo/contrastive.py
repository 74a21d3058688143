r"""ODMO's embedding loss ``L_es``: contrastive springs between codes, and the σ² prior term.

**Contrastive term** (eq. 1). For a pair of clips with code means :math:`\mu_i, \mu_j` at distance
:math:`d = \lVert\mu_i - \mu_j\rVert_2` and :math:`y = 1` when both clips show the same action:

.. math:: L_c = \tfrac12\Big[\,y\,d^2 + (1 - y)\,\max(0,\ \alpha - d)^2\Big]

Same-class codes are tied by a spring of rest length 0; codes of different classes push each other
apart until they are ``α`` apart (the margin, 5 in the paper), and then stop interacting.

**Prior term**, with the encoder's :math:`q(z \mid x) = \mathcal N(\mu, \mathrm{diag}\, s^2)` and the
prior variance :math:`\sigma^2` (0.05):

* the paper's equation, ``"code"``: :math:`\mathrm{KL}(\mathcal N(\mu, s^2)\,\Vert\,\mathcal N(0, \sigma^2
I))`,
  which also pulls every :math:`\mu` towards the origin with stiffness :math:`1/\sigma^2 = 20`;
* the reference implementation, ``"noise"``: :math:`\mathrm{KL}(\mathcal N(0, s^2)\,\Vert\,\mathcal N(0,
\sigma^2 I))`,
  the noise alone, so that :math:`\mu` is shaped only by the contrastive term (and the reconstruction);
* a standard VAE, ``"standard"``: :math:`\mathrm{KL}(\mathcal N(\mu, s^2)\,\Vert\,\mathcal N(0, I))`.

**Class-balanced pairs.** Batches hold the same number of clips of every class
(:class:`BalancedBatches`), and :func:`balanced_pairs` gives every clip of the batch one partner of its
own class and one of another class, so the two kinds of pairs are equally many.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import torch
from torch import Tensor

from motionlab.models.gaussian import gaussian_kl
from motionlab.models.odmo.config import PRIOR_TARGETS


def contrastive_loss(mu_a: Tensor, mu_b: Tensor, same: Tensor, margin: float, slack: float = 0.0) -> Tensor:
    """Eq. 1 for each pair: codes ``(P, D)`` and ``(P, D)``, ``same`` ``(P,)`` bool -> losses ``(P,)``.

    ``slack`` > 0 replaces the same-class term by ``max(0, d² - slack²)``: same-class codes move freely
    within ``slack`` of each other (the reference implementation uses 0.5).
    """
    if mu_a.shape != mu_b.shape or mu_a.dim() != 2:
        raise ValueError(
            f"contrastive_loss: mu_a and mu_b must both be (P, D), got {tuple(mu_a.shape)} and "
            f"{tuple(mu_b.shape)}"
        )
    if same.shape != mu_a.shape[:1] or same.dtype != torch.bool:
        raise ValueError(
            f"contrastive_loss: same must be a bool tensor ({mu_a.shape[0]},), got {same.dtype} "
            f"{tuple(same.shape)}"
        )
    if not margin > 0:
        raise ValueError(f"contrastive_loss: margin must be positive, got {margin}")
    squared = (mu_a - mu_b).pow(2).sum(dim=-1)
    # the square root's gradient is infinite at 0: keep a floor under it (it only matters for d < 1e-6)
    distance = squared.clamp_min(1e-12).sqrt()
    apart = torch.relu(margin - distance).pow(2)
    together = torch.relu(squared - slack**2) if slack > 0 else squared
    return 0.5 * torch.where(same, together, apart)


def prior_term(mu: Tensor, logvar: Tensor, prior_variance: float, target: str) -> Tensor:
    """The prior term of each clip ``(B,)`` (KL summed over the ``D`` code dimensions; see the module
    notes)."""
    if target not in PRIOR_TARGETS:
        raise ValueError(f"prior_term: target must be one of {PRIOR_TARGETS}, got {target!r}")
    if not prior_variance > 0:
        raise ValueError(f"prior_term: prior_variance must be positive, got {prior_variance}")
    if target == "standard":
        return gaussian_kl(mu, logvar).sum(dim=-1)
    mean = mu if target == "code" else torch.zeros_like(mu)
    return gaussian_kl(mean, logvar, prior_logvar=math.log(prior_variance)).sum(dim=-1)


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
    if labels.dim() != 1 or labels.is_floating_point():
        raise ValueError(
            f"balanced_pairs: labels must be a 1-D integer tensor, got {labels.dtype} {tuple(labels.shape)}"
        )
    classes, counts = labels.unique(return_counts=True)
    if classes.numel() < 2:
        raise ValueError(
            "balanced_pairs: a batch needs clips of at least 2 classes for different-class pairs"
        )
    if bool((counts < 2).any()):
        raise ValueError(
            f"balanced_pairs: classes {classes[counts < 2].tolist()} have a single clip in the batch; "
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


class BalancedBatches:
    """A batch source of class-balanced batches ``(features (B, T, F), labels (B,))`` for the training loop.

    Every batch has ``batch_size / n_classes`` clips of each class. An epoch shuffles each class's clips and
    deals them out; it ends when the smallest class runs out (so every clip is used once at most).
    """

    def __init__(self, features: Tensor, labels: Tensor, n_classes: int) -> None:
        if labels.dim() != 1 or labels.shape[0] != features.shape[0]:
            raise ValueError(
                f"BalancedBatches: labels must be ({features.shape[0]},), got {tuple(labels.shape)}"
            )
        counts = torch.bincount(labels, minlength=n_classes)
        if counts.numel() != n_classes or bool((counts < 2).any()):
            raise ValueError(
                f"BalancedBatches: every one of the {n_classes} classes needs at least 2 clips, "
                f"got counts {counts.tolist()}"
            )
        self.features = features
        self.labels = labels
        self.n_classes = n_classes
        self.members = [torch.nonzero(labels == c).flatten() for c in range(n_classes)]

    def per_class(self, batch_size: int) -> int:
        """Clips of each class in a batch of ``batch_size`` (which must be a multiple of the class count)."""
        if batch_size % self.n_classes or batch_size < 2 * self.n_classes:
            raise ValueError(
                f"BalancedBatches: batch_size must be a multiple of {self.n_classes} classes with at "
                f"least 2 clips each, got {batch_size}"
            )
        return batch_size // self.n_classes

    def __call__(
        self, epoch: int, generator: torch.Generator, batch_size: int
    ) -> Iterator[tuple[Tensor, Tensor]]:
        k = self.per_class(batch_size)
        shuffled = [m[torch.randperm(m.numel(), generator=generator)] for m in self.members]
        n_batches = min(m.numel() for m in shuffled) // k
        if n_batches == 0:
            raise ValueError(f"BalancedBatches: the smallest class has fewer than {k} clips for one batch")
        for b in range(n_batches):
            index = torch.cat([m[b * k : (b + 1) * k] for m in shuffled])
            yield self.features[index], self.labels[index]
