r"""Classifier-based scores: Inception Score and recognition accuracy.

Both read the output of a pretrained action classifier on generated motions.

Inception Score (Salimans et al., 2016):

.. math::
    \mathrm{IS} = \exp\Bigl(\mathbb{E}_x\, \mathrm{KL}\bigl(p(y \mid x) \,\Vert\, p(y)\bigr)\Bigr),
    \qquad p(y) = \mathbb{E}_x\, p(y \mid x).

It is high when every motion is classified confidently (sharp :math:`p(y|x)`) and the classes are used
evenly (flat :math:`p(y)`); it lies between 1 (all predictions identical) and the number of classes ``C``
(confident predictions spread uniformly over the classes).
"""

from __future__ import annotations

import numbers
from typing import overload

import numpy as np
from scipy.special import rel_entr

from motionlab.validation import ArrayLike, as_float_array, as_labels, check_scalar

_ROW_SUM_TOLERANCE = 1e-4


def _probabilities(probs: ArrayLike, func: str) -> np.ndarray:
    p = as_float_array(probs, "probs", func, ndim=2, layout="(N, C)")
    if (p < 0).any() or (p > 1).any():
        raise ValueError(f"{func}: probs must lie in [0, 1]; pass softmax(logits), not logits")
    worst = float(np.abs(p.sum(axis=1) - 1.0).max())
    if worst > _ROW_SUM_TOLERANCE:
        raise ValueError(f"{func}: every row of probs must sum to 1 (worst row is off by {worst:.3g})")
    return p


def _score(p: np.ndarray) -> float:
    marginal = p.mean(axis=0, keepdims=True)
    mean_kl = rel_entr(p, marginal).sum(axis=1).mean()
    return float(np.exp(mean_kl))


@overload
def inception_score(probs: ArrayLike, splits: None = None) -> float: ...
@overload
def inception_score(probs: ArrayLike, splits: int) -> tuple[float, float]: ...
def inception_score(probs: ArrayLike, splits: int | None = None) -> float | tuple[float, float]:
    """Inception Score of class probabilities ``probs`` ``(N, C)`` (rows sum to 1).

    Args:
        probs: the classifier's ``p(y | x)`` for each of ``N`` generated motions.
        splits: ``None`` (default) scores the whole set and returns a float. An integer ``s`` cuts the
            rows into ``s`` contiguous, nearly equal chunks (``numpy.array_split``), scores each, and
            returns ``(mean, std)`` over the chunks (population std, ``ddof=0``, as in the original code).
    """
    p = _probabilities(probs, "inception_score")
    if splits is None:
        return _score(p)
    count = int(check_scalar(splits, "splits", "inception_score", kind=numbers.Integral, minimum=1))
    if count > p.shape[0]:
        raise ValueError(f"inception_score: splits ({count}) cannot exceed the number of rows ({p.shape[0]})")
    scores = np.array([_score(chunk) for chunk in np.array_split(p, count)])
    return float(scores.mean()), float(scores.std())


def recognition_accuracy(logits_or_probs: ArrayLike, labels: ArrayLike) -> float:
    """Fraction of motions whose arg-max class equals the requested label.

    Args:
        logits_or_probs: classifier scores ``(N, C)``; logits and probabilities give the same arg-max.
            Ties go to the lowest class index.
        labels: requested classes ``(N,)``, integers in ``[0, C)``.
    """
    func = "recognition_accuracy"
    scores = as_float_array(logits_or_probs, "logits_or_probs", func, ndim=2, layout="(N, C)")
    target = as_labels(labels, "labels", func, length=scores.shape[0])
    if target.dtype.kind not in "biu":
        raise TypeError(f"{func}: labels must be integer class indices, got dtype {target.dtype}")
    n_classes = scores.shape[1]
    if target.min() < 0 or target.max() >= n_classes:
        raise ValueError(
            f"{func}: labels must lie in [0, {n_classes}), got values in [{target.min()}, {target.max()}]"
        )
    return float(np.mean(scores.argmax(axis=1) == target))
