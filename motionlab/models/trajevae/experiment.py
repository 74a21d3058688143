"""The chapter's models trained and swept on both cores, each model's sweep as soon as it has trained.

Seven training runs on two cores leave one core idle while the last run trains; :func:`train_and_sweep`
chains every run with its k sweep (:func:`~motionlab.train.parallel.run_paired`), so the sweeps of the
models that are done fill that core. The sweep of a model loads it from the checkpoint cache and is seeded
as an in-process :func:`~motionlab.models.trajevae.evaluate.sweep_given_joints` call, so the tables do not
depend on where or when it ran.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from torch import Tensor, nn

from motionlab.models.trajevae.data import CompletionBatches
from motionlab.models.trajevae.evaluate import N_SAMPLES, Sweep, sweep_given_joints
from motionlab.models.trajevae.training import ModelConfig, completion_data_config, train_completion_model
from motionlab.train import TrainConfig, TrainResult, is_cached
from motionlab.train.parallel import run_paired


def _train_in_worker(
    name: str, cfg: ModelConfig, positions: Tensor, rotations: Tensor, train_config: TrainConfig
) -> float:
    """Body of a worker call: train one model into the checkpoint cache, return its training seconds."""
    _, result = train_completion_model(name, cfg, positions, rotations, train_config, progress=False)
    return result.metrics["train_seconds"]


def _sweep_in_worker(
    name: str,
    cfg: ModelConfig,
    positions: Tensor,
    rotations: Tensor,
    train_config: TrainConfig,
    windows: Tensor,
    ks: Sequence[int],
    multimodal: Sequence[np.ndarray],
) -> Sweep:
    """Body of a worker call: load the trained model from the cache (its chain trained it) and sweep it over
    ``ks``."""
    model, _ = train_completion_model(name, cfg, positions, rotations, train_config, progress=False)
    return sweep_given_joints(model, windows, ks, N_SAMPLES, 0, multimodal)


def train_and_sweep(
    runs: dict[str, ModelConfig],
    positions: Tensor,
    rotations: Tensor,
    train_config: TrainConfig,
    windows: Tensor,
    ks: dict[str, Sequence[int]],
    multimodal: Sequence[np.ndarray],
    processes: int = 2,
) -> tuple[dict[str, nn.Module], dict[str, TrainResult], dict[str, float], dict[str, Sweep]]:
    """Train (or load) every ``{cache name: config}`` of ``runs`` and sweep it, ``processes`` calls at a time.

    Args:
        positions, rotations, train_config: as for
        :func:`~motionlab.models.trajevae.training.train_completion_model`. windows: the test windows ``(N, T,
        J * 3)``; ks: the given-trajectory counts of each run's sweep; multimodal:
        :func:`~motionlab.models.trajevae.evaluate.multimodal_futures` of the windows.

    Returns:
        The models and their training results (loaded here from the cache), the training seconds of the runs
        trained now, and each run's sweep ``{k: {metric: (mean, ci95)}}``; all keyed like ``runs``.
    """
    data_config = completion_data_config(CompletionBatches(positions, rotations, augment=False).positions)
    trainings = {
        name: (_train_in_worker, (name, cfg, positions, rotations, train_config))
        for name, cfg in runs.items()
        if not is_cached(name, cfg, train_config, data_config)
    }
    sweeps = {
        name: (
            _sweep_in_worker,
            (name, cfg, positions, rotations, train_config, windows, ks[name], multimodal),
        )
        for name, cfg in runs.items()
    }
    seconds, sweeps = run_paired(trainings, sweeps, processes)
    models, results = {}, {}
    for name, cfg in runs.items():
        models[name], results[name] = train_completion_model(name, cfg, positions, rotations, train_config)
    return models, results, seconds, sweeps
