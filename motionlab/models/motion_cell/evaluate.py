"""The paper's evaluation protocol on the course benchmark: Table 2 rows, mean-collapse curves, t-SNE.

* **Protocol.** Every model generates :data:`PROTOCOL_FRAMES` = 140 frames per sample and the first
  :data:`DISCARDED_FRAMES` = 20 are discarded, for every action; a sample set holds the same number of
  samples for every action x body type combination. The paper (§5.1) does so for walking and jogging only;
  its jumping and lifting samples were "terminated when they collapse to the mean pose" (we measure
  collapse instead, below).
* **Table 2.** Each row is the mean and 95% interval over repeated sample sets (ours: the paper's Table 2
  gives one value per model, from one set of 1,000 samples per combination) of IS and FID, and of the
  recognition accuracy and diversity we add (:func:`attribute_metrics`), measured with the benchmark's GRU
  evaluator; the real row is the held-out test split (:func:`real_row`). The paper's IS (eq. 27, 28) is
  over the *attributes*: its ``p(a | X)`` spans both controls (action x gender there, action x body type
  here), as the product of the two attribute classifiers' outputs; ``is_action`` is the IS of the action
  head alone.
  :func:`difference_interval` compares two rows (Welch's interval of the difference of their means).
* **Mean collapse.** Each frame's distance to the data set's mean pose (mean over joints of the
  Euclidean distance, in the body frame of :func:`motionlab.evaluation.body_frame_features`), averaged
  over the samples of the non-periodic actions. A model that regresses to the mean drifts towards zero;
  :func:`collapse_ratio` divides its level over frames 60-140 by real data's level. A model can also fail
  the other way, drifting into poses far from the mean; :func:`speed_curve` (mean joint speed in the body
  frame) tells the two apart: a collapsed model also stops moving.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from typing import NamedTuple, Protocol

import numpy as np
import torch
from scipy.special import stdtrit
from torch import Tensor

from motionlab.evaluation import body_frame_poses, joint_speed
from motionlab.evaluation.benchmark import Benchmark, feature_metrics
from motionlab.evaluation.evaluator import Evaluator
from motionlab.geometry import quat_geodesic
from motionlab.metrics import inception_score, mean_ci, repeat_seed
from motionlab.models.motion_cell.baselines import BaselineConfig
from motionlab.models.motion_cell.data import PoseCodec
from motionlab.models.motion_cell.model import MotionCellConfig
from motionlab.validation import check_scalar, check_tensor

PROTOCOL_FRAMES = 140
DISCARDED_FRAMES = 20
#: Frames (half-open) over which the mean-collapse ratio is measured.
COLLAPSE_FRAMES = (60, 140)
#: The benchmark's actions that happen once per clip (the others repeat: walk, jog, wave).
NON_PERIODIC_ACTIONS = ("jump", "lift", "kick")


class MotionGenerator(Protocol):
    """What the protocol needs of a model: its config (class counts), a codec and ``generate``."""

    cfg: MotionCellConfig | BaselineConfig
    codec: PoseCodec

    def generate(
        self, action: Tensor, body: Tensor, n_frames: int, generator: torch.Generator | None = None
    ) -> Tensor: ...


class SampleSet(NamedTuple):
    """Generated clips: positions ``(N, T, 22, 3)`` over all generated frames, and attributes ``(N,)``
    each."""

    positions: Tensor
    action: Tensor
    body: Tensor

    @property
    def evaluated(self) -> Tensor:
        """The frames the metrics see, ``(N, T - DISCARDED_FRAMES, 22, 3)``."""
        return self.positions[:, DISCARDED_FRAMES:]


class ModelEvaluation(NamedTuple):
    """A Table 2 row ``{metric: (mean, 95% half-width)}``, the first sample set it was measured on, and
    every repeat's values ``{metric: (v_1, ..., v_R)}`` (for :func:`difference_interval`)."""

    row: dict[str, tuple[float, float]]
    samples: SampleSet
    values: dict[str, tuple[float, ...]]


def joint_attribute_probs(action_probs: Tensor, body_probs: Tensor) -> Tensor:
    """``p(action, body | X)`` ``(N, A * B)`` (index ``action * B + body``) from the two attribute
    classifiers' ``(N, A)`` and ``(N, B)``: their product, as two separate classifiers give (the paper's
    §3.4: one classifier per attribute)."""
    if action_probs.dim() != 2 or body_probs.dim() != 2 or action_probs.shape[0] != body_probs.shape[0]:
        raise ValueError(
            f"joint_attribute_probs: expected (N, A) and (N, B), got {tuple(action_probs.shape)} and "
            f"{tuple(body_probs.shape)}"
        )
    return (action_probs[:, :, None] * body_probs[:, None, :]).flatten(1)


def attribute_metrics(
    evaluator: Evaluator,
    positions: Tensor | np.ndarray,
    action: np.ndarray,
    reference_features: Tensor,
    rng: np.random.Generator,
) -> dict[str, float]:
    """One sample set's row: ``is`` (the paper's, over action x body), ``is_action`` (action head only),
    ``accuracy`` (action), ``fid``, ``diversity`` and ``multimodality``, from one pass of the evaluator."""
    features = evaluator.features(positions)
    heads = evaluator.classifier.heads
    with torch.no_grad():
        action_probs = torch.softmax(heads["action"](features).double(), dim=-1)
        body_probs = torch.softmax(heads["body"](features).double(), dim=-1)
    row = feature_metrics(features, action_probs, np.asarray(action), reference_features, rng)
    row["is_action"] = row.pop("is")
    return {"is": inception_score(joint_attribute_probs(action_probs, body_probs)), **row}


def real_row(
    evaluator: Evaluator, benchmark: Benchmark, n_repeats: int = 10, seed: int = 0
) -> dict[str, tuple[float, float]]:
    """The "real data" row: the held-out test clips against the training clips, ``{metric: (mean, 95%
    half-width)}``; the test set is fixed, only Diversity's and Multimodality's pairs are redrawn."""
    reference = evaluator.features(benchmark.train.positions)
    rows = [
        attribute_metrics(
            evaluator,
            benchmark.test.positions,
            benchmark.test.action,
            reference,
            np.random.default_rng([seed, r]),
        )
        for r in range(n_repeats)
    ]
    return {key: mean_ci([row[key] for row in rows]) for key in rows[0]}


def difference_interval(
    a: Sequence[float], b: Sequence[float], confidence: float = 0.95
) -> tuple[float, float, float]:
    """``(mean(a) - mean(b), lower, upper)``: Welch's confidence interval of the difference of two metrics'
    means over independent repeats (unequal variances); the difference is significant when the interval
    excludes 0."""
    x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if x.ndim != 1 or y.ndim != 1 or x.size < 2 or y.size < 2:
        raise ValueError(
            f"difference_interval: need two 1-D samples of 2 or more, got {x.shape} and {y.shape}"
        )
    check_scalar(
        confidence,
        "confidence",
        "difference_interval",
        minimum=0.0,
        maximum=1.0,
        include_minimum=False,
        include_maximum=False,
    )
    va, vb = x.var(ddof=1) / x.size, y.var(ddof=1) / y.size
    diff = float(x.mean() - y.mean())
    se = float(np.sqrt(va + vb))
    if se == 0.0:
        return diff, diff, diff
    dof = (va + vb) ** 2 / (va**2 / (x.size - 1) + vb**2 / (y.size - 1))
    half = float(stdtrit(dof, 0.5 * (1.0 + confidence))) * se  # Student's t quantile (scipy.stats.t.ppf's)
    return diff, diff - half, diff + half


def attribute_grid(n_per_combination: int, n_actions: int = 6, n_bodies: int = 2) -> tuple[Tensor, Tensor]:
    """Actions and body types ``(n_actions * n_bodies * n_per_combination,)``: every combination equally
    often."""
    check_scalar(n_per_combination, "n_per_combination", "attribute_grid", kind=numbers.Integral, minimum=1)
    check_scalar(n_actions, "n_actions", "attribute_grid", kind=numbers.Integral, minimum=1)
    check_scalar(n_bodies, "n_bodies", "attribute_grid", kind=numbers.Integral, minimum=1)
    combination = torch.arange(n_actions * n_bodies).repeat_interleave(n_per_combination)
    return combination // n_bodies, combination % n_bodies


def protocol_samples(
    model: MotionGenerator,
    n_per_combination: int,
    generator: torch.Generator,
    n_frames: int = PROTOCOL_FRAMES,
) -> SampleSet:
    """One sample set: ``n_per_combination`` clips of ``n_frames`` for every action x body combination."""
    action, body = attribute_grid(n_per_combination, model.cfg.n_actions, model.cfg.n_bodies)
    with torch.no_grad():
        poses = model.generate(action, body, n_frames, generator)
        positions = model.codec.positions(poses, body)
    return SampleSet(positions, action, body)


def evaluate_model(
    model: MotionGenerator,
    evaluator: Evaluator,
    reference_features: Tensor,
    n_per_combination: int,
    n_repeats: int,
    seed: int = 0,
) -> ModelEvaluation:
    """Table 2 metrics of ``model`` over ``n_repeats`` sample sets (frames 20-140 of each sample).

    Repeat ``r`` draws its samples with ``torch.Generator().manual_seed(repeat_seed(seed, r))`` and its
    Diversity pairs with ``numpy.random.default_rng([seed, r])``, so the numbers are reproducible.
    """
    check_scalar(
        n_repeats,
        "n_repeats (2 or more, for an interval)",
        "evaluate_model",
        kind=numbers.Integral,
        minimum=2,
    )
    rows, first = [], None
    for r in range(n_repeats):
        samples = protocol_samples(
            model, n_per_combination, torch.Generator().manual_seed(repeat_seed(seed, r))
        )
        first = samples if first is None else first
        rows.append(
            attribute_metrics(
                evaluator,
                samples.evaluated,
                samples.action.numpy(),
                reference_features,
                np.random.default_rng([seed, r]),
            )
        )
    return ModelEvaluation(
        {key: mean_ci([row[key] for row in rows]) for key in rows[0]},
        first,
        {key: tuple(row[key] for row in rows) for key in rows[0]},
    )


def rotation_error_degrees(codec: PoseCodec, poses: Tensor, clean: Tensor) -> float:
    """Mean angle (degrees) between the joint rotations of two sets of pose vectors ``(..., 90)``."""
    return float(torch.rad2deg(quat_geodesic(codec.split(poses)[0], codec.split(clean)[0]).mean()))


def mean_pose(positions: Tensor | np.ndarray) -> Tensor:
    """The data set's mean pose ``(22, 3)``: body-frame positions averaged over all clips and frames."""
    return body_frame_poses(torch.as_tensor(np.asarray(positions))).flatten(0, -3).mean(0)


def distance_to_pose(positions: Tensor | np.ndarray, pose: Tensor) -> Tensor:
    """Mean over joints of the distance (metres) of each frame's body-frame pose to ``pose``: ``(N, T)``."""
    poses = body_frame_poses(torch.as_tensor(np.asarray(positions)))
    if pose.shape != poses.shape[-2:]:
        raise ValueError(f"distance_to_pose: pose must be {tuple(poses.shape[-2:])}, got {tuple(pose.shape)}")
    return (poses - pose).norm(dim=-1).mean(-1)


def action_mask(
    action: Tensor | np.ndarray, action_names: Sequence[str], chosen: Sequence[str] = NON_PERIODIC_ACTIONS
) -> Tensor:
    """Boolean ``(N,)``: which clips' actions are among ``chosen`` (names from ``action_names``)."""
    unknown = set(chosen) - set(action_names)
    if unknown:
        raise ValueError(f"action_mask: unknown actions {sorted(unknown)}; the data has {list(action_names)}")
    ids = torch.tensor([list(action_names).index(name) for name in chosen])
    return torch.isin(torch.as_tensor(np.asarray(action)), ids)


def collapse_curve(samples: SampleSet, pose: Tensor, action_names: Sequence[str]) -> Tensor:
    """Distance to ``pose`` per frame ``(T,)``, averaged over the samples of the non-periodic actions."""
    mask = action_mask(samples.action, action_names)
    if not bool(mask.any()):
        raise ValueError("collapse_curve: the sample set has no clip of a non-periodic action")
    return distance_to_pose(samples.positions[mask], pose).mean(0)


def real_collapse_level(
    positions: Tensor | np.ndarray, action: Tensor | np.ndarray, pose: Tensor, action_names: Sequence[str]
) -> float:
    """Real data's mean distance to ``pose`` over every frame of its non-periodic clips (the ratio's unit)."""
    mask = action_mask(action, action_names)
    if not bool(mask.any()):
        raise ValueError("real_collapse_level: no clip of a non-periodic action")
    return float(distance_to_pose(torch.as_tensor(np.asarray(positions))[mask], pose).mean())


def speed_by_phase(
    positions: Tensor | np.ndarray, period: int, first: int = DISCARDED_FRAMES, fps: float = 30.0
) -> Tensor:
    """Mean :func:`joint_speed` (m/s) of the frames ``t >= first`` grouped by ``t mod period``: ``(period,)``.

    Frame ``t``'s speed is the move from frame ``t - 1`` to ``t``, so with motion words of ``period`` frames
    entry 0 is the step across a word boundary and the others are the steps inside a word.
    """
    check_scalar(period, "period", "speed_by_phase", kind=numbers.Integral, minimum=1)
    speed = joint_speed(positions, fps)[..., first:]
    frames = torch.arange(first, first + speed.shape[-1])
    return torch.stack([speed[..., frames % period == phase].mean() for phase in range(period)])


def speed_curve(samples: SampleSet, action_names: Sequence[str], fps: float = 30.0) -> Tensor:
    """:func:`joint_speed` per frame ``(T,)``, averaged over the samples of the non-periodic actions."""
    mask = action_mask(samples.action, action_names)
    if not bool(mask.any()):
        raise ValueError("speed_curve: the sample set has no clip of a non-periodic action")
    return joint_speed(samples.positions[mask], fps).mean(0)


def real_speed_level(
    positions: Tensor | np.ndarray,
    action: Tensor | np.ndarray,
    action_names: Sequence[str],
    fps: float = 30.0,
) -> float:
    """Real data's mean :func:`joint_speed` over every frame of its non-periodic clips."""
    mask = action_mask(action, action_names)
    if not bool(mask.any()):
        raise ValueError("real_speed_level: no clip of a non-periodic action")
    return float(joint_speed(torch.as_tensor(np.asarray(positions))[mask], fps).mean())


#: Frames of the moving average in :func:`event_strength` (half a second at 30 fps).
EVENT_WINDOW = 15


def event_strength(
    positions: Tensor | np.ndarray,
    action: Tensor | np.ndarray,
    action_names: Sequence[str],
    window: int = EVENT_WINDOW,
    fps: float = 30.0,
) -> float:
    """How hard the non-periodic clips move at their busiest (m/s): the mean over those clips of the
    largest ``window``-frame moving average of :func:`joint_speed`.

    A clip that performs its jump, lift or kick has one busy half second whenever it happens; a clip that
    never gets going, or stands still, does not. Compare it as a ratio to real clips'.
    """
    check_scalar(window, "window", "event_strength", kind=numbers.Integral, minimum=1)
    mask = action_mask(action, action_names)
    if not bool(mask.any()):
        raise ValueError("event_strength: no clip of a non-periodic action")
    speed = joint_speed(torch.as_tensor(np.asarray(positions))[mask], fps)
    if speed.shape[-1] < window:
        raise ValueError(
            f"event_strength: clips of {speed.shape[-1]} frames are shorter than the window ({window})"
        )
    return float(speed.unfold(-1, window, 1).mean(-1).max(-1).values.mean())


def collapse_ratio(curve: Tensor, real_level: float, frames: tuple[int, int] = COLLAPSE_FRAMES) -> float:
    """Mean of ``curve`` ``(T,)`` over ``frames`` divided by ``real_level`` (1: as lively as real data)."""
    check_tensor(curve, "curve", "collapse_ratio", ndim=1)
    begin, end = frames
    if not 0 <= begin < end <= curve.shape[0]:
        raise ValueError(f"collapse_ratio: frames {frames} do not fit a curve of {curve.shape[0]} frames")
    check_scalar(real_level, "real_level", "collapse_ratio", minimum=0.0, include_minimum=False)
    return float(curve[begin:end].mean()) / real_level


def tsne_embedding(features: Tensor | np.ndarray, seed: int = 0, perplexity: float = 30.0) -> np.ndarray:
    """2-D t-SNE embedding ``(N, 2)`` of feature vectors ``(N, D)`` (scikit-learn, PCA initialisation,
    seeded)."""
    from sklearn.manifold import TSNE

    x = np.asarray(features, dtype=np.float64)
    if x.ndim != 2 or x.shape[0] < 5:
        raise ValueError(f"tsne_embedding: features must be (N, D) with N >= 5, got {x.shape}")
    return TSNE(
        n_components=2, perplexity=min(perplexity, (x.shape[0] - 1) / 3), init="pca", random_state=seed
    ).fit_transform(x)
