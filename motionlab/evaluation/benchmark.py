"""The course benchmark: one synthetic data set, one pair of evaluation classifiers, one real-data row.

Every model chapter trains on :func:`load_benchmark`'s training split and is measured with
:func:`benchmark_evaluator` against its test split, so numbers are comparable across chapters. The data
and the trained classifiers are cached under ``build/``, so only the first chapter that asks pays for them.
"""

from __future__ import annotations

from typing import Literal, NamedTuple

import numpy as np
import torch

from motionlab import config
from motionlab.data.store import MotionSet
from motionlab.data.synthetic import load_splits
from motionlab.evaluation.evaluator import Evaluator, evaluator_run, load_evaluator
from motionlab.metrics import diversity, fid, inception_score, mean_ci, multimodality
from motionlab.train.run import Run

#: The benchmark's seed; each split draws from its own random streams of this seed.
BENCHMARK_SEED = 0


class Benchmark(NamedTuple):
    """Train, validation and test clips of the benchmark (4-second clips, 30 fps, 12 style modes)."""

    train: MotionSet
    val: MotionSet
    test: MotionSet


def benchmark_sizes() -> tuple[int, int, int]:
    """Clips per style mode in (train, val, test) for the active profile."""
    return config.choose(quick=(8, 2, 4), full=(80, 10, 20))


def load_benchmark() -> Benchmark:
    """The benchmark splits (generated once, then loaded from ``build/data``)."""
    return Benchmark(*load_splits(BENCHMARK_SEED, benchmark_sizes()))


def labels_of(data: MotionSet) -> dict[str, np.ndarray]:
    """The classifier heads' labels of a data set: action, mode and body type ``(N,)`` each."""
    return {"action": data.action, "mode": data.mode, "body": data.body}


def benchmark_evaluator(kind: Literal["conv", "gru"] = "gru", progress: bool | None = None) -> Evaluator:
    """The frozen evaluation classifier of ``kind`` trained on the benchmark's training split, validated on
    its val split (cached)."""
    train, val, _ = load_benchmark()
    evaluator, _ = load_evaluator(
        train.positions,
        labels_of(train),
        kind=kind,
        progress=progress,
        val_positions=val.positions,
        val_labels=labels_of(val),
    )
    return evaluator


def evaluator_runs(kinds: tuple[Literal["conv", "gru"], ...] = ("gru", "conv")) -> dict[str, Run]:
    """``{kind: Run}``: the training runs of the benchmark's evaluators (:func:`benchmark_evaluator` loads
    them from the cache). A chapter that measures with them trains them beside its own runs
    (``train_many(..., alongside=evaluator_runs())``), so a fresh build pays for them on the worker cores."""
    train, val, _ = load_benchmark()
    return {
        kind: evaluator_run(
            train.positions,
            labels_of(train),
            kind=kind,
            val_positions=val.positions,
            val_labels=labels_of(val),
        )
        for kind in kinds
    }


def sample_metrics(
    evaluator: Evaluator,
    positions: np.ndarray | torch.Tensor,
    action: np.ndarray,
    reference_features: torch.Tensor,
    rng: np.random.Generator,
) -> dict[str, float]:
    """The action-conditioned metric row of one sample set (the ODMO / Action2Motion table columns).

    Args:
        positions: generated (or held-out real) clips ``(N, T, 22, 3)``.
        action: the action each clip was asked to be ``(N,)``.
        reference_features: evaluator features of the training data ``(M, D)`` (FID's reference).
        rng: draws the Diversity and Multimodality pairs.

    Returns:
        ``accuracy``, ``fid``, ``diversity``, ``multimodality`` and the inception score ``is``.
    """
    return feature_metrics(
        *evaluator.features_and_probs(positions, "action"), action, reference_features, rng
    )


def feature_metrics(
    features: torch.Tensor,
    probs: torch.Tensor,
    action: np.ndarray,
    reference_features: torch.Tensor,
    rng: np.random.Generator,
) -> dict[str, float]:
    """:func:`sample_metrics` from the evaluator's ``features`` ``(N, D)`` and action ``probs`` ``(N, C)``."""
    action = np.asarray(action)
    return {
        "accuracy": float((probs.argmax(dim=-1).numpy() == action).mean()),
        "fid": fid(features, reference_features),
        "diversity": diversity(features, n_pairs=min(200, len(action)), rng=rng),
        "multimodality": multimodality(
            features, action, n_pairs=min(20, int(np.bincount(action).min())), rng=rng
        ),
        "is": inception_score(probs),
    }


def real_reference(
    evaluator: Evaluator, benchmark: Benchmark, n_repeats: int = 10, seed: int = 0
) -> dict[str, tuple[float, float]]:
    """The papers' "real data" row: held-out test clips measured against the training clips.

    Each repeat draws the pairs of Diversity / Multimodality afresh (the test set itself is fixed and is the
    sample set); returns ``{metric: (mean, 95% CI half-width)}``.
    """
    reference = evaluator.features(benchmark.train.positions)
    features, probs = evaluator.features_and_probs(benchmark.test.positions, "action")
    rows = [
        feature_metrics(features, probs, benchmark.test.action, reference, np.random.default_rng([seed, r]))
        for r in range(n_repeats)
    ]
    return {key: mean_ci([row[key] for row in rows]) for key in rows[0]}
