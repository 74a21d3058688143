"""ODMO's tables on the course benchmark, each number a mean with its 95 % interval over repeated sample sets.

* Tables 1–2 (:func:`metric_row`): accuracy, FID, Diversity, Multimodality (the frozen GRU evaluator's
  features, FID against the training clips) and n-APD (APD of each class's generated clips over that of
  the held-out real clips, in joint positions with every clip starting at the origin facing +x).
* Table 3 (:func:`mode_homogeneity_interval`): the paper's mode homogeneity
  (:func:`~motionlab.metrics.mode_homogeneity`) of the *real* training clips grouped by the modes discovered
  in a model's code space; each repeat keeps a random share of every class's clips.
* Ours beside Table 3 (:func:`style_purity_interval`): clips *generated* from each discovered mode, their
  true style recognised by the evaluator's style head, :func:`~motionlab.metrics.mode_purity` over all
  modes.
* Table 4 (:func:`end_point_control`): for each class, training codes sent to end points on the segment
  from their own end point to that of another clip of the class; accuracy and ``dist_e``, the mean squared
  distance (m²) between the requested end point and where the generated motion's root ends.
* New (:func:`mode_recovery`): the adjusted Rand index between the discovered modes of the training
  codes and the synthetic data's true style modes, per action. The evaluator is not involved: this is
  the latent space against the ground truth.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from motionlab.data.store import MotionSet
from motionlab.evaluation.benchmark import feature_metrics, sample_metrics
from motionlab.evaluation.evaluator import Evaluator
from motionlab.metrics import (
    Interval,
    adjusted_rand_index,
    end_point_mse,
    mean_ci,
    mode_homogeneity,
    mode_purity,
    n_apd,
    repeat_metric,
)
from motionlab.models.odmo.data import prepare, to_positions
from motionlab.models.odmo.modes import ModeSet
from motionlab.models.odmo.sampling import ODMOSampler, Samples, end_point_sweep, to_end_point
from motionlab.validation import check_scalar

#: Columns of Tables 1–2, in order.
METRICS = ("accuracy", "fid", "diversity", "multimodality", "n_apd")


@dataclass(frozen=True, eq=False)
class Reference:
    """What the sample sets are measured against.

    Attributes:
        evaluator: the frozen GRU evaluation classifier.
        train_features: its features of the training clips ``(N, 30)`` (FID's reference).
        real_positions: held-out real clips ``(M, T, J, 3)``, starting at the origin facing +x (n-APD's
        reference). real_action: their actions ``(M,)``.
    """

    evaluator: Evaluator
    train_features: Tensor
    real_positions: Tensor
    real_action: np.ndarray

    @classmethod
    def build(
        cls, evaluator: Evaluator, train: MotionSet, held_out: MotionSet, floor_clearance: float
    ) -> Reference:
        """FID against the ``train`` clips, n-APD against the ``held_out`` ones (e.g. the validation
        split)."""
        return cls(
            evaluator,
            evaluator.features(train.positions),
            canonical_positions(held_out, floor_clearance),
            np.asarray(held_out.action),
        )


def canonical_positions(data: MotionSet, floor_clearance: float) -> Tensor:
    """Joint positions ``(N, T, J, 3)`` of real clips moved to start at the origin facing +x, like generated
    ones."""
    return to_positions(prepare(data, 1, floor_clearance).features, 1, floor_clearance)


def set_metrics(
    reference: Reference, positions: Tensor | np.ndarray, action: np.ndarray, rng: np.random.Generator
) -> dict[str, float]:
    """One row of Tables 1–2 for one set of clips ``(N, T, J, 3)`` of actions ``(N,)``."""
    row = sample_metrics(reference.evaluator, positions, action, reference.train_features, rng)
    row["n_apd"] = n_apd(
        torch.as_tensor(positions).flatten(2),
        action,
        reference.real_positions.flatten(2),
        reference.real_action,
    )
    return {name: row[name] for name in METRICS}


def metric_row(
    reference: Reference, sampler: ODMOSampler, n_per_class: int, n_sets: int = 10, seed: int = 0
) -> dict[str, Interval]:
    """One row of Tables 1–2: ``{metric: Interval}`` over ``n_sets`` sample sets of ``n_per_class`` clips per
    class."""
    _check_counts("metric_row", n_per_class=n_per_class, n_sets=n_sets)

    def draw(generator: torch.Generator) -> tuple[Samples, np.random.Generator]:
        rng = np.random.default_rng(generator.initial_seed())
        return sampler.sample_classes(n_per_class, rng), rng

    return repeat_metric(
        lambda drawn: set_metrics(reference, drawn[0].positions, drawn[0].action, drawn[1]),
        draw,
        n_sets,
        seed,
    )


def real_row(
    reference: Reference, test: MotionSet, floor_clearance: float, n_sets: int = 10, seed: int = 0
) -> dict[str, Interval]:
    """The "real data" row: the test clips measured like a sample set (n-APD against the reference's clips).

    The clips are fixed; the repeats redraw the Diversity and Multimodality pairs.
    """
    _check_counts("real_row", n_sets=n_sets)
    positions, action = canonical_positions(test, floor_clearance), np.asarray(test.action)
    features, probs = reference.evaluator.features_and_probs(positions, "action")
    real_n_apd = n_apd(
        positions.flatten(2), action, reference.real_positions.flatten(2), reference.real_action
    )

    def row(
        rng: np.random.Generator,
    ) -> dict[str, float]:  # set_metrics, with the fixed clips' parts computed once
        metrics = {
            **feature_metrics(features, probs, action, reference.train_features, rng),
            "n_apd": real_n_apd,
        }
        return {name: metrics[name] for name in METRICS}

    return repeat_metric(row, lambda generator: np.random.default_rng(generator.initial_seed()), n_sets, seed)


def mode_homogeneity_interval(
    modes: ModeSet, positions: Tensor | np.ndarray, n_sets: int = 10, share: float = 0.5, seed: int = 0
) -> Interval:
    """Table 3: ODMO's mode homogeneity (per cent) of the real training clips ``positions`` ``(N, T, J, 3)``,
    grouped by the modes ``modes`` discovered for their codes (``modes.labels``, in the same order).

    Each of the ``n_sets`` repeats keeps a random ``share`` of every class's clips (without replacement).
    """
    _check_counts("mode_homogeneity_interval", n_sets=n_sets)
    check_scalar(share, "share", "mode_homogeneity_interval", minimum=0, maximum=1, include_minimum=False)
    flat = torch.as_tensor(positions).flatten(1).numpy()
    if flat.shape[0] != modes.labels.shape[0]:
        raise ValueError(
            f"mode_homogeneity_interval: {flat.shape[0]} clips for {modes.labels.shape[0]} mode labels"
        )

    def draw(generator: torch.Generator) -> np.ndarray:
        rng = np.random.default_rng(generator.initial_seed())
        keep = [
            rng.choice(members, size=max(2, round(share * len(members))), replace=False)
            for members in (np.flatnonzero(modes.action == c) for c in range(len(modes.classes)))
        ]
        return np.sort(np.concatenate(keep))

    return repeat_metric(
        lambda kept: mode_homogeneity(flat[kept], modes.action[kept], modes.labels[kept]), draw, n_sets, seed
    )


def style_purity_interval(
    reference: Reference, sampler: ODMOSampler, n_per_mode: int, n_sets: int = 10, seed: int = 0
) -> Interval:
    """Ours, beside Table 3: purity of the true styles (recognised by the evaluator) among clips generated
    from each discovered mode."""
    _check_counts("style_purity_interval", n_per_mode=n_per_mode, n_sets=n_sets)

    def draw(generator: torch.Generator) -> tuple[np.ndarray, np.ndarray]:
        clips = sampler.sample_modes(n_per_mode, np.random.default_rng(generator.initial_seed()))
        found = sampler.modes.global_ids(clips.action, clips.mode)
        return found, reference.evaluator.predict(clips.positions, "mode").numpy()

    return repeat_metric(lambda drawn: mode_purity(*drawn), draw, n_sets, seed)


def end_point_control(
    reference: Reference, sampler: ODMOSampler, n_codes: int = 40, n_end_points: int = 10, seed: int = 0
) -> dict[str, Interval]:
    """Table 4: ``accuracy`` and ``dist_e`` (mean squared distance, m²) of end-point customisation, intervals
    over the code groups.

    For each class, ``n_codes`` training codes are picked at random; each is sent to ``n_end_points`` end
    points from its own clip's end point to that of another random clip of the class. ``dist_e`` is measured
    on the generated motion's root; ``dist_e_trajectory`` on the trajectory generator's output, which the
    motion was asked to follow.
    """
    _check_counts("end_point_control", n_codes=n_codes, n_end_points=n_end_points)
    rng = np.random.default_rng(seed)
    modes = sampler.modes
    accuracy, distance, trajectory_distance = [], [], []
    for action in range(len(modes.classes)):
        members = np.flatnonzero(modes.action == action)
        source = rng.choice(members, size=n_codes)
        other = rng.choice(members, size=n_codes)
        targets = np.concatenate(
            [
                end_point_sweep(modes.end_points[s], modes.end_points[o], n_end_points)
                for s, o in zip(source, other)
            ]
        )
        clips = to_end_point(sampler, action, np.repeat(modes.codes[source], n_end_points, axis=0), targets)
        correct = (reference.evaluator.predict(clips.positions).numpy() == action).reshape(
            n_codes, n_end_points
        )
        accuracy.extend(correct.mean(axis=1))
        grouped_targets = targets.reshape(n_codes, n_end_points, 3)
        for paths, found in ((clips.features[..., -3:], distance), (clips.trajectory, trajectory_distance)):
            grouped = paths.numpy().reshape(n_codes, n_end_points, -1, 3)
            found.extend(end_point_mse(p, t) for p, t in zip(grouped, grouped_targets))
    return {
        "accuracy": _interval(accuracy),
        "dist_e": _interval(distance),
        "dist_e_trajectory": _interval(trajectory_distance),
    }


def _check_counts(where: str, **counts: int) -> None:
    for name, count in counts.items():
        check_scalar(count, name, where, kind=numbers.Integral, minimum=1)


def _interval(values: list[float]) -> Interval:
    mean, half_width = mean_ci(values)
    return Interval(mean, half_width, tuple(float(v) for v in values), 0.95)


def mode_recovery(modes: ModeSet, true_mode: np.ndarray) -> np.ndarray:
    """Adjusted Rand index between discovered and true modes of the training codes, per action ``(A,)``."""
    true_mode = np.asarray(true_mode)
    if true_mode.shape != modes.labels.shape:
        raise ValueError(
            f"mode_recovery: true_mode must be ({modes.labels.shape[0]},), got {true_mode.shape}"
        )
    return np.array(
        [
            adjusted_rand_index(modes.labels[modes.action == a], true_mode[modes.action == a])
            for a in range(len(modes.classes))
        ]
    )
