"""Chapter 06's experiment: the data, the model sizes and schedules per profile, and the training calls.

The notebook, the benchmark and the tests share these, so the numbers they report belong to the same
models. Everything here goes through the course's one training loop and its checkpoint cache.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import torch
from torch import Tensor

from motionlab import config
from motionlab.data.synthetic import load_or_generate
from motionlab.evaluation.benchmark import Benchmark
from motionlab.models.moglow.baseline import GaussianAR
from motionlab.models.moglow.config import GaussianARConfig, MoGlowConfig
from motionlab.models.moglow.data import MoGlowDataConfig, MoGlowFeatures, clip_features
from motionlab.models.moglow.generate import seed_features, splice_controls
from motionlab.models.moglow.model import MoGlow
from motionlab.models.moglow.training import PreparedData, data_identity, nll_per_frame_loss, prepare_data
from motionlab.train import (
    PiecewiseLinear,
    TensorBatches,
    TrainConfig,
    TrainResult,
    build_seeded,
    is_cached,
    train_or_load,
)
from motionlab.train.parallel import run_in_workers

#: Walk and jog as in the paper, plus wave: the only action of our data set that stands in place, so
#: that "stand still" is a command the models have seen.
DATA = MoGlowDataConfig(actions=("walk", "jog", "wave"))

#: Frames per training window (``tau`` history frames, then the frames whose likelihood is trained).
WINDOW = 45
STRIDE = 10

#: The dropout rates compared; the paper used 0.95.
DROPOUT_RATES = (0.0, 0.5, 0.95)


def moglow_config(dropout: float) -> MoGlowConfig:
    """The chapter's MoGlow for the active profile (tiny in the quick profile)."""
    return MoGlowConfig(
        steps=config.choose(quick=2, full=4),
        hidden=config.choose(quick=8, full=64),
        cond_features=config.choose(quick=8, full=64),
        dropout=dropout,
    )


def baseline_config(dropout: float = 0.0) -> GaussianARConfig:
    """The chapter's Gaussian autoregressive LSTM for the active profile."""
    return GaussianARConfig(hidden=config.choose(quick=16, full=256), dropout=dropout)


def _train_config(steps: int, lr: float) -> TrainConfig:
    return TrainConfig(
        steps=steps,
        batch_size=32,
        lr=lr,
        grad_clip=5.0,
        lr_schedule=PiecewiseLinear(((0, 1.0), (steps, 0.05))),
    )


def moglow_train_config() -> TrainConfig:
    """AdamW, linear decay of the learning rate to 5 %; 500 steps in the full profile."""
    return _train_config(config.choose(quick=12, full=500), 2e-3)


def baseline_train_config() -> TrainConfig:
    """As :func:`moglow_train_config`, with 300 steps and a smaller learning rate (the LSTM trains faster)."""
    return _train_config(config.choose(quick=12, full=300), 1e-3)


def load_data(benchmark: Benchmark) -> PreparedData:
    """The chapter's training, validation and test windows (:data:`DATA`, :data:`WINDOW`, :data:`STRIDE`)."""
    return prepare_data(benchmark, DATA, WINDOW, STRIDE)


class Trained(NamedTuple):
    """A trained (or cache-loaded) model, its training result, and the RMS residual of its linear fit."""

    model: MoGlow | GaussianAR
    result: TrainResult
    linear_rms: float


def _train(
    name: str,
    model_class: type[MoGlow] | type[GaussianAR],
    cfg,
    data: PreparedData,
    train_cfg: TrainConfig,
    progress: bool | None,
) -> Trained:
    model = build_seeded(lambda: model_class(cfg), train_cfg.seed)
    linear_rms = model.initialize(data.train.pose, data.train.control)
    result = train_or_load(
        name,
        cfg,
        model,
        nll_per_frame_loss,
        TensorBatches((data.train.pose, data.train.control)),
        train_cfg,
        data_config=data_identity(DATA, WINDOW, STRIDE),
        progress=progress,
    )
    return Trained(model, result, linear_rms)


def train_moglow(data: PreparedData, dropout: float, progress: bool | None = None) -> Trained:
    """Fit the linear predictor, then train (or load) the chapter's MoGlow with history dropout
    ``dropout``."""
    cfg = moglow_config(dropout)
    return _train("moglow", MoGlow, cfg, data, moglow_train_config(), progress)


def train_baseline(data: PreparedData, dropout: float = 0.0, progress: bool | None = None) -> Trained:
    """Fit the linear predictor, then train (or load) the Gaussian autoregressive baseline."""
    cfg = baseline_config(dropout)
    return _train("moglow_gaussian_ar", GaussianAR, cfg, data, baseline_train_config(), progress)


def _train_in_worker(dropout: float | None, data: PreparedData) -> None:
    """Body of a worker process: train MoGlow with ``dropout`` (``None``: the baseline) into the cache."""
    if dropout is None:
        train_baseline(data, progress=False)
    else:
        train_moglow(data, dropout, progress=False)


def train_all(
    data: PreparedData, processes: int = 2, progress: bool | None = None
) -> tuple[dict[float, Trained], Trained]:
    """MoGlow at every rate of :data:`DROPOUT_RATES` and the Gaussian baseline, ``processes`` runs at a time.

    The runs train in worker processes (:mod:`motionlab.train.parallel`), one thread each, then every model
    is loaded here from the cache (seeded runs: the weights do not depend on where they were trained).
    Returns ``({rate: Trained}, baseline)``.
    """
    identity = data_identity(DATA, WINDOW, STRIDE)
    pending = [
        rate
        for rate in DROPOUT_RATES
        if not is_cached("moglow", moglow_config(rate), moglow_train_config(), identity)
    ]
    if not is_cached("moglow_gaussian_ar", baseline_config(), baseline_train_config(), identity):
        pending.append(None)
    run_in_workers(_train_in_worker, [(rate, data) for rate in pending], processes)
    runs = {rate: train_moglow(data, rate, progress) for rate in DROPOUT_RATES}
    return runs, train_baseline(data, progress=progress)


#: Seconds of each piece of the control test: walk, stand, jog, stand.
PIECE_SECONDS = 3.0

#: The 20-second stability test: clip length and the seed of its (generated, held-out) clips.
LONG_SECONDS = 20.0
LONG_SEED = 1


class ControlTest(NamedTuple):
    """Spliced command sequences ``control`` ``(N, T, 3)`` (m/frame, rad/frame), the seeds that start them,
    and the frame ranges of the pieces (walk, stand, jog, stand) within ``control``."""

    control: Tensor
    seed: MoGlowFeatures
    pieces: tuple[tuple[int, int], ...]


def control_test(
    clips: MoGlowFeatures,
    action: np.ndarray,
    action_names: Sequence[str],
    n: int,
    history: int,
    blend: int = 15,
    fps: int = 30,
) -> ControlTest:
    """``n`` commands spliced from held-out recorded controls: walk, stand (a wave clip), jog, stand.

    Args:
        clips: raw features of held-out clips ``(M, T, ·)`` (e.g. ``clip_features(test, DATA,
        augment=False)``). action: the action id of each clip ``(M,)``; ``action_names`` maps ids to names.
        n: how many commands (clip ``k * count // n`` of each action for command ``k``).
        history: frames of the seed (taken from the walk clip, right before its piece of control).
    """
    names = [str(a) for a in action_names]
    by_action = {
        name: np.flatnonzero(np.asarray(action) == names.index(name)) for name in ("walk", "jog", "wave")
    }
    if any(len(ids) == 0 for ids in by_action.values()):
        raise ValueError(
            f"control_test: needs walk, jog and wave clips, got counts "
            f"{ {k: len(v) for k, v in by_action.items()} }"
        )
    length = round(PIECE_SECONDS * fps)
    first = 1 + history
    if clips.control.shape[1] < first + length:
        raise ValueError(
            f"control_test: clips of {clips.control.shape[1]} frames are too short for {PIECE_SECONDS} s "
            f"pieces after {first} frames"
        )
    commands, seeds = [], []
    for k in range(n):
        walk, jog, wave = (int(by_action[a][k * len(by_action[a]) // n]) for a in ("walk", "jog", "wave"))
        pieces = [clips.control[i, first : first + length] for i in (walk, wave, jog, wave)]
        commands.append(splice_controls(pieces, blend))
        seeds.append(walk)
    step = length - blend
    bounds = tuple((i * step, i * step + step) for i in range(4))
    return ControlTest(torch.stack(commands), seed_features(clips, seeds, history), bounds)


def long_clips(n_per_mode: int) -> MoGlowFeatures:
    """Raw features of held-out 20-second walk and jog clips (generated once, cached under ``build/data``)."""
    data = load_or_generate(LONG_SEED, n_per_mode, seconds=LONG_SECONDS, split="test")
    return clip_features(
        data, MoGlowDataConfig(actions=("walk", "jog"), mirror=False, reverse_time=False), augment=False
    )
