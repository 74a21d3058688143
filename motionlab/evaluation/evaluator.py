"""The frozen evaluation classifiers every chapter measures its samples with.

:func:`load_evaluator` trains a :class:`~motionlab.evaluation.classifiers.MotionClassifier` on the training
split of the synthetic data set (through the one training loop, so it is cached and trained once; given
held-out clips, it validates on them as it trains), and wraps it with its input standardisation in an
:class:`Evaluator` that takes global joint positions::

    evaluator = load_evaluator(motion_set, split.train, kind="gru")
    probs = evaluator.probs(generated_positions, head="action")     # (N, 6)
    feats = evaluator.features(generated_positions)                 # (N, 30), for FID
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import partial
from typing import Any, Literal

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor, nn

from motionlab import config
from motionlab.data.datasets import Standardizer
from motionlab.evaluation.classifiers import HEADS, ClassifierConfig, MotionClassifier
from motionlab.evaluation.inputs import EVAL_FEATURES, body_frame_features
from motionlab.train import TrainConfig, TrainResult, validation_every
from motionlab.train.run import Run, given
from motionlab.validation import Checked, choice, integer, real

#: Clips are evaluated in chunks of this many to bound memory.
CHUNK = 256


@dataclass(frozen=True)
class ClassifierTraining(Checked):
    """What every evaluation classifier's config holds: its widths and how it is trained.

    Attributes:
        steps: training steps; batch_size: clips (or windows) per step; lr: AdamW learning rate.
        hidden: conv channels or GRU width (Action2Motion: 128); feature_dim: the GRU's feature size
            (Action2Motion: 30).
        seed: seeds initialisation and batch order.
    """

    steps: int = integer(300, minimum=1)
    batch_size: int = integer(64, minimum=1)
    lr: float = real(2e-3, above=0)
    hidden: int = integer(128, minimum=1)
    feature_dim: int = integer(30, minimum=1)
    seed: int = config.seed_field()

    def training(self, n_items: int, validate: bool = False) -> TrainConfig:
        """The classifier's :class:`~motionlab.train.TrainConfig` on ``n_items`` training items (a batch
        holds at most all of them); ``validate``: it validates 40 times
        (:func:`~motionlab.train.validation_every`)."""
        return TrainConfig(
            steps=self.steps,
            batch_size=min(self.batch_size, n_items),
            lr=self.lr,
            grad_clip=1.0,
            seed=self.seed,
            checkpoint_every=None,
            val_every=validation_every(self.steps) if validate else None,
        )


@dataclass(frozen=True)
class EvaluatorConfig(ClassifierTraining):
    """How an evaluation classifier is built and trained (the training fields: :class:`ClassifierTraining`).

    Attributes:
        kind: ``"conv"`` (Motion Cell paper) or ``"gru"`` (Action2Motion / ODMO).
        min_crop: each batch is a random window of between ``min_crop`` frames and the whole clip, so the
            classifier recognises clips of any length in that range (models generate various lengths).
    """

    kind: Literal["conv", "gru"] = choice(("conv", "gru"), "gru")
    min_crop: int = integer(40, minimum=1)


def default_evaluator_config(kind: Literal["conv", "gru"]) -> EvaluatorConfig:
    """The course's evaluator settings for the active profile."""
    return EvaluatorConfig(
        kind=kind, steps=config.choose(quick=40, full=300), hidden=config.choose(quick=32, full=128)
    )


class Evaluator(nn.Module):
    """A trained classifier plus its input standardisation; reads global positions ``(N, T, 22, 3)``."""

    def __init__(self, classifier: MotionClassifier, standardizer: Standardizer) -> None:
        super().__init__()
        self.classifier = classifier
        self.standardizer = standardizer

    def inputs(self, positions: Tensor | np.ndarray) -> Tensor:
        """Standardised classifier input ``(N, T, 67)`` from positions ``(N, T, 22, 3)``."""
        positions = torch.as_tensor(positions, dtype=torch.float32)
        if positions.dim() != 4:
            raise ValueError(f"Evaluator: positions must be (N, T, 22, 3), got {tuple(positions.shape)}")
        return self.standardizer.transform(body_frame_features(positions))

    @torch.no_grad()
    def _chunked(self, positions: Tensor | np.ndarray, fn) -> Tensor:
        positions = torch.as_tensor(positions, dtype=torch.float32)
        if positions.dim() != 4 or positions.shape[0] == 0:
            raise ValueError(
                f"Evaluator: positions must be a non-empty (N, T, 22, 3), got {tuple(positions.shape)}"
            )
        self.eval()
        return torch.cat(
            [fn(self.inputs(positions[i : i + CHUNK])) for i in range(0, positions.shape[0], CHUNK)]
        )

    def _head(self, head: str) -> nn.Module:
        if head not in self.classifier.heads:
            raise KeyError(f"Evaluator has heads {list(self.classifier.heads)}, not {head!r}")
        return self.classifier.heads[head]

    def logits(self, positions: Tensor | np.ndarray, head: str = "action") -> Tensor:
        """Class logits ``(N, C)`` of one head (``action``, ``mode`` or ``body``)."""
        self._head(head)
        return self._chunked(positions, lambda x: self.classifier(x)[head])

    def probs(self, positions: Tensor | np.ndarray, head: str = "action") -> Tensor:
        """Class probabilities ``(N, C)`` of one head."""
        return torch.softmax(self.logits(positions, head).double(), dim=-1)

    def predict(self, positions: Tensor | np.ndarray, head: str = "action") -> Tensor:
        """Predicted class ``(N,)`` of one head."""
        return self.logits(positions, head).argmax(dim=-1)

    def features(self, positions: Tensor | np.ndarray) -> Tensor:
        """Feature vectors ``(N, D)`` for FID, Diversity and Multimodality (deterministic)."""
        return self._chunked(positions, self.classifier.features)

    def features_and_probs(
        self, positions: Tensor | np.ndarray, head: str = "action"
    ) -> tuple[Tensor, Tensor]:
        """:meth:`features` ``(N, D)`` and :meth:`probs` ``(N, C)`` of one head from a single pass over the
        clips (the same numbers as the two calls, at half the cost: the recurrent trunk dominates)."""
        classify, width = self._head(head), self.classifier.feature_dim

        def both(x: Tensor) -> Tensor:
            features = self.classifier.features(x)
            return torch.cat([features, classify(features)], dim=-1)

        out = self._chunked(positions, both)
        return out[:, :width], torch.softmax(out[:, width:].double(), dim=-1)

    def accuracy(
        self, positions: Tensor | np.ndarray, labels: Tensor | np.ndarray, head: str = "action"
    ) -> float:
        """Fraction of clips whose predicted ``head`` class equals ``labels`` ``(N,)``."""
        labels = torch.as_tensor(np.asarray(labels), dtype=torch.int64)
        predicted = self.predict(positions, head)
        if labels.shape != predicted.shape:
            raise ValueError(
                f"Evaluator.accuracy: labels {tuple(labels.shape)} do not match {tuple(predicted.shape)} "
                "clips"
            )
        return float((predicted == labels).double().mean())


def _crop_batches(inputs: Tensor, labels: dict[str, Tensor], min_crop: int, held_out: bool = False):
    """A batch source of random windows of the clips ``inputs`` ``(N, T, F)``, with their ``labels``
    ``{head: (N,)}``: every batch has one random length in ``[min_crop, T]`` and a random start per clip.
    In training order (shuffled, the final short batch dropped); ``held_out``: every clip once in its order,
    the final short batch kept (validation: the generator alone fixes the windows)."""
    n, n_frames = inputs.shape[:2]

    def batches(epoch: int, generator: torch.Generator, batch_size: int):
        order = torch.arange(n) if held_out else torch.randperm(n, generator=generator)
        for begin in range(0, n if held_out else n - batch_size + 1, batch_size):
            index = order[begin : begin + batch_size]
            length = int(torch.randint(min(min_crop, n_frames), n_frames + 1, (1,), generator=generator))
            start = torch.randint(0, n_frames - length + 1, (len(index),), generator=generator)
            frames = start[:, None] + torch.arange(length)
            window = inputs[index[:, None], frames]
            yield window, {name: value[index] for name, value in labels.items()}

    return batches


def _classification_loss(
    model: MotionClassifier, batch, step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    inputs, labels = batch
    logits = model(inputs)
    terms = {f"ce_{name}": F.cross_entropy(logits[name], labels[name]) for name in logits}
    return {"loss": sum(terms.values()), **terms}


def data_fingerprint(positions: np.ndarray | Tensor) -> str:
    """A short hash of a positions array (part of a trained evaluator's cache key)."""
    array = np.ascontiguousarray(np.asarray(positions, dtype=np.float32))
    return hashlib.sha256(array.tobytes()).hexdigest()[:16] + f"-{array.shape}"


def _training_tensors(
    positions: np.ndarray | Tensor, labels: dict[str, np.ndarray | Tensor], what: str = "labels"
) -> tuple[Tensor, dict[str, Tensor]]:
    """The training (or validation) clips as float32 and the labels as int64 tensors, checked against each
    other (``what``: the labels' name in the errors)."""
    unknown = set(labels) - set(HEADS)
    if unknown:
        raise ValueError(f"load_evaluator: unknown label heads {sorted(unknown)} in {what}; use {HEADS}")
    positions = torch.as_tensor(np.asarray(positions), dtype=torch.float32)
    label_tensors = {
        name: torch.as_tensor(np.asarray(value), dtype=torch.int64) for name, value in labels.items()
    }
    for name, value in label_tensors.items():
        if value.shape != positions.shape[:1]:
            raise ValueError(
                f"load_evaluator: {what}[{name!r}] has shape {tuple(value.shape)}, expected "
                f"({positions.shape[0]},)"
            )
    return positions, label_tensors


def _training_identity(
    positions: Tensor, labels: dict[str, Tensor], cfg: EvaluatorConfig, validate: bool = False
) -> tuple[str, dict[str, Any], TrainConfig, dict[str, Any]]:
    """What names an evaluator's training run in the checkpoint cache: its name, model config, training
    config (``validate``: with validation) and data config (computed without building the model, so without
    touching the global RNG)."""
    classes = {name: int(value.max()) + 1 for name, value in labels.items()}
    classifier_cfg = ClassifierConfig(cfg.kind, EVAL_FEATURES, classes, cfg.hidden, cfg.feature_dim)
    train_cfg = cfg.training(positions.shape[0], validate)
    data_config = {
        "positions": data_fingerprint(positions),
        "labels": {k: data_fingerprint(v.numpy()) for k, v in labels.items()},
    }
    return f"evaluator_{cfg.kind}", {"evaluator": cfg, "classifier": classifier_cfg}, train_cfg, data_config


def _classifier_loss(model: Evaluator, batch, step: int, coeffs: dict[str, float]) -> dict[str, Tensor]:
    return _classification_loss(model.classifier, batch, step, coeffs)


def build_evaluator(classifier: ClassifierConfig, positions: Tensor, seed: int) -> Evaluator:
    """An untrained :class:`Evaluator`: its standardisation fitted on the features of ``positions``
    ``(N, T, 22, 3)``, its classifier's weights drawn after seeding torch's global generator with ``seed``."""
    standardizer = Standardizer(EVAL_FEATURES).fit(body_frame_features(positions))
    torch.manual_seed(seed)
    return Evaluator(MotionClassifier(classifier), standardizer)


def _evaluator_batches(
    positions: Tensor, labels: dict[str, Tensor], min_crop: int, model: Evaluator, held_out: bool = False
):
    """Random windows (:func:`_crop_batches`) of the clips ``positions`` ``(N, T, 22, 3)``, standardised by
    ``model``'s standardiser (fitted on the training clips); ``held_out``: in validation order."""
    inputs = model.standardizer.transform(body_frame_features(positions))
    return _crop_batches(inputs, labels, min_crop, held_out)


def _validation_tensors(
    val_positions: np.ndarray | Tensor | None,
    val_labels: dict[str, np.ndarray | Tensor] | None,
    classes: dict[str, int],
) -> tuple[Tensor, dict[str, Tensor]] | None:
    """The validation clips and labels as tensors (``None`` when neither is given), checked against the
    classifier's heads and their ``classes``."""
    if (val_positions is None) != (val_labels is None):
        raise ValueError("evaluator_run: give both val_positions and val_labels, or neither")
    if val_positions is None:
        return None
    positions, labels = _training_tensors(val_positions, val_labels, "val_labels")
    if positions.dim() != 4 or not len(positions):
        raise ValueError(
            f"evaluator_run: val_positions must be a non-empty (M, T, 22, 3), got {tuple(positions.shape)}"
        )
    if set(labels) != set(classes):
        raise ValueError(
            f"evaluator_run: val_labels has heads {sorted(labels)}, the training labels {sorted(classes)}"
        )
    for name, value in labels.items():
        if int(value.min()) < 0 or int(value.max()) >= classes[name]:
            raise ValueError(
                f"evaluator_run: val_labels[{name!r}] must lie in [0, {classes[name]}) (the training "
                f"labels' classes), got [{int(value.min())}, {int(value.max())}]"
            )
    return positions, labels


def evaluator_run(
    positions: np.ndarray | Tensor,
    labels: dict[str, np.ndarray | Tensor],
    cfg: EvaluatorConfig | None = None,
    kind: Literal["conv", "gru"] = "gru",
    *,
    val_positions: np.ndarray | Tensor | None = None,
    val_labels: dict[str, np.ndarray | Tensor] | None = None,
) -> Run:
    """The :class:`~motionlab.train.run.Run` that trains an evaluation classifier on training clips
    ``positions`` ``(N, T, 22, 3)`` with ``labels`` ``{"action": (N,), "mode": (N,), "body": (N,)}`` (any
    subset of these heads); ``cfg``: by default :func:`default_evaluator_config` of ``kind``.

    Given held-out clips ``val_positions`` ``(M, T, 22, 3)`` with ``val_labels`` (the same heads), the run
    validates on them 40 times (:func:`~motionlab.train.validation_every`): random windows as in training,
    standardised with the training clips' statistics, every clip once, the same windows in every pass.
    """
    cfg = default_evaluator_config(kind) if cfg is None else cfg
    positions, label_tensors = _training_tensors(positions, labels)
    validate = val_positions is not None or val_labels is not None
    name, model_config, train_cfg, data_config = _training_identity(positions, label_tensors, cfg, validate)
    val = _validation_tensors(val_positions, val_labels, model_config["classifier"].classes)
    return Run(
        name,
        model_config,
        partial(build_evaluator, model_config["classifier"], positions),
        given(_classifier_loss),
        partial(_evaluator_batches, positions, label_tensors, cfg.min_crop),
        train_cfg,
        data_config,
        val_batches=None if val is None else partial(_evaluator_batches, *val, cfg.min_crop, held_out=True),
    )


def load_evaluator(
    positions: np.ndarray | Tensor,
    labels: dict[str, np.ndarray | Tensor],
    cfg: EvaluatorConfig | None = None,
    kind: Literal["conv", "gru"] = "gru",
    progress: bool | None = None,
    *,
    val_positions: np.ndarray | Tensor | None = None,
    val_labels: dict[str, np.ndarray | Tensor] | None = None,
) -> tuple[Evaluator, TrainResult]:
    """Train (or load from the cache) an evaluation classifier on training clips (:func:`evaluator_run`).

    Args:
        positions: training clips ``(N, T, 22, 3)``, global positions in metres.
        labels: ``{"action": (N,), "mode": (N,), "body": (N,)}`` integer labels (any subset of these heads).
        cfg: the settings; by default :func:`default_evaluator_config` of ``kind``.
        progress: show a progress bar (default: in the full profile only).
        val_positions, val_labels: held-out clips ``(M, T, 22, 3)`` and their labels (the same heads) the
            run validates on (the result's ``history.val_terms``); by default it does not validate.

    Returns:
        The frozen :class:`Evaluator` (eval mode, no gradients needed) and the training result.
    """
    run = evaluator_run(positions, labels, cfg, kind, val_positions=val_positions, val_labels=val_labels)
    evaluator, result = run.train(progress)
    evaluator.requires_grad_(False)
    return evaluator.eval(), result
