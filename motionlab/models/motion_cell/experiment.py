"""Chapter 04's experiment: its sizes and schedules per profile, its named training runs, training them all.

Fairness: every Table 2 model trains on the same denoised clips, with the same batch size, learning rate and
number of steps (the output-representation comparison has its own, shorter, equal budget), and is
evaluated by the same protocol (:mod:`.evaluate`). Every run is seeded by its own configs, so its weights
do not depend on the process that trained it or on the order of the runs.

The chapter's steps::

    evaluators = prepare_evaluators(("conv", "gru"))  # in two workers, while the denoiser trains here
    data = prepare_training_data(benchmark.train, benchmark.val, cfg)
    gru = evaluators.result()["gru"].model
    trained = train_all(cfg, data, gru, gru.features(benchmark.train.positions))
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, replace
from functools import partial

import torch
from torch import Tensor, nn

from motionlab import config
from motionlab.evaluation.benchmark import benchmark_evaluator
from motionlab.evaluation.evaluator import Evaluator
from motionlab.models.motion_cell.baselines import BaselineConfig, FrameBaseline, baseline_loss
from motionlab.models.motion_cell.data import PoseCodec
from motionlab.models.motion_cell.denoise import DenoiserConfig, PreparedData
from motionlab.models.motion_cell.evaluate import ModelEvaluation, evaluate_model
from motionlab.models.motion_cell.heads import OUTPUT_KINDS
from motionlab.models.motion_cell.losses import ClassifierLoss, LossConfig, motion_cell_loss
from motionlab.models.motion_cell.model import MotionCellConfig, MotionCellModel
from motionlab.train import KLAnneal, LinearRamp, TrainConfig, TrainResult, build_seeded, train_or_load
from motionlab.train import is_cached as cache_entry_exists
from motionlab.train.many import Trained, train_many
from motionlab.train.schedules import Schedule
from motionlab.validation import check_scalar, instance, integer, real

#: The rows of the paper's Table 2 (run name -> label): the Motion Cell, its ablations, the baselines.
TABLE = {
    "mcell": "Motion Cell",
    "nc": "NC (no classifier loss)",
    "nl": "NL (all alpha_k = 1)",
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
    steps: int = integer(200, minimum=10)  # the schedules need 10 steps
    representation_steps: int = integer(60, minimum=10)
    collapse_steps: int = integer(1000, minimum=10)
    denoiser_steps: int = integer(400, minimum=1)
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
    def full(cls) -> ExperimentConfig:
        """The reported models (the defaults)."""
        return cls()

    @classmethod
    def long(cls) -> ExperimentConfig:
        """A longer, larger run for the training command (``python -m motionlab.train motion_cell --config
        long``): the Motion Cell at :class:`MotionCellConfig`'s own sizes (hidden 128, words of 64), 20 times
        the full profile's steps (6,000; the output heads 1,600; the longer mean-collapse runs 10,000); the
        same denoiser and evaluation as :meth:`full`."""
        return cls(
            motion_cell=MotionCellConfig(), steps=6_000, representation_steps=1_600, collapse_steps=10_000
        )


def learning_rate_decay(steps: int) -> LinearRamp:
    """The learning-rate factor of every run: 1 for the first 60% of the steps, then linear down to 0.1."""
    check_scalar(steps, "steps", "learning_rate_decay", kind=numbers.Integral, minimum=1)
    return LinearRamp(int(0.6 * steps), steps - int(0.6 * steps), 1.0, 0.1)


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


@dataclass(frozen=True, eq=False)
class MotionCellRun:
    """One training run of the chapter (a :class:`~motionlab.train.many.Run`): a Motion Cell (or ablation,
    or output head) or a baseline on the denoised training data.

    Attributes:
        name: the checkpoint's name; model, loss, train_config: the model, loss and training configs;
        data: the denoised training data (its fingerprint and the window length enter the cache key).
    """

    name: str
    model: MotionCellConfig | BaselineConfig
    loss: LossConfig
    train_config: TrainConfig
    data: PreparedData

    @property
    def uses_classifier(self) -> bool:
        """Whether the run trains with the classifier loss of eq. 24 (and so needs the conv evaluator)."""
        ramp = self.train_config.schedules.get("classifier")
        return ramp is not None and ramp(self.train_config.steps) > 0

    def _cache_key(self) -> tuple[dict, TrainConfig, dict]:
        data_config = {"poses": self.data.fingerprint, "window": self.data.batches.length}
        return {"model": self.model, "loss": self.loss}, self.train_config, data_config

    def is_cached(self) -> bool:
        model_config, train_config, data_config = self._cache_key()
        return cache_entry_exists(self.name, model_config, train_config, data_config)

    def _classifier_loss(self) -> ClassifierLoss:
        """Eq. 24's loss with the benchmark's frozen conv evaluator, its layer weights taken from the
        (denoised) training clips."""
        batches, codec = self.data.batches, self.data.codec
        with torch.no_grad():
            positions = codec.positions(batches.poses, batches.body)
        return ClassifierLoss(benchmark_evaluator("conv", progress=False), positions)

    def train(self, progress: bool | None = None) -> tuple[nn.Module, TrainResult]:
        """Train the model (or load it from the checkpoint cache).

        The classifier loss, which needs the conv evaluator (cached by
        :func:`~motionlab.evaluation.benchmark.prepare_evaluators`), is built only when the run trains, so
        loading a model costs no evaluator and no pass over the training clips.
        """
        if isinstance(self.model, BaselineConfig):
            loss_fn = baseline_loss(self.loss)
        else:
            classifier = self._classifier_loss() if self.uses_classifier and not self.is_cached() else None
            loss_fn = motion_cell_loss(self.loss, classifier)
        model = build_model(self.model, self.data.codec, self.train_config.seed)
        model_config, train_config, data_config = self._cache_key()
        result = train_or_load(
            self.name,
            model_config,
            model,
            loss_fn,
            self.data.batches,
            train_config,
            data_config=data_config,
            progress=progress,
        )
        return model, result


def runs(cfg: ExperimentConfig, data: PreparedData) -> dict[str, MotionCellRun]:
    """The chapter's runs by name, the longest first: the Motion Cell and ERD trained ``collapse_steps``
    (``mcell_long``, ``erd_long``), the Motion Cell and its ablations (SL, NL, NC), the baselines, and the
    three output heads (``output_quaternion`` ...)."""
    mc, steps = cfg.motion_cell, cfg.steps

    def run(
        name: str, model: MotionCellConfig | BaselineConfig, loss: LossConfig, steps: int, schedules: dict
    ) -> MotionCellRun:
        train = TrainConfig(
            steps=steps,
            batch_size=cfg.batch_size,
            lr=cfg.lr,
            schedules=schedules,
            lr_schedule=learning_rate_decay(steps),
            checkpoint_every=None,
        )
        return MotionCellRun(f"mcell_{name}", model, loss, train, data)

    def variant(
        name: str, model: MotionCellConfig, loss: LossConfig, classifier: float, steps: int = steps
    ) -> MotionCellRun:
        schedules = motion_cell_schedules(steps, cfg.beta, classifier, cfg.word_drop)
        return run(name, model, loss, steps, schedules)

    def baseline(kind: str, schedules: dict, name: str | None = None, steps: int = steps) -> MotionCellRun:
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

    def erd(steps: int, name: str = "erd") -> MotionCellRun:
        noise = LinearRamp(0, int(0.6 * steps), 0.0, cfg.input_noise)
        return baseline("erd", {"input_noise": noise}, name, steps)

    def output_head(kind: str) -> MotionCellRun:
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


def train_all(
    cfg: ExperimentConfig,
    data: PreparedData,
    evaluator: Evaluator | None = None,
    reference: Tensor | None = None,
    processes: int = 2,
    progress: bool | None = None,
) -> dict[str, Trained[ModelEvaluation | None]]:
    """Train (or load) every run of :func:`runs`, ``processes`` at a time in worker processes.

    The conv evaluator must be cached first (the classifier loss loads it). With ``evaluator`` (the
    benchmark's GRU evaluator) and ``reference`` (its features of the training clips ``(N, D)``), every
    Table 2 model is measured in a worker as soon as it is trained: :attr:`Trained.measured` is its
    :class:`~.evaluate.ModelEvaluation` (``None`` for the output-head runs).
    """
    if (evaluator is None) != (reference is None):
        raise ValueError("train_all: give both evaluator and reference, or neither")
    then = None
    if evaluator is not None:
        then = partial(
            table_row,
            evaluator=evaluator,
            reference=reference,
            n_per_combination=cfg.n_per_combination,
            n_repeats=cfg.n_repeats,
        )
    return train_many(runs(cfg, data), then=then, processes=processes, progress=progress)
