"""Chapter 10's MoGlow on recorded motion: MoGlow and the Gaussian autoregressive baseline on the CMU clips of
Walk and Run, in the shape every family has for the training command (``python -m motionlab.apps.training
moglow_cmu``): :data:`CHAPTER`, :data:`DEFAULT_RUN`, :class:`ExperimentConfig` (``quick()``, ``full()``,
``long()``), :func:`load_data`, :func:`runs`, :func:`measure`, :func:`with_steps` and :func:`train_all`.

**Splits.** ODMO's protocol splits the clips into training and test clips only. The runs here validate while
they train (their held-out curve says whether they levelled off), so a stratified share of the *training*
clips (``val_share``) is held out for it; the test clips stay for the chapter's measurement, the held-out
likelihood per frame (:func:`measure`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from torch import nn

from motionlab import config
from motionlab.data.cmu_mocap import split_clips
from motionlab.evaluation import real
from motionlab.metrics import mean_ci
from motionlab.models.moglow.baselines import GaussianAR, GaussianARConfig
from motionlab.models.moglow.data import MoGlowDataConfig, PreparedData, prepare_real
from motionlab.models.moglow.experiment import BASELINE, autoregressive_run
from motionlab.models.moglow.losses import held_out_nll_per_window
from motionlab.models.moglow.model import MoGlow, MoGlowConfig
from motionlab.train import PiecewiseLinear, TrainConfig, validation_every
from motionlab.train.many import Trained, train_many
from motionlab.train.run import Run
from motionlab.validation import instance, integer
from motionlab.validation import real as real_number

#: The chapter that trains this family, and its main run (the training command's default).
CHAPTER, DEFAULT_RUN = "10_real_motion_capture", "MoGlow"

#: ``load_data`` reads a folder of clips given as ``--data PATH``.
READS_FOLDER = True


@dataclass(frozen=True)
class ExperimentConfig(config.ProfileConfig):
    """MoGlow and the Gaussian autoregressive baseline on the CMU clips of Walk and Run (about 12 fps); the
    defaults are the full profile (:meth:`full`: MoGlow 30,000 steps, about 9 minutes on one core, by which
    its held-out likelihood still improves; the baseline 40,000, about 6 minutes, by which its own has
    levelled off).

    Attributes:
        n_clips: the benchmark clips kept (a stratified subset; ``None``: all 970), as chapter 10's
            ``RealExperimentConfig.n_clips``.
        val_share: the share of the training clips of every class held out for the runs' validation curve
            (stratified, drawn with seed 0).
        data: the actions (names of the CMU classes) and the augmentation (mirroring and time reversal, as
            in the paper).
        window, stride: frames per training window and the step between windows.
        history: ``H`` previous poses (5 frames: 0.4 s at 12 fps, close to the paper's 10 frames at 20 fps).
        moglow_steps, moglow_hidden, cond_features, dropout: MoGlow's size and history dropout.
        baseline_hidden: the Gaussian baseline's LSTM units.
        moglow_train_steps, baseline_train_steps, lr, batch_size: AdamW training of both.
    """

    n_clips: int | None = integer(None, minimum=28, optional=True)
    val_share: float = real_number(0.15, above=0, below=1)
    data: MoGlowDataConfig = instance(MoGlowDataConfig, MoGlowDataConfig(actions=("Walk", "Run")))
    window: int = integer(20, minimum=1)
    stride: int = integer(20, minimum=1)
    history: int = integer(5, minimum=1)
    moglow_steps: int = integer(4, minimum=1)
    moglow_hidden: int = integer(64, minimum=1)
    cond_features: int = integer(64, minimum=1)
    dropout: float = real_number(0.0, minimum=0, below=1)
    baseline_hidden: int = integer(128, minimum=1)
    moglow_train_steps: int = integer(30_000, minimum=1)
    baseline_train_steps: int = integer(40_000, minimum=1)
    lr: float = real_number(2e-3, above=0)
    batch_size: int = integer(32, minimum=1)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.window <= self.history:
            raise ValueError(
                f"ExperimentConfig: window {self.window} must be longer than history {self.history}"
            )

    @classmethod
    def quick(cls) -> ExperimentConfig:
        """Tiny models, 6 steps, on chapter 10's quick subset of 112 clips: the code paths."""
        return cls(
            n_clips=112,
            moglow_steps=2,
            moglow_hidden=8,
            cond_features=8,
            baseline_hidden=16,
            moglow_train_steps=6,
            baseline_train_steps=6,
        )

    @classmethod
    def long(cls) -> ExperimentConfig:
        """A longer run: 8 Glow steps (the paper's 16 at a GPU's budget), twice the steps."""
        return cls(moglow_steps=8, moglow_train_steps=60_000, baseline_train_steps=80_000)

    def schedule(self, steps: int) -> TrainConfig:
        """AdamW with the learning rate decaying linearly to 5 % by the last of ``steps``, validating 40
        times."""
        return TrainConfig(
            steps=steps,
            batch_size=self.batch_size,
            lr=self.lr,
            grad_clip=5.0,
            lr_schedule=PiecewiseLinear(((0, 1.0), (steps, 0.05))),
            val_every=validation_every(steps),
        )

    def moglow(self, pose_dim: int, control_dim: int) -> MoGlowConfig:
        """MoGlow for poses of ``pose_dim`` and controls of ``control_dim`` channels."""
        return MoGlowConfig(
            pose_dim=pose_dim,
            control_dim=control_dim,
            history=self.history,
            steps=self.moglow_steps,
            hidden=self.moglow_hidden,
            cond_features=self.cond_features,
            dropout=self.dropout,
        )

    def baseline(self, pose_dim: int, control_dim: int) -> GaussianARConfig:
        """The Gaussian autoregressive LSTM (no history dropout)."""
        return GaussianARConfig(
            pose_dim=pose_dim,
            control_dim=control_dim,
            history=self.history,
            hidden=self.baseline_hidden,
            dropout=0.0,
        )


@dataclass(frozen=True)
class ChapterData:
    """The prepared windows (training windows augmented; validation windows from the held-out training clips;
    the test clips' windows) and what identifies the training clips, for the cache key."""

    windows: PreparedData
    clips_identity: dict[str, Any]


def prepare(cfg: ExperimentConfig, bench: real.RealBenchmark) -> ChapterData:
    """Split ``cfg.val_share`` of the training clips of ``cfg.data.actions`` off for validation (stratified,
    seed 0), then window and standardise the three parts (:func:`~.data.prepare_real`, scalers fitted on the
    remaining training windows)."""
    names = list(bench.train.action_names)
    unknown = [a for a in cfg.data.actions if a not in names]
    if unknown:
        raise ValueError(f"prepare: unknown actions {unknown}; the clips have {names}")
    wanted = np.isin(bench.train.action, [names.index(a) for a in cfg.data.actions])
    fit, val = split_clips(bench.train.subset(np.flatnonzero(wanted)), cfg.val_share, 0)
    windows = prepare_real(fit, bench.test, cfg.data, cfg.window, cfg.stride, val=val)
    return ChapterData(windows, real.clips_fingerprint(bench.train))


def load_data(cfg: ExperimentConfig, folder: Path | None = None) -> ChapterData:
    """Chapter 10's clips (floors levelled, stratified train/test split; ``folder``: a downloaded
    Action2Motion folder instead of the compact copy), prepared by :func:`prepare`."""
    if not isinstance(cfg, ExperimentConfig):
        raise TypeError(f"load_data: cfg must be an ExperimentConfig, got {type(cfg).__name__}")
    return prepare(cfg, real.load_real_benchmark(cfg.n_clips, source=folder))


def runs(cfg: ExperimentConfig, data: ChapterData) -> dict[str, Run]:
    """MoGlow (:data:`DEFAULT_RUN`, cached as ``real_moglow``) and the Gaussian baseline (``real_moglow_
    gaussian_ar``), each validating on the held-out training clips; the cache key holds the training clips'
    identity, the validation share and the window settings."""
    windows = data.windows
    pose_dim, control_dim = windows.train.pose.shape[-1], windows.train.control.shape[-1]
    identity = {
        "clips": data.clips_identity,
        "val_share": cfg.val_share,
        "data": asdict(cfg.data),
        "window": cfg.window,
        "stride": cfg.stride,
    }
    return {
        DEFAULT_RUN: autoregressive_run(
            "real_moglow",
            MoGlow,
            cfg.moglow(pose_dim, control_dim),
            cfg.schedule(cfg.moglow_train_steps),
            windows,
            identity,
        ),
        BASELINE: autoregressive_run(
            "real_moglow_gaussian_ar",
            GaussianAR,
            cfg.baseline(pose_dim, control_dim),
            cfg.schedule(cfg.baseline_train_steps),
            windows,
            identity,
        ),
    }


def train_all(
    cfg: ExperimentConfig, data: ChapterData, processes: int | None = None, progress: bool | None = None
) -> dict[str, Trained]:
    """Train (or load) both runs, ``processes`` at a time, and return them by name."""
    return train_many(runs(cfg, data), processes=processes, progress=progress)


def measure(cfg: ExperimentConfig, data: ChapterData, name: str, model: nn.Module) -> dict[str, Any]:
    """The run's held-out NLL per frame (nats) over the test clips' windows, with its 95 % interval."""
    mean, half = mean_ci(held_out_nll_per_window(model, data.windows.test).numpy())
    return {"test_nll_per_frame": {"mean": float(mean), "ci95": float(half)}}


def with_steps(cfg: ExperimentConfig, name: str, steps: int) -> ExperimentConfig:
    """``cfg`` with run ``name`` trained for ``steps`` steps."""
    return replace(cfg, **{"baseline_train_steps" if name == BASELINE else "moglow_train_steps": steps})
