"""Chapter 06's experiment: one config per profile, the named training runs, and the call that trains them.

The notebook, the benchmark and the tests share these, so the numbers they report belong to the same
models. Every run goes through the course's one training loop and its checkpoint cache
(:func:`motionlab.train.train_or_load`), and :func:`train_all` through
:func:`motionlab.train.many.train_many`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial
from typing import Any

from torch import nn

from motionlab import config
from motionlab.evaluation.benchmark import Benchmark, load_benchmark
from motionlab.metrics import mean_ci
from motionlab.models.moglow.baselines import GaussianAR, GaussianARConfig
from motionlab.models.moglow.data import (
    MoGlowDataConfig,
    PreparedData,
    clip_features,
    data_identity,
    prepare_data,
    select_actions,
)
from motionlab.models.moglow.evaluate import control_test, run_control_test
from motionlab.models.moglow.losses import held_out_nll_per_window, nll_per_frame_loss
from motionlab.models.moglow.model import MoGlow, MoGlowConfig
from motionlab.train import PiecewiseLinear, TensorBatches, TrainConfig, build_seeded, validation_every
from motionlab.train.many import Trained, train_many
from motionlab.train.run import Run, given
from motionlab.validation import instance, integer, real, tuple_of

#: The run name of the Gaussian autoregressive baseline in :func:`runs`.
BASELINE = "Gaussian AR"


def moglow_name(dropout: float, rescale: bool = True) -> str:
    """The run name of MoGlow with history dropout ``dropout`` in :func:`runs`, e.g. ``"MoGlow p=0.5"``, or
    ``"MoGlow p=0.95 unscaled"`` for the variant that does not rescale the kept poses."""
    return f"MoGlow p={dropout}" if rescale else f"MoGlow p={dropout} unscaled"


@dataclass(frozen=True)
class ExperimentConfig(config.ProfileConfig):
    """Every size, step count and schedule of chapter 06: the defaults are the full profile (:meth:`full`),
    as the course runs it (MoGlow 20,000 steps, about 12 minutes per model on one CPU thread, by which MoGlow
    p=0.95's held-out likelihood has levelled off; the baseline 12,000, by which its own has); :meth:`quick`
    is tiny.

    Attributes:
        data: which clips and which augmentation. Walk and jog as in the paper, plus wave: the only action
            of our data set that stands in place, so that "stand still" is a command the models have seen.
        window, stride: frames per training window (``H`` history frames, then the frames whose
            likelihood is trained) and the step between windows.
        dropout_rates: MoGlow's history dropout rates compared (the paper used 0.95), with the kept poses
            rescaled by ``1 / (1 - p)`` in training (standard inverted dropout).
        unscaled_rates: rates also trained without that rescaling (the authors' released code), to show
            what it does once the dropout is switched off for generation.
        moglow_steps, moglow_hidden, cond_features: MoGlow's Glow steps ``K``, LSTM units per coupling and
            shared conditioning features (:class:`~.model.MoGlowConfig`).
        baseline_hidden: the Gaussian baseline's LSTM units.
        moglow_train_steps, moglow_lr, baseline_train_steps, baseline_lr: optimiser steps and learning rates
            (AdamW; the baseline's LSTM trains faster).
        batch_size, grad_clip, final_lr_factor: shared by both: windows per batch, gradient-norm clip, and
            the factor the learning rate decays to, linearly, by the last step.
        glow_steps_per_level, glow_hidden, glow_train_steps: the fixed-length Glow of :mod:`.fixed_length`
            (chapter 05 trains it, this chapter compares with it).
        n_commands: spliced command sequences in the control test (:func:`~.evaluate.control_test`), each
            of four pieces of ``piece_seconds``.
        n_long, long_seconds, long_seed: held-out clips per walk/jog style of the stability test, their
            length and the seed they are generated from (:func:`~.evaluate.long_clips`).
        n_repeats: sample sets for the evaluation-classifier metrics.
        bench_batch: the large batch of the chapter's generation-speed measurement.
        small_flow_steps: training steps of the small conditional flow the chapter writes in the notebook.
    """

    data: MoGlowDataConfig = instance(MoGlowDataConfig, MoGlowDataConfig(actions=("walk", "jog", "wave")))
    window: int = integer(45, minimum=1)
    stride: int = integer(10, minimum=1)
    dropout_rates: tuple[float, ...] = tuple_of((0.0, 0.5, 0.95), minimum=0, below=1, nonempty=True)
    unscaled_rates: tuple[float, ...] = tuple_of((0.95,), minimum=0, below=1)
    moglow_steps: int = integer(4, minimum=1)
    moglow_hidden: int = integer(64, minimum=1)
    cond_features: int = integer(64, minimum=1)
    baseline_hidden: int = integer(256, minimum=1)
    moglow_train_steps: int = integer(20_000, minimum=1)
    moglow_lr: float = real(2e-3, above=0)
    baseline_train_steps: int = integer(12_000, minimum=1)
    baseline_lr: float = real(1e-3, above=0)
    batch_size: int = integer(32, minimum=1)
    grad_clip: float = real(5.0, above=0)
    final_lr_factor: float = real(0.05, minimum=0)
    glow_steps_per_level: int = integer(4, minimum=1)
    glow_hidden: int = integer(64, minimum=1)
    glow_train_steps: int = integer(300, minimum=1)
    n_commands: int = integer(8, minimum=1)
    piece_seconds: float = real(3.0, above=0)
    n_long: int = integer(2, minimum=1)
    long_seconds: float = real(20.0, above=0)
    long_seed: int = integer(1, minimum=0)
    n_repeats: int = integer(3, minimum=1)
    bench_batch: int = integer(256, minimum=1)
    small_flow_steps: int = integer(300, minimum=1)

    @classmethod
    def quick(cls) -> ExperimentConfig:
        """Tiny models and a few steps (the test profile): the code paths, not the numbers."""
        return replace(
            cls(),
            moglow_steps=2,
            moglow_hidden=8,
            cond_features=8,
            baseline_hidden=16,
            moglow_train_steps=12,
            baseline_train_steps=12,
            glow_steps_per_level=1,
            glow_hidden=8,
            glow_train_steps=6,
            n_commands=2,
            n_long=1,
            n_repeats=2,
            bench_batch=8,
            small_flow_steps=60,
        )

    @classmethod
    def long(cls) -> ExperimentConfig:
        """A longer, larger run for the training command (``python -m motionlab.apps.training moglow --config
        long``): MoGlow for the paper's 80,000 steps with twice its LSTM and conditioning widths (128), the
        fixed-length Glow 6,000 steps; the baseline, data and evaluation as in :meth:`full`."""
        return replace(
            cls(),
            moglow_hidden=128,
            cond_features=128,
            moglow_train_steps=80_000,
            glow_train_steps=6_000,
        )

    def moglow(self, dropout: float, rescale: bool = True) -> MoGlowConfig:
        """The chapter's MoGlow with history dropout ``dropout`` (kept poses rescaled unless ``rescale`` is
        false)."""
        return MoGlowConfig(
            steps=self.moglow_steps,
            hidden=self.moglow_hidden,
            cond_features=self.cond_features,
            dropout=dropout,
            dropout_rescale=rescale,
        )

    def baseline(self) -> GaussianARConfig:
        """The chapter's Gaussian autoregressive LSTM (no history dropout)."""
        return GaussianARConfig(hidden=self.baseline_hidden, dropout=0.0)

    def _schedule(self, steps: int, lr: float) -> TrainConfig:
        return TrainConfig(
            steps=steps,
            batch_size=self.batch_size,
            lr=lr,
            grad_clip=self.grad_clip,
            lr_schedule=PiecewiseLinear(((0, 1.0), (steps, self.final_lr_factor))),
            val_every=validation_every(steps),  # the held-out curve: 40 passes over the validation windows
        )

    def moglow_train(self) -> TrainConfig:
        """MoGlow's training: AdamW, the learning rate decaying linearly to ``final_lr_factor``."""
        return self._schedule(self.moglow_train_steps, self.moglow_lr)

    def baseline_train(self) -> TrainConfig:
        """The baseline's training: as :meth:`moglow_train` with its own steps and learning rate."""
        return self._schedule(self.baseline_train_steps, self.baseline_lr)

    def data_identity(self) -> dict[str, Any]:
        """What defines the training windows, for the checkpoint cache key (:func:`~.data.data_identity`)."""
        return data_identity(self.data, self.window, self.stride)


def load_data(cfg: ExperimentConfig, benchmark: Benchmark | None = None) -> PreparedData:
    """The chapter's training and test windows and scalers (``cfg.data``, ``cfg.window``, ``cfg.stride``) of
    ``benchmark`` (default: the course benchmark)."""
    return prepare_data(
        load_benchmark() if benchmark is None else benchmark, cfg.data, cfg.window, cfg.stride
    )


def build_autoregressive(
    model_class: type[MoGlow] | type[GaussianAR], model_cfg: MoGlowConfig | GaussianARConfig, seed: int
) -> MoGlow | GaussianAR:
    """MoGlow or the Gaussian baseline, its weights drawn from ``seed`` (its linear predictor is fitted by
    :func:`fit_predictor` when it trains)."""
    return build_seeded(partial(model_class, model_cfg), seed)


def fit_predictor(data: PreparedData, model: MoGlow | GaussianAR) -> None:
    """Fit the linear predictor of a model about to train to the training windows (the fit's RMS residual,
    in standard units, stays on the model as ``model.linear.fit_rms``; a model loaded from the cache has
    the fitted predictor in its weights, and ``model.initialize(pose, control, solve=False)`` measures it)."""
    model.initialize(data.train.pose, data.train.control)


def training_batches(data: PreparedData, model: nn.Module) -> TensorBatches:
    """The chapter's training windows: poses and controls."""
    return TensorBatches((data.train.pose, data.train.control))


def validation_batches(data: PreparedData, model: nn.Module) -> TensorBatches:
    """The validation windows (poses and controls), every one in its order, for the run's held-out curve."""
    if data.val is None:
        raise ValueError("validation_batches: the prepared data has no validation windows (data.val is None)")
    return TensorBatches((data.val.pose, data.val.control), shuffle=False, drop_last=False)


def autoregressive_run(
    name: str,
    model_class: type[MoGlow] | type[GaussianAR],
    model_cfg: MoGlowConfig | GaussianARConfig,
    train_config: TrainConfig,
    data: PreparedData,
    data_identity: dict[str, Any],
) -> Run:
    """The :class:`~motionlab.train.run.Run` of MoGlow or of the Gaussian baseline on the chapter's windows
    (``data_identity``, what defines them, is the cache key's data part); it validates on ``data.val`` every
    ``train_config.val_every`` steps when that is set."""
    return Run(
        name,
        model_cfg,
        partial(build_autoregressive, model_class, model_cfg),
        given(nll_per_frame_loss),
        partial(training_batches, data),
        train_config,
        data_identity,
        partial(fit_predictor, data),
        None if train_config.val_every is None else partial(validation_batches, data),
    )


def runs(cfg: ExperimentConfig, data: PreparedData) -> dict[str, Run]:
    """MoGlow at every rate of ``cfg.dropout_rates`` and, unscaled, of ``cfg.unscaled_rates``
    (:func:`moglow_name`), then the Gaussian baseline (:data:`BASELINE`): the chapter's runs in the order to
    start them (MoGlow trains longest)."""
    identity = cfg.data_identity()
    variants = [(rate, True) for rate in cfg.dropout_rates] + [(rate, False) for rate in cfg.unscaled_rates]
    named = {
        moglow_name(rate, rescale): autoregressive_run(
            "moglow", MoGlow, cfg.moglow(rate, rescale), cfg.moglow_train(), data, identity
        )
        for rate, rescale in variants
    }
    named[BASELINE] = autoregressive_run(
        "moglow_gaussian_ar", GaussianAR, cfg.baseline(), cfg.baseline_train(), data, identity
    )
    return named


def train_all(
    cfg: ExperimentConfig, data: PreparedData, processes: int | None = None, progress: bool | None = None
) -> dict[str, Trained]:
    """Train (or load) every run of :func:`runs`, ``processes`` at a time, and return them by name."""
    return train_many(runs(cfg, data), processes=processes, progress=progress)


#: The chapter that trains this family, and its main run (the training command's default).
CHAPTER, DEFAULT_RUN = "06_moglow", moglow_name(0.95)


def _interval(values: Any) -> dict[str, float]:
    mean, half = mean_ci(values)
    return {"mean": float(mean), "ci95": float(half)}


def measure(cfg: ExperimentConfig, data: PreparedData, name: str, model: nn.Module) -> dict[str, Any]:
    """The training command's measurement of run ``name``: the chapter's held-out NLL per frame and the
    control test's mismatch on the zero-latent path (a diverging sample is reported, not hidden)."""
    test = load_benchmark().test
    test_set = select_actions(test, cfg.data.actions)
    test_raw = clip_features(test, cfg.data, augment=False)
    out: dict[str, Any] = {"test_nll_per_frame": _interval(held_out_nll_per_window(model, data.test).numpy())}
    names = [str(action) for action in test_set.action_names]
    history = model.cfg.history
    commands = control_test(test_raw, test_set.action, names, cfg.n_commands, history, cfg.piece_seconds)
    try:
        mismatch = run_control_test(model, data.scalers, commands, 0.0).mismatch
    except ValueError as error:
        out["control_mismatch_zero_latent"] = f"generation diverged: {error}"
        return out
    out["control_mismatch_zero_latent"] = _interval(mismatch.numpy())
    return out


def with_steps(cfg: ExperimentConfig, name: str, steps: int) -> ExperimentConfig:
    """``cfg`` with run ``name`` trained for ``steps`` steps (the baseline's ``baseline_train_steps``, every
    MoGlow's ``moglow_train_steps``)."""
    field_name = "baseline_train_steps" if name == BASELINE else "moglow_train_steps"
    return replace(cfg, **{field_name: steps})
