"""Mode discovery and sampling in ODMO's code space.

**Discovery.** For each action class, a Gaussian mixture (scikit-learn) is fitted to the code means ``μ``
of that class's training clips for every number of components ``K = 3 … 11``, and each fit is scored
by the mean silhouette ``s̄_K`` of its hard assignments. The number of modes is the first ``K`` whose
silhouette is more than 95 % of the next one's (``s̄_K > 0.95 · s̄_{K+1}``): more components are taken only
while they make the clusters clearly better separated. Components that keep fewer than ``min_share`` of
the class's codes are dropped (tiny clusters are outliers, not styles), and the others' weights are
renormalised; the share is ours, the paper's supplement (§2.2) drops components of fewer than 10 codes.

**Sampling.** *Mode-preserving* sampling gives every mode its share of the samples (the mixture weights,
or probabilities the user picks) and draws each sample from its mode's Gaussian. The conventional
sampler (``ODMO_conv``) fits one Gaussian per class; a standard VAE samples its prior ``N(0, I)``. All
three are a :class:`ModeSet`. The end point ``r_e`` of a sampled code is that of the training clip whose
code is nearest (:meth:`ModeSet.nearest_end_points`), as in the reference implementation; the paper (§4)
fits a k-nearest-neighbour regressor from codes to end points.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import multivariate_normal
from sklearn.metrics import silhouette_score
from sklearn.mixture import GaussianMixture
from threadpoolctl import threadpool_limits

from motionlab.validation import check_scalar

#: Component counts tried by :func:`discover_modes`, and the silhouette ratio of the selection rule.
K_VALUES = tuple(range(3, 12))
SILHOUETTE_RATIO = 0.95


@dataclass(frozen=True, eq=False)
class ClassModes:
    """The modes of one class: Gaussian components ``means (K, D)``, ``covariances (K, D, D)``, ``weights
    (K,)``; ``silhouettes`` maps each tried component count to its score (empty for a fixed sampler)."""

    means: np.ndarray
    covariances: np.ndarray
    weights: np.ndarray
    silhouettes: dict[int, float]

    @property
    def n_modes(self) -> int:
        return int(self.means.shape[0])

    def assign(self, codes: np.ndarray) -> np.ndarray:
        """The most probable mode of each code ``(n, D) -> (n,)`` (weighted Gaussian densities)."""
        log_density = np.stack(
            [
                np.log(w) + multivariate_normal(m, c, allow_singular=True).logpdf(codes)
                for m, c, w in zip(self.means, self.covariances, self.weights)
            ],
            axis=-1,
        )
        return log_density.reshape(len(codes), -1).argmax(axis=-1)


@dataclass(frozen=True, eq=False)
class ModeSet:
    """Modes of every class plus the training codes they came from.

    Attributes:
        classes: one :class:`ClassModes` per action class.
        codes: training code means ``(N, D)``; action: their classes ``(N,)``; end_points: ``r_e`` ``(N, 3)``.
        labels: each training code's mode within its class ``(N,)``.
    """

    classes: tuple[ClassModes, ...]
    codes: np.ndarray
    action: np.ndarray
    end_points: np.ndarray
    labels: np.ndarray

    def check_action(self, action: int) -> int:
        """``action`` as an ``int`` if it is a class index; ``TypeError`` or ``ValueError`` otherwise."""
        check_scalar(
            action, "action", "ModeSet", kind=numbers.Integral, minimum=0, maximum=len(self.classes) - 1
        )
        return int(action)

    def global_ids(self, action: np.ndarray, mode: np.ndarray) -> np.ndarray:
        """One id per (class, mode within the class) pair, unique across classes: class ``c``'s modes follow
        class ``c - 1``'s. ``action`` and ``mode`` ``(n,)`` -> ``(n,)``."""
        offsets = np.cumsum([0] + [m.n_modes for m in self.classes])[:-1]
        return offsets[np.asarray(action)] + np.asarray(mode)

    def global_labels(self) -> np.ndarray:
        """Each training code's mode as one id across classes ``(N,)`` (see :meth:`global_ids`)."""
        return self.global_ids(self.action, self.labels)

    def nearest_end_points(self, action: int, codes: np.ndarray) -> np.ndarray:
        """``r_e`` ``(n, 3)`` of the training clips of ``action`` whose codes are nearest to ``codes`` ``(n,
        D)``."""
        action = self.check_action(action)
        members = np.flatnonzero(self.action == action)
        distance = ((codes[:, None, :] - self.codes[members][None, :, :]) ** 2).sum(axis=-1)
        return self.end_points[members[distance.argmin(axis=1)]]

    def sample(
        self,
        action: int,
        n: int,
        rng: np.random.Generator,
        probabilities: Sequence[float] | None = None,
        mode: int | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mode-preserving sampling of ``n`` codes of ``action``: ``codes (n, D)`` and their modes ``(n,)``.

        Mode ``m`` gets ``n · p_m`` samples (largest remainders get the leftovers), with ``p`` the mixture
        weights, the given ``probabilities``, or all mass on ``mode``.
        """
        modes = self.classes[self.check_action(action)]
        if mode is not None:
            check_scalar(mode, "mode", "ModeSet.sample", kind=numbers.Integral)
            if not 0 <= mode < modes.n_modes:
                raise ValueError(
                    f"ModeSet.sample: action {action} has modes 0..{modes.n_modes - 1}, got {mode}"
                )
            probabilities = np.eye(modes.n_modes)[mode]
        share = mode_counts(modes.weights if probabilities is None else np.asarray(probabilities, float), n)
        picked = np.repeat(np.arange(modes.n_modes), share)
        codes = np.concatenate(
            [
                rng.multivariate_normal(modes.means[k], modes.covariances[k], size=int(count))
                for k, count in enumerate(share)
            ],
            axis=0,
        )
        return codes, picked


def mode_counts(probabilities: np.ndarray, n: int) -> np.ndarray:
    """Split ``n`` samples over modes in proportion to ``probabilities`` ``(K,)`` (largest remainder
    method)."""
    p = np.asarray(probabilities, dtype=np.float64)
    if p.ndim != 1 or p.size == 0 or not np.all(np.isfinite(p)) or np.any(p < 0) or p.sum() <= 0:
        raise ValueError(
            f"mode_counts: probabilities must be non-negative, finite, with a positive sum, got {p}"
        )
    check_scalar(n, "n", "mode_counts", kind=numbers.Integral, minimum=0)
    exact = p / p.sum() * n
    counts = np.floor(exact).astype(np.int64)
    leftovers = np.argsort(-(exact - counts), kind="stable")[: n - counts.sum()]
    counts[leftovers] += 1
    return counts


def choose_component_count(
    k_values: Sequence[int], silhouettes: Sequence[float], ratio: float = SILHOUETTE_RATIO
) -> int:
    """The first component count ``K`` (of ``k_values``) whose mean silhouette ``s̄_K`` exceeds
    ``ratio · s̄_{K+1}``, the next count's (the last count when there is none)."""
    if len(k_values) != len(silhouettes) or not k_values:
        raise ValueError(
            f"choose_component_count: need one silhouette per k, got {len(k_values)} k and "
            f"{len(silhouettes)} scores"
        )
    for i in range(len(k_values) - 1):
        if silhouettes[i] > ratio * silhouettes[i + 1]:
            return int(k_values[i])
    return int(k_values[-1])


def _mixture(codes: np.ndarray, k: int, seed: int) -> GaussianMixture:
    return GaussianMixture(
        n_components=k, covariance_type="full", reg_covar=1e-4, n_init=1, random_state=seed
    ).fit(codes)


def fit_class_modes(
    codes: np.ndarray, k_values: Sequence[int] = K_VALUES, min_share: float = 0.05, seed: int = 0
) -> ClassModes:
    """The modes of one class's codes ``(n, D)`` (see the module notes)."""
    codes = np.asarray(codes, dtype=np.float64)
    if codes.ndim != 2 or not np.all(np.isfinite(codes)):
        raise ValueError(f"fit_class_modes: codes must be a finite (n, D) array, got shape {codes.shape}")
    if codes.shape[0] <= max(k_values):
        raise ValueError(
            f"fit_class_modes: {codes.shape[0]} codes are too few for up to {max(k_values)} components"
        )
    check_scalar(min_share, "min_share", "fit_class_modes", minimum=0, maximum=1, include_maximum=False)
    fits, scores = {}, {}
    with threadpool_limits(1):  # BLAS threads only fight over the 2 cores on matrices this small
        for k in k_values:
            fits[k] = _mixture(codes, k, seed)
            labels = fits[k].predict(codes)
            scores[k] = float(silhouette_score(codes, labels)) if len(np.unique(labels)) > 1 else -1.0
    best = fits[choose_component_count(list(k_values), [scores[k] for k in k_values])]
    shares = np.bincount(best.predict(codes), minlength=best.n_components) / codes.shape[0]
    keep = shares >= min_share
    weights = best.weights_[keep] / best.weights_[keep].sum()
    return ClassModes(best.means_[keep], best.covariances_[keep], weights, scores)


def _mode_set(
    classes: list[ClassModes], codes: np.ndarray, action: np.ndarray, end_points: np.ndarray
) -> ModeSet:
    labels = np.zeros(len(codes), dtype=np.int64)
    for c, modes in enumerate(classes):
        members = action == c
        labels[members] = modes.assign(codes[members])
    return ModeSet(tuple(classes), codes, action, end_points, labels)


def _check_codes(
    codes: np.ndarray, action: np.ndarray, end_points: np.ndarray, n_classes: int, func: str
) -> tuple:
    # copies: a ModeSet owns its arrays (a NumPy view of a caller's tensor would change with the tensor)
    codes = np.array(codes, dtype=np.float64)
    action = np.array(action, dtype=np.int64)
    end_points = np.array(end_points, dtype=np.float64)
    if codes.ndim != 2 or action.shape != codes.shape[:1] or end_points.shape != (codes.shape[0], 3):
        raise ValueError(
            f"{func}: need codes (N, D), action (N,) and end_points (N, 3), got {codes.shape}, "
            f"{action.shape} and {end_points.shape}"
        )
    missing = sorted(set(range(n_classes)) - set(action.tolist()))
    if missing:
        raise ValueError(f"{func}: classes {missing} have no codes")
    return codes, action, end_points


def discover_modes(
    codes: np.ndarray,
    action: np.ndarray,
    end_points: np.ndarray,
    n_classes: int,
    k_values: Sequence[int] = K_VALUES,
    min_share: float = 0.05,
    seed: int = 0,
) -> ModeSet:
    """Per-class Gaussian mixtures over training codes ``(N, D)`` with silhouette-chosen sizes (ODMO's
    modes)."""
    codes, action, end_points = _check_codes(codes, action, end_points, n_classes, "discover_modes")
    classes = [fit_class_modes(codes[action == c], k_values, min_share, seed) for c in range(n_classes)]
    return _mode_set(classes, codes, action, end_points)


def single_gaussian_modes(
    codes: np.ndarray, action: np.ndarray, end_points: np.ndarray, n_classes: int
) -> ModeSet:
    """One Gaussian per class, fitted to its training codes (the conventional sampler, ``ODMO_conv``)."""
    codes, action, end_points = _check_codes(codes, action, end_points, n_classes, "single_gaussian_modes")
    classes = []
    for c in range(n_classes):
        members = codes[action == c]
        covariance = np.cov(members, rowvar=False) + 1e-4 * np.eye(codes.shape[1])
        classes.append(ClassModes(members.mean(axis=0)[None], covariance[None], np.ones(1), {}))
    return _mode_set(classes, codes, action, end_points)


def prior_modes(codes: np.ndarray, action: np.ndarray, end_points: np.ndarray, n_classes: int) -> ModeSet:
    """The standard-VAE sampler: the prior ``N(0, I)`` for every class (end points still from the nearest
    code)."""
    codes, action, end_points = _check_codes(codes, action, end_points, n_classes, "prior_modes")
    dim = codes.shape[1]
    classes = [ClassModes(np.zeros((1, dim)), np.eye(dim)[None], np.ones(1), {}) for _ in range(n_classes)]
    return _mode_set(classes, codes, action, end_points)
