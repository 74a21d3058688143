"""Load-or-train through the checkpoint cache (:mod:`motionlab.checkpoints`), with resumable runs.

A run is identified by its name and :func:`run_identity`: the model config, the training config's
:meth:`~motionlab.train.train_config.TrainConfig.identity` and an optional data config (the batch source
itself is not hashed: put what defines the data into ``data_config``). The cache entry
``<name>-<hash>.pt`` holds the weights with ``extra = {"history": ..., "metrics": ...}``; while a run is
in progress its resumable state lives next to it in ``<name>-<hash>.resume.pt``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterable
from dataclasses import replace
from pathlib import Path
from typing import Any, TypeVar

import torch
from torch import nn

from motionlab.checkpoints import (
    CheckpointRefused,
    checkpoint_path,
    config_dict,
    load_checkpoint,
    save_checkpoint,
)
from motionlab.train import reference
from motionlab.train.batches import BatchSource
from motionlab.train.history import History
from motionlab.train.loop import Callback, LossFn, TrainResult, train
from motionlab.train.runtime import current as current_execution
from motionlab.train.state import ResumeFile
from motionlab.train.train_config import TrainConfig

M = TypeVar("M", bound=nn.Module)


def run_identity(
    model_config: Any, train_config: TrainConfig, data_config: Any | None = None
) -> dict[str, Any]:
    """The hashed description of a training run (model config, training config, data config)."""
    if not isinstance(train_config, TrainConfig):
        raise TypeError(f"train_config must be a TrainConfig, got {type(train_config).__name__}")
    return {
        "model": config_dict(model_config),
        "train": train_config.identity(),
        "data": None if data_config is None else config_dict(data_config),
    }


def resume_path(name: str, identity: dict[str, Any]) -> Path:
    """``<name>-<hash>.resume.pt`` beside the cache entry of the run."""
    return checkpoint_path(name, identity).with_suffix(".resume.pt")


def build_seeded(factory: Callable[[], M], seed: int) -> M:
    """``factory()`` (a model's constructor) with torch's global RNG seeded by ``seed``, inside a fork.

    A model's initial weights then depend on its config alone, not on what ran before it (a notebook's
    earlier cells, or a worker process's other jobs); the caller's random state is left as it was.
    """
    with torch.random.fork_rng():
        torch.manual_seed(seed)
        return factory()


def is_cached(
    name: str, model_config: Any, train_config: TrainConfig, data_config: Any | None = None
) -> bool:
    """Whether :func:`train_or_load` with these arguments would load a reference model or a cache entry
    (and not train)."""
    identity = run_identity(model_config, train_config, data_config)
    return reference.find(name, identity) is not None or checkpoint_path(name, identity).exists()


def _cached_result(name: str, identity: dict[str, Any], model: nn.Module) -> TrainResult | None:
    """The run's reference model (full profile) or cache entry, loaded into ``model``; ``None`` (model
    untouched) when there is neither or the cache entry is unusable. A reference model that does not fit
    raises (:class:`~motionlab.train.reference.ReferenceError`), it is never replaced by a retraining."""
    backup = {k: v.detach().clone() for k, v in model.state_dict().items()}
    shipped = reference.find(name, identity)
    # a reference model is checked against its manifest's identity (the run's, but for its data's last bits)
    expected = identity if shipped is None else reference.read_manifest(shipped)["config"]
    try:
        extra = load_checkpoint(name, expected, model, path=shipped, refuse=shipped is not None)
    except CheckpointRefused as exc:
        raise reference.ReferenceError(f"{exc} (retrain it with `make reference`)") from None
    if extra is None:
        return None
    reference.note_use(name, identity, shipped)
    try:
        history = History.from_dict(extra["history"])
        metrics = {str(k): float(v) for k, v in extra["metrics"].items()}
        if not all(math.isfinite(v) for v in metrics.values()):
            raise ValueError("a metric is not finite")
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        model.load_state_dict(backup)
        warnings.warn(
            f"ignoring cache entry for {name!r} (retraining): its history or metrics are malformed: {exc}",
            stacklevel=3,
        )
        return None
    return TrainResult(
        history, metrics, loaded_from_cache=True, path=shipped or checkpoint_path(name, identity)
    )


def load_cached(
    name: str, model_config: Any, train_config: TrainConfig, data_config: Any | None, model: nn.Module
) -> TrainResult | None:
    """The cached run of these configs loaded into ``model`` (left in eval mode), or ``None`` (``model``
    untouched) when the cache holds no usable entry: what :func:`train_or_load` does before training."""
    cached = _cached_result(name, run_identity(model_config, train_config, data_config), model)
    if cached is not None:
        model.eval()
    return cached


def train_or_load(
    name: str,
    model_config: Any,
    model: nn.Module,
    loss_fn: LossFn,
    data: BatchSource,
    train_config: TrainConfig,
    *,
    data_config: Any | None = None,
    val_data: BatchSource | None = None,
    progress: bool | None = None,
    callbacks: Iterable[Callback] = (),
) -> TrainResult:
    """Load the cached weights of this run into ``model``, or train it (resuming an interrupted run) and cache
    it.

    Args:
        name: a simple identifier of the run, e.g. ``"mcell_vae"``.
        model_config: the model's config dataclass (or a dict); part of the cache key.
        model: a freshly built model; updated in place and left in ``eval()`` mode.
        loss_fn, data, val_data, progress, callbacks: as for :func:`~motionlab.train.loop.train`.
        train_config: the :class:`TrainConfig`; its :meth:`~TrainConfig.identity` is part of the cache key.
        data_config: what defines the data (a dataclass or dict), part of the cache key when given.

    Returns:
        :class:`TrainResult`; ``loaded_from_cache`` says whether training was skipped. A missing, corrupt
        or mismatching entry is retrained, never half-loaded.
    """
    cached = load_cached(name, model_config, train_config, data_config, model)
    if cached is not None:
        return cached
    identity = run_identity(model_config, train_config, data_config)
    resume = ResumeFile(resume_path(name, identity), identity)
    execution = current_execution()
    if not execution.resume and execution.is_main:
        resume.remove()  # the training command without --resume: start afresh
    result = train(
        model,
        loss_fn,
        data,
        train_config,
        val_data=val_data,
        progress=progress,
        callbacks=callbacks,
        resume=resume,
        desc=name,
    )
    if not execution.is_main:  # data-parallel training: the first process writes the cache entry
        return result
    path = save_checkpoint(
        name,
        identity,
        model,
        extra={
            "history": result.history.to_dict(),
            "metrics": result.metrics,
            "trained_on": reference.trained_on(),
        },
    )
    reference.note_use(name, identity)
    reference.note_trained(name)
    resume.remove()
    return replace(result, path=path)
