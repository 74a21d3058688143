"""The chapter's training runs (jobs): the Motion Cell and its ablations, the baselines, the output heads.

A job is a pair like ``("variant", "mcell")``; :func:`job_run` turns it into the configs of its run under
the chapter's settings, and :func:`train_job` trains it (or loads it from the checkpoint cache).
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import torch
from torch import nn

from motionlab.evaluation.evaluator import Evaluator
from motionlab.models.motion_cell.baselines import baseline_loss
from motionlab.models.motion_cell.config import OUTPUT_KINDS, BaselineConfig, LossConfig, MotionCellConfig
from motionlab.models.motion_cell.losses import ClassifierLoss, motion_cell_loss
from motionlab.models.motion_cell.preparation import PreparedData
from motionlab.models.motion_cell.settings import ChapterSettings
from motionlab.models.motion_cell.training import is_cached, motion_cell_schedules, train_model
from motionlab.train import LinearRamp, TrainConfig, TrainResult

#: The Motion Cell and its ablations (the paper's Table 2 rows).
VARIANTS = ("mcell", "nc", "nl", "sl")
VARIANT_NAMES = {
    "mcell": "Motion Cell",
    "nc": "NC (no classifier loss)",
    "nl": "NL (all alpha_k = 1)",
    "sl": "SL (no motion words)",
}
BASELINES = ("erd", "quaternet")
BASELINE_NAMES = {"erd": "ERD", "quaternet": "QuaterNet-style"}


def learning_rate_decay(steps: int) -> LinearRamp:
    """The learning-rate factor of every run: 1 for the first 60% of the steps, then linear down to 0.1."""
    return LinearRamp(int(0.6 * steps), steps - int(0.6 * steps), 1.0, 0.1)


class Run(NamedTuple):
    """Everything that defines one training run of the chapter (and its checkpoint)."""

    name: str
    model: MotionCellConfig | BaselineConfig
    loss: LossConfig
    train: TrainConfig


#: A job of the chapter: ``("variant", "mcell" | "nc" | "nl" | "sl")``, ``("baseline", "erd" | "quaternet")``
#: or ``("output", "quaternion" | "matrix" | "axis_angle")``.
Job = tuple[str, str]


def chapter_jobs() -> list[Job]:
    """Every training run of the chapter, the longest first (the order in which
    :func:`~motionlab.models.motion_cell.runner.train_chapter` starts them)."""
    return (
        [("variant", "sl"), ("variant", "mcell"), ("variant", "nl"), ("variant", "nc")]
        + [("baseline", kind) for kind in reversed(BASELINES)]
        + [("output", kind) for kind in OUTPUT_KINDS]
    )


def job_run(job: Job, settings: ChapterSettings) -> Run:
    """The :class:`Run` of a job under ``settings`` (see :data:`Job`)."""
    kind, name = job
    mc = settings.motion_cell
    steps = settings.steps

    def train(steps: int, schedules: dict) -> TrainConfig:
        return TrainConfig(
            steps=steps,
            batch_size=settings.batch_size,
            lr=settings.lr,
            schedules=schedules,
            lr_schedule=learning_rate_decay(steps),
            checkpoint_every=None,
        )

    if kind == "variant" and name in VARIANTS:
        model = replace(mc, word_length=1) if name == "sl" else mc
        loss = LossConfig(joint_weights="uniform" if name == "nl" else "impact")
        classifier = 0.0 if name == "nc" else settings.classifier
        return Run(
            f"mcell_{name}",
            model,
            loss,
            train(steps, motion_cell_schedules(steps, settings.beta, classifier, settings.word_drop)),
        )
    if kind == "baseline" and name in BASELINES:
        model = BaselineConfig(
            kind=name,
            n_joints=mc.n_joints,
            hidden_dim=mc.hidden_dim,
            encoder_dim=mc.hidden_dim,
            control_dim=mc.control_dim,
            n_actions=mc.n_actions,
            n_bodies=mc.n_bodies,
        )
        schedules = (
            {"input_noise": LinearRamp(0, int(0.6 * steps), 0.0, settings.input_noise)}
            if name == "erd"
            else {"sampling": LinearRamp(int(0.1 * steps), int(0.5 * steps), 0.0, settings.sampling)}
        )
        return Run(f"mcell_{name}", model, LossConfig(), train(steps, schedules))
    if kind == "output" and name in OUTPUT_KINDS:
        short = settings.representation_steps
        return Run(
            f"mcell_output_{name}",
            replace(mc, output=name),
            LossConfig(),
            train(short, motion_cell_schedules(short, settings.beta, 0.0, settings.word_drop)),
        )
    raise ValueError(f"job_run: unknown job {job!r}; see chapter_jobs() for the jobs of the chapter")


def job_data_config(settings: ChapterSettings, data: PreparedData) -> dict:
    """What defines the training data of every job (part of the cache key)."""
    return {"poses": data.fingerprint, "window": settings.window}


def train_job(
    job: Job,
    settings: ChapterSettings,
    data: PreparedData,
    classifier: Evaluator | None = None,
    progress: bool | None = None,
) -> tuple[nn.Module, TrainResult]:
    """Train (or load from the cache) one job; Motion Cell variants with a classifier loss need ``classifier``
    (the frozen conv evaluator of eq. 24)."""
    run = job_run(job, settings)
    if job[0] == "baseline":
        loss_fn = baseline_loss(run.loss)
    else:
        needs_classifier = uses_classifier(job, settings)
        if needs_classifier and classifier is None:
            raise ValueError(
                f"train_job: {job} uses the classifier loss; pass the conv evaluator as classifier"
            )
        loss_fn = motion_cell_loss(run.loss, classifier_loss(classifier, data) if needs_classifier else None)
    return train_model(
        run.name,
        run.model,
        data.codec,
        loss_fn,
        data.batches,
        run.train,
        data_config=job_data_config(settings, data),
        loss_config=run.loss,
        progress=progress,
    )


def uses_classifier(job: Job, settings: ChapterSettings) -> bool:
    """Whether ``job`` trains with the classifier loss of eq. 24 (and so needs the conv evaluator)."""
    run = job_run(job, settings)
    return "classifier" in run.train.schedules and run.train.schedules["classifier"](run.train.steps) > 0


def classifier_loss(classifier: Evaluator, data: PreparedData) -> ClassifierLoss:
    """Eq. 24's loss with the frozen ``classifier``, its targets taken from the (denoised) training clips."""
    batches = data.batches
    with torch.no_grad():
        positions = data.codec.positions(batches.poses, batches.body)
    return ClassifierLoss(
        classifier, positions, batches.action, batches.body, int(data.codec.offsets.shape[0])
    )


def job_is_cached(job: Job, settings: ChapterSettings, data: PreparedData) -> bool:
    """Whether :func:`train_job` would load ``job`` from the cache."""
    run = job_run(job, settings)
    return is_cached(run.name, run.model, run.train, job_data_config(settings, data), run.loss)
