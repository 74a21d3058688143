"""Chapter 04's experiment: its sizes and schedules per profile, its named training runs, training them all.

Fairness: every Table 2 model trains on the same denoised clips, with the same batch size, learning rate and
number of steps (the output-representation comparison has its own, shorter, equal budget), and is
evaluated by the same protocol (:mod:`.evaluate`). Every run is seeded by its own configs, so its weights
do not depend on the process that trained it or on the order of the runs.

The chapter's steps (and the training command's: :data:`CHAPTER`, :data:`DEFAULT_RUN`, :func:`load_data`,
:func:`runs`, :func:`measure`, :func:`with_steps`, as in every family)::

    data = load_data(cfg)        # denoised clips; the benchmark's evaluators train in two workers meanwhile
    trained = train_all(cfg, data)
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from motionlab import config
from motionlab.data.store import MotionSet
from motionlab.evaluation.benchmark import benchmark_evaluator, evaluator_runs, load_benchmark
from motionlab.evaluation.evaluator import Evaluator, data_fingerprint
from motionlab.models.motion_cell.baselines import BaselineConfig, FrameBaseline, baseline_loss
from motionlab.models.motion_cell.data import PoseCodec, WindowBatches, cut_windows, motion_cell_features
from motionlab.models.motion_cell.denoise import (
    CAPTURE_SEED,
    DENOISER_DATA_SEED,
    DENOISER_THREADS,
    VAL_CAPTURE_SEED,
    DenoiserConfig,
    DenoisingAutoencoder,
    PreparedData,
    denoiser_loss,
    noisy_features,
)
from motionlab.models.motion_cell.evaluate import ModelEvaluation, evaluate_model, rotation_error_degrees
from motionlab.models.motion_cell.heads import OUTPUT_KINDS
from motionlab.models.motion_cell.losses import ClassifierLoss, LossConfig, LossFn, motion_cell_loss
from motionlab.models.motion_cell.model import MotionCellConfig, MotionCellModel
from motionlab.train import (
    KLAnneal,
    LinearRamp,
    TensorBatches,
    TrainConfig,
    build_seeded,
    train_or_load,
    validation_every,
)
from motionlab.train.many import Trained, train_many, train_meanwhile
from motionlab.train.run import Run
from motionlab.train.schedules import Schedule
from motionlab.validation import check_scalar, instance, integer, real

#: The chapter that trains this family, and its main run (the training command's default).
CHAPTER, DEFAULT_RUN = "04_motion_cell", "mcell"

#: The rows of the paper's Table 2 (run name -> label): the Motion Cell, its ablations, the baselines.
TABLE = {
    "mcell": "Motion Cell",
    "nc": "NC (no classifier loss)",
    "nl": "NL (all joint weights 1)",
    "sl": "SL (single layer: no word encoder or decoder)",
    "erd": "ERD",
    "quaternet": "QuaterNet-style",
}


@dataclass(frozen=True)
class ExperimentConfig(config.ProfileConfig):
    """Everything the chapter's runs depend on: :meth:`quick` (tiny and fast) or :meth:`full` (the reported
    models); :meth:`current` is the one of the active profile.

    Attributes:
        motion_cell: the full model's architecture (ablations and baselines are derived from it).
        denoiser: the denoising autoencoder's architecture.
        window: training window in frames (a multiple of the word length); batch_size, lr: for every run.
        steps: optimiser steps of every Table 2 model; representation_steps: of each output-head run;
            collapse_steps: of the Motion Cell and ERD trained longer for the mean-collapse comparison
            (``mcell_long``, ``erd_long``).
        denoiser_steps, denoiser_batch, denoiser_lr: the denoiser's training (windows of ``window`` frames);
            denoiser_copies: noisy copies of the validation split it sees.
        beta: lambda_KL after annealing (the paper: 1); classifier: lambda_CL after its ramp; word_drop:
            final rate of scheduled motion-word dropping; input_noise: ERD's final input noise (std, in
            pose-vector units); sampling: QuaterNet's final scheduled-sampling probability.
        n_per_combination, n_repeats: evaluation sample sets (per action x body) and their number.
    """

    motion_cell: MotionCellConfig = instance(
        MotionCellConfig,
        default_factory=lambda: MotionCellConfig(
            word_dim=48, feature_dim=48, latent_dim=16, hidden_dim=64, control_dim=16
        ),
    )
    denoiser: DenoiserConfig = instance(
        DenoiserConfig, default_factory=lambda: DenoiserConfig(channels=96, bottleneck=64)
    )
    window: int = integer(96, minimum=1)
    batch_size: int = integer(32, minimum=1)
    lr: float = real(3e-3, above=0)
    steps: int = integer(800, minimum=10)  # the schedules need 10 steps
    representation_steps: int = integer(240, minimum=10)
    collapse_steps: int = integer(2000, minimum=10)
    denoiser_steps: int = integer(2000, minimum=1)
    denoiser_batch: int = integer(16, minimum=1)
    denoiser_lr: float = real(1e-3, above=0)
    denoiser_copies: int = integer(3, minimum=1)
    beta: float = real(1.0, minimum=0)
    classifier: float = real(1.0, minimum=0)
    word_drop: float = real(0.5, minimum=0, maximum=1)
    input_noise: float = real(0.05, minimum=0)
    sampling: float = real(1.0, minimum=0, maximum=1)
    n_per_combination: int = integer(20, minimum=1)
    n_repeats: int = integer(5, minimum=2)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.window % self.motion_cell.word_length:
            raise ValueError(
                f"ExperimentConfig: window ({self.window}) must be a multiple of the word length "
                f"({self.motion_cell.word_length})"
            )

    @classmethod
    def quick(cls) -> ExperimentConfig:
        """Tiny models and a few steps: the whole chapter in about a minute of training."""
        return cls(
            motion_cell=MotionCellConfig(
                word_dim=16, feature_dim=16, latent_dim=8, hidden_dim=16, control_dim=8
            ),
            denoiser=DenoiserConfig(channels=16, bottleneck=8),
            window=24,
            batch_size=16,
            steps=12,
            representation_steps=10,
            collapse_steps=16,
            denoiser_steps=10,
            denoiser_batch=8,
            denoiser_copies=1,
            n_per_combination=2,
            n_repeats=2,
        )

    @classmethod
    def long(cls) -> ExperimentConfig:
        """A longer, larger run for the training command (``python -m motionlab.apps.training motion_cell
        --config long``): the Motion Cell at :class:`MotionCellConfig`'s own sizes (hidden 128, words of 64),
        6,000 steps (the output heads 1,600; the longer mean-collapse runs 10,000); the same denoiser and
        evaluation as :meth:`full`."""
        return cls(
            motion_cell=MotionCellConfig(), steps=6_000, representation_steps=1_600, collapse_steps=10_000
        )


def prepare_training_data(
    train: MotionSet, val: MotionSet, cfg: ExperimentConfig, progress: bool | None = None
) -> PreparedData:
    """Capture the training split with noise, train the denoiser on the validation split (or load it from
    the checkpoint cache), and denoise the capture.

    The denoiser validates on the captured training split against its clean clips, a split it never trains
    on, all windows in order. The models' validation windows (:attr:`PreparedData.val`) are the
    validation split captured with its own noise (:data:`~.denoise.VAL_CAPTURE_SEED`), denoised by the same
    denoiser and encoded by the same codec (fitted on the captured training split, not refitted).

    Args:
        train, val: the benchmark's training and validation splits (clean clips).
        cfg: the chapter's :class:`ExperimentConfig` (the denoiser, its training, the window).
        progress: the denoiser's progress bar.
    """
    captured = noisy_features(train.rotations, train.positions, CAPTURE_SEED)
    codec = PoseCodec(train.offsets, train.parents.tolist()).fit(captured)
    captured_poses = codec.encode(captured)
    clean = codec.encode(motion_cell_features(train.rotations, train.positions))
    clean_val = codec.encode(motion_cell_features(val.rotations, val.positions))
    rng = np.random.default_rng(DENOISER_DATA_SEED)
    noisy_val = torch.cat(
        [codec.encode(noisy_features(val.rotations, val.positions, rng)) for _ in range(cfg.denoiser_copies)]
    )
    pairs = TensorBatches(
        (
            cut_windows(noisy_val, cfg.window),
            cut_windows(clean_val.repeat(cfg.denoiser_copies, 1, 1), cfg.window),
        )
    )
    loss_cfg = LossConfig()
    train_cfg = TrainConfig(
        steps=cfg.denoiser_steps,
        batch_size=min(cfg.denoiser_batch, len(pairs)),
        lr=cfg.denoiser_lr,
        lr_schedule=learning_rate_decay(cfg.denoiser_steps),
        checkpoint_every=None,
        val_every=validation_every(cfg.denoiser_steps),
    )
    own_codec = codec.copy()
    with config.threads(DENOISER_THREADS):
        denoiser = build_seeded(lambda: DenoisingAutoencoder(cfg.denoiser, own_codec), train_cfg.seed)
        result = train_or_load(
            "mcell_denoiser",
            {"model": cfg.denoiser, "loss": loss_cfg},
            denoiser,
            denoiser_loss(loss_cfg),
            pairs,
            train_cfg,
            val_data=TensorBatches(
                (cut_windows(captured_poses, cfg.window), cut_windows(clean, cfg.window)),
                shuffle=False,
                drop_last=False,
            ),
            data_config={
                "val": data_fingerprint(noisy_val.numpy()),
                "codec": data_fingerprint(captured.numpy()),
                "window": cfg.window,
            },
            progress=progress,
        )
    denoised = denoiser.denoise(captured_poses)
    errors = {
        "captured": rotation_error_degrees(codec, captured_poses, clean),
        "denoised": rotation_error_degrees(codec, denoised, clean),
    }
    batches = WindowBatches(denoised, train.action, train.body, cfg.window)
    val_denoised = denoiser.denoise(
        codec.encode(noisy_features(val.rotations, val.positions, VAL_CAPTURE_SEED))
    )
    val_batches = WindowBatches(
        val_denoised, val.action, val.body, cfg.window, shuffle=False, drop_last=False
    )
    return PreparedData(
        codec,
        captured_poses,
        batches,
        data_fingerprint(denoised.numpy()),
        denoiser,
        result,
        errors,
        val_batches,
    )


def learning_rate_decay(steps: int) -> LinearRamp:
    """The learning-rate factor of every run (and of the denoiser): 1 for the first 60% of the steps, linear
    down to 0.1 by 80%, then held at 0.1, so that the last fifth shows whether the loss has levelled off at
    the final rate."""
    check_scalar(steps, "steps", "learning_rate_decay", kind=numbers.Integral, minimum=1)
    start = int(0.6 * steps)
    return LinearRamp(start, max(int(0.8 * steps) - start, 1), 1.0, 0.1)  # a run of 1 step: factor 1


def motion_cell_schedules(
    steps: int, beta: float = 1.0, classifier: float = 0.0, word_drop: float = 0.0
) -> dict[str, Schedule]:
    """The Motion Cell's coefficient schedules over a run of ``steps``.

    * ``beta``: lambda_KL as in §3.5.1: 0 for the first 10% (warm-up), linear to ``beta`` by 70%
      (annealing), then held at ``beta`` for the last 30% (the paper's "cool-down", at lambda_KL = 1);
    * ``classifier``: lambda_CL, 0 for the first 30%, linear to ``classifier`` by 50% ("ramped in after
      the start": the classifier only makes sense once reconstructions look like motion);
    * ``word_drop``: scheduled motion-word dropping, from 0 at 10% to ``word_drop`` at 60%.
    """
    check_scalar(steps, "steps", "motion_cell_schedules", kind=numbers.Integral, minimum=10)

    def at(fraction: float) -> int:
        return int(round(fraction * steps))

    return {
        "beta": KLAnneal(max_value=beta, warmup=at(0.1), anneal=at(0.6)),
        "classifier": LinearRamp(at(0.3), at(0.2), 0.0, classifier),
        "word_drop": LinearRamp(at(0.1), at(0.5), 0.0, word_drop),
    }


def build_model(cfg: MotionCellConfig | BaselineConfig, codec: PoseCodec, seed: int = 0) -> nn.Module:
    """A fresh Motion Cell or baseline for ``cfg``, its weights drawn from ``seed`` (the caller's random
    state is untouched); the model gets its own copy of ``codec``."""
    if not isinstance(cfg, (MotionCellConfig, BaselineConfig)):
        raise TypeError(f"build_model: cfg must be a MotionCellConfig or BaselineConfig, got {cfg!r}")
    network = FrameBaseline if isinstance(cfg, BaselineConfig) else MotionCellModel
    own_codec = codec.copy()
    return build_seeded(lambda: network(cfg, own_codec), seed)


def uses_classifier(train_config: TrainConfig) -> bool:
    """Whether a run of ``train_config`` trains with the classifier loss of eq. 24 (and so needs the conv
    evaluator)."""
    ramp = train_config.schedules.get("classifier")
    return ramp is not None and ramp(train_config.steps) > 0


def make_loss(
    model: MotionCellConfig | BaselineConfig, loss: LossConfig, data: PreparedData, classifier: bool
) -> LossFn:
    """The objective of a run: the baselines' loss, or the Motion Cell's (eq. 25) with, if ``classifier``,
    eq. 24's loss through the benchmark's frozen conv evaluator (trained by :func:`load_data`), its layer
    weights taken from the (denoised) training clips."""
    if isinstance(model, BaselineConfig):
        return baseline_loss(loss)
    if not classifier:
        return motion_cell_loss(loss, None)
    batches, codec = data.batches, data.codec
    with torch.no_grad():
        positions = codec.positions(batches.poses, batches.body)
    return motion_cell_loss(loss, ClassifierLoss(benchmark_evaluator("conv", progress=False), positions))


def _windows(data: PreparedData, model: nn.Module) -> WindowBatches:
    return data.batches


def validation_batches(data: PreparedData, model: nn.Module) -> WindowBatches:
    """The validation windows (one per validation clip, every clip in its order, the last batch kept), for a
    run's held-out curve; each batch is a :class:`~.data.WindowBatch` like the training ones."""
    if data.val is None:
        raise ValueError("validation_batches: the prepared data has no validation windows (data.val is None)")
    return data.val


def motion_cell_run(
    name: str,
    model: MotionCellConfig | BaselineConfig,
    loss: LossConfig,
    train_config: TrainConfig,
    data: PreparedData,
) -> Run:
    """The :class:`~motionlab.train.run.Run` of a Motion Cell (or ablation, or output head) or a baseline on
    the denoised training data (its fingerprint and the window length are the cache key's data part); it
    validates on ``data.val`` every ``train_config.val_every`` steps when that is set."""
    return Run(
        name,
        {"model": model, "loss": loss},
        partial(build_model, model, data.codec),
        partial(make_loss, model, loss, data, uses_classifier(train_config)),
        partial(_windows, data),
        train_config,
        {"poses": data.fingerprint, "window": data.batches.length},
        val_batches=None if train_config.val_every is None else partial(validation_batches, data),
    )


def runs(cfg: ExperimentConfig, data: ChapterData | PreparedData) -> dict[str, Run]:
    """The chapter's runs by name, the longest first: the Motion Cell and ERD trained ``collapse_steps``
    (``mcell_long``, ``erd_long``), the Motion Cell and its ablations (SL, NL, NC), the baselines, and the
    three output heads (``output_quaternion`` ...), on ``data`` (the chapter's, or denoised data alone)."""
    prepared = data.prepared if isinstance(data, ChapterData) else data
    mc, steps = cfg.motion_cell, cfg.steps

    def run(
        name: str, model: MotionCellConfig | BaselineConfig, loss: LossConfig, steps: int, schedules: dict
    ) -> Run:
        train = TrainConfig(
            steps=steps,
            batch_size=cfg.batch_size,
            lr=cfg.lr,
            schedules=schedules,
            lr_schedule=learning_rate_decay(steps),
            checkpoint_every=None,
            val_every=validation_every(steps),  # the held-out curve: 40 passes over the validation windows
        )
        return motion_cell_run(f"mcell_{name}", model, loss, train, prepared)

    def variant(
        name: str, model: MotionCellConfig, loss: LossConfig, classifier: float, steps: int = steps
    ) -> Run:
        schedules = motion_cell_schedules(steps, cfg.beta, classifier, cfg.word_drop)
        return run(name, model, loss, steps, schedules)

    def baseline(kind: str, schedules: dict, name: str | None = None, steps: int = steps) -> Run:
        model = BaselineConfig(
            kind=kind,
            n_joints=mc.n_joints,
            hidden_dim=mc.hidden_dim,
            encoder_dim=mc.hidden_dim,
            control_dim=mc.control_dim,
            n_actions=mc.n_actions,
            n_bodies=mc.n_bodies,
        )
        return run(name or kind, model, LossConfig(), steps, schedules)

    def erd(steps: int, name: str = "erd") -> Run:
        noise = LinearRamp(0, int(0.6 * steps), 0.0, cfg.input_noise)
        return baseline("erd", {"input_noise": noise}, name, steps)

    def output_head(kind: str) -> Run:
        short = cfg.representation_steps
        schedules = motion_cell_schedules(short, cfg.beta, 0.0, cfg.word_drop)
        return run(f"output_{kind}", replace(mc, output=kind), LossConfig(), short, schedules)

    return {
        "mcell_long": variant("mcell_long", mc, LossConfig(), cfg.classifier, cfg.collapse_steps),
        "erd_long": erd(cfg.collapse_steps, "erd_long"),
        "sl": variant("sl", replace(mc, word_length=1, word_layers=False), LossConfig(), cfg.classifier),
        "mcell": variant("mcell", mc, LossConfig(), cfg.classifier),
        "nl": variant("nl", mc, LossConfig(joint_weights="uniform"), cfg.classifier),
        "nc": variant("nc", mc, LossConfig(), 0.0),
        "quaternet": baseline(
            "quaternet", {"sampling": LinearRamp(int(0.1 * steps), int(0.5 * steps), 0.0, cfg.sampling)}
        ),
        "erd": erd(steps),
        **{f"output_{kind}": output_head(kind) for kind in OUTPUT_KINDS},
    }


@dataclass(frozen=True)
class ChapterData:
    """What the chapter's runs train on and are measured with.

    Attributes:
        prepared: the denoised training data (:func:`prepare_training_data`).
        evaluator: the benchmark's frozen GRU evaluator; reference: its features of the training clips
            ``(N, D)`` (FID's reference).
    """

    prepared: PreparedData
    evaluator: Evaluator
    reference: Tensor


def load_data(
    cfg: ExperimentConfig, progress: bool | None = None, processes: int | None = None
) -> ChapterData:
    """The chapter's data: the benchmark's training split captured with noise and denoised
    (:func:`prepare_training_data`, here), while ``processes`` workers train the benchmark's two evaluators
    (the conv one for eq. 24's loss, the GRU one to measure); then the GRU evaluator and its reference."""
    benchmark = load_benchmark()
    prepare = partial(prepare_training_data, benchmark.train, benchmark.val, cfg, progress)
    prepared = train_meanwhile(evaluator_runs(("conv", "gru")), prepare, processes)
    gru = benchmark_evaluator("gru", progress=False)
    return ChapterData(prepared, gru, gru.features(benchmark.train.positions))


def table_row(
    name: str,
    model: nn.Module,
    evaluator: Evaluator,
    reference: Tensor,
    n_per_combination: int,
    n_repeats: int,
) -> ModelEvaluation | None:
    """The Table 2 row of a run in :data:`TABLE` (:func:`~.evaluate.evaluate_model`, seed 0); ``None`` for
    the others."""
    if name not in TABLE:
        return None
    return evaluate_model(model, evaluator, reference, n_per_combination, n_repeats, seed=0)


def measure(cfg: ExperimentConfig, data: ChapterData, name: str, model: nn.Module) -> dict[str, Any]:
    """The training command's measurement of run ``name``: its Table 2 row (IS, FID, accuracy, diversity,
    ``{metric: {"mean", "ci95"}}``); the output-head runs have none."""
    row = table_row(name, model, data.evaluator, data.reference, cfg.n_per_combination, cfg.n_repeats)
    if row is None:
        return {"table2": None, "note": f"{name!r} is not a row of the chapter's Table 2"}
    return {"table2": {key: {"mean": mean, "ci95": half} for key, (mean, half) in row.row.items()}}


def with_steps(cfg: ExperimentConfig, name: str, steps: int) -> ExperimentConfig:
    """``cfg`` with run ``name`` trained for ``steps`` optimiser steps (the output heads share
    ``representation_steps``, the other runs ``steps``)."""
    field_name = "representation_steps" if name.startswith("output_") else "steps"
    return replace(cfg, **{field_name: steps})


def train_all(
    cfg: ExperimentConfig, data: ChapterData, processes: int | None = None, progress: bool | None = None
) -> dict[str, Trained[ModelEvaluation | None]]:
    """Train (or load) every run of :func:`runs`, ``processes`` at a time in worker processes, and measure
    every Table 2 model in a worker as soon as it is trained: :attr:`Trained.measured` is its
    :class:`~.evaluate.ModelEvaluation` (``None`` for the output-head runs)."""
    then = partial(
        table_row,
        evaluator=data.evaluator,
        reference=data.reference,
        n_per_combination=cfg.n_per_combination,
        n_repeats=cfg.n_repeats,
    )
    return train_many(runs(cfg, data), then=then, processes=processes, progress=progress)
