r"""Diversity metrics: APD (DLow), Diversity and Multimodality (Action2Motion), per-class APD and n-APD
(ODMO).

**APD** (average pairwise distance, Yuan & Kitani 2020, "DLow") of ``K`` samples :math:`x_1..x_K`, each a
whole sequence flattened to one vector of ``T·D`` numbers:

.. math:: \mathrm{APD} = \frac{1}{K(K-1)} \sum_{i \ne j} \lVert x_i - x_j \rVert_2 .

The norm is over the whole flattened sequence (not per frame), and the mean is over ordered pairs
``i ≠ j``, which equals the mean over unordered pairs (``scipy.spatial.distance.pdist``).

**Diversity** and **Multimodality** (Guo et al. 2020, "Action2Motion"; also used by ODMO) work on
classifier features ``(N, D)``. Diversity draws ``N_d`` index pairs and averages the feature distance;
multimodality does the same within each action class with ``N_l`` pairs per class and averages over
classes (the course's ``N_d``, ``N_l`` are Action2Motion's ``S_d``, ``S_l``; ``S`` is the course's number of
diffusion steps). As in the authors' evaluation code, both indices of a pair are drawn uniformly *with
replacement*, so a pair can repeat a motion (distance 0): the expected value is
:math:`\frac{1}{N^2}\sum_{i,j}\lVert f_i - f_j\rVert`. The papers use ``N_d = 200`` and ``N_l = 20``.

**n-APD** (Lu et al. 2022, "ODMO"): the APD of all generated sequences of one action class, divided by the
APD of the real sequences of that class, averaged over classes. 1 means "as diverse as the data".
"""

from __future__ import annotations

import numbers
from collections.abc import Hashable

import numpy as np

from motionlab.validation import ArrayLike, RngLike, as_float_array, as_labels, as_rng, check_scalar

#: Pairs drawn by :func:`diversity` in Action2Motion's protocol (``N_d``).
DIVERSITY_PAIRS = 200
#: Pairs per class drawn by :func:`multimodality` in Action2Motion's protocol (``N_l``).
MULTIMODALITY_PAIRS = 20


def _apd(flat: np.ndarray) -> float:
    from scipy.spatial.distance import pdist  # scipy.spatial costs 0.2 s to import: on first use

    return float(pdist(flat).mean())


def apd(samples: ArrayLike) -> float:
    """Average pairwise L2 distance between ``K >= 2`` samples ``(K, T, D)`` (any trailing layout).

    Each sample is flattened to one vector (all frames and coordinates) before taking distances, as in
    DLow. Scales linearly: ``apd(c * x) == |c| * apd(x)``.
    """
    x = as_float_array(samples, "samples", "apd", min_ndim=2, layout="(K, T, D)")
    if x.shape[0] < 2:
        raise ValueError(f"apd: samples needs at least 2 samples along the first axis, got {x.shape[0]}")
    return _apd(x.reshape(x.shape[0], -1))


def _mean_pair_distance(
    features: np.ndarray, pool: np.ndarray, n_pairs: int, rng: np.random.Generator
) -> float:
    first = features[rng.choice(pool, size=n_pairs, replace=True)]
    second = features[rng.choice(pool, size=n_pairs, replace=True)]
    return float(np.linalg.norm(first - second, axis=1).mean())


def diversity(features: ArrayLike, n_pairs: int, rng: RngLike) -> float:
    """Action2Motion diversity: mean feature distance over ``n_pairs`` random pairs of motions.

    Args:
        features: classifier features ``(N, D)`` of ``N >= 2`` generated motions (any classes).
        n_pairs: ``N_d``, the number of pairs (:data:`DIVERSITY_PAIRS` = 200 in the papers).
        rng: a ``numpy.random.Generator`` or an integer seed; the same seed gives the same value.
    """
    func = "diversity"
    x = as_float_array(features, "features", func, ndim=2, layout="(N, D)")
    if x.shape[0] < 2:
        raise ValueError(f"{func}: features needs at least 2 rows, got {x.shape[0]}")
    count = int(check_scalar(n_pairs, "n_pairs", func, kind=numbers.Integral, minimum=1))
    return _mean_pair_distance(x, np.arange(x.shape[0]), count, as_rng(rng, func))


def multimodality(features: ArrayLike, labels: ArrayLike, n_pairs: int, rng: RngLike) -> float:
    """Action2Motion multimodality: within-class diversity, ``n_pairs`` pairs per class, averaged over
    classes.

    Args:
        features: classifier features ``(N, D)``.
        labels: action class of each row ``(N,)``; every class present needs at least 2 rows.
        n_pairs: ``N_l``, pairs per class (:data:`MULTIMODALITY_PAIRS` = 20 in the papers).
        rng: a ``numpy.random.Generator`` or an integer seed. Classes are visited in sorted order.
    """
    func = "multimodality"
    x = as_float_array(features, "features", func, ndim=2, layout="(N, D)")
    y = as_labels(labels, "labels", func, length=x.shape[0])
    count = int(check_scalar(n_pairs, "n_pairs", func, kind=numbers.Integral, minimum=1))
    generator = as_rng(rng, func)
    classes, codes, sizes = np.unique(y, return_inverse=True, return_counts=True)
    too_small = classes[sizes < 2]
    if too_small.size:
        raise ValueError(
            f"{func}: every class needs at least 2 rows; classes {too_small.tolist()} have fewer"
        )
    per_class = [
        _mean_pair_distance(x, np.flatnonzero(codes == k), count, generator) for k in range(classes.size)
    ]
    return float(np.mean(per_class))


def _per_class_apd(x: np.ndarray, y: np.ndarray, name: str, func: str) -> dict[Hashable, float]:
    flat = x.reshape(x.shape[0], -1)
    result: dict[Hashable, float] = {}
    for label in np.unique(y):
        rows = flat[y == label]
        if rows.shape[0] < 2:
            raise ValueError(
                f"{func}: class {label.item()!r} of {name} has only 1 sequence; APD needs at least 2"
            )
        result[label.item()] = _apd(rows)
    return result


def class_apd(sequences: ArrayLike, labels: ArrayLike) -> dict[Hashable, float]:
    """APD of the sequences of each class: ``{label: apd}``, classes in sorted order.

    Args:
        sequences: ``(N, T, D)`` (any trailing layout), one row per motion.
        labels: class of each sequence ``(N,)``; every class present needs at least 2 sequences.
    """
    func = "class_apd"
    x = as_float_array(sequences, "sequences", func, min_ndim=2, layout="(N, T, D)")
    return _per_class_apd(x, as_labels(labels, "labels", func, length=x.shape[0]), "sequences", func)


def n_apd(
    generated: ArrayLike, generated_labels: ArrayLike, real: ArrayLike, real_labels: ArrayLike
) -> float:
    """ODMO's normalised APD: mean over classes of ``APD(generated of c) / APD(real of c)``.

    Both sets must contain the same classes, each with at least 2 sequences, and every real class must
    have a non-zero APD. ``generated`` and ``real`` have the same trailing layout ``(T, D)``.
    """
    func = "n_apd"
    gen = as_float_array(generated, "generated", func, min_ndim=2, layout="(N, T, D)")
    ref = as_float_array(real, "real", func, min_ndim=2, layout="(N, T, D)")
    if gen.shape[1:] != ref.shape[1:]:
        raise ValueError(
            f"{func}: generated and real must share the per-sequence shape, got {gen.shape[1:]} and "
            f"{ref.shape[1:]}"
        )
    gen_labels = as_labels(generated_labels, "generated_labels", func, length=gen.shape[0])
    gen_apd = _per_class_apd(gen, gen_labels, "generated", func)
    real_apd = _per_class_apd(
        ref, as_labels(real_labels, "real_labels", func, length=ref.shape[0]), "real", func
    )
    if set(gen_apd) != set(real_apd):
        raise ValueError(
            f"{func}: generated and real must contain the same classes, got {sorted(gen_apd)} and "
            f"{sorted(real_apd)}"
        )
    degenerate = [label for label, value in real_apd.items() if value == 0.0]
    if degenerate:
        raise ValueError(
            f"{func}: real sequences of classes {degenerate} are all identical (APD 0); cannot normalise"
        )
    return float(np.mean([gen_apd[label] / real_apd[label] for label in real_apd]))
