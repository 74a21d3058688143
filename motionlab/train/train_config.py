"""The training configuration: everything that decides the trained weights, validated when built."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

from motionlab.checkpoints import config_dict
from motionlab.train.schedules import Schedule


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _check_positive_int(name: str, value: Any, allow_none: bool = False) -> None:
    if value is None and allow_none:
        return
    if not _is_int(value) or value < 1:
        raise ValueError(
            f"TrainConfig.{name} must be a positive int{' or None' if allow_none else ''}, got {value!r}"
        )


def _check_schedule(name: str, schedule: Any) -> None:
    if not (dataclasses.is_dataclass(schedule) and not isinstance(schedule, type) and callable(schedule)):
        raise TypeError(
            f"TrainConfig.{name} must be a schedule dataclass from motionlab.train.schedules (or one "
            "like them), "
            f"got {type(schedule).__name__}"
        )


def schedule_config(schedule: Schedule) -> dict[str, Any]:
    """A schedule as a hashable dict: its class name and its fields."""
    return {"kind": type(schedule).__name__, **config_dict(schedule)}


@dataclass(frozen=True)
class TrainConfig:
    """How to train: length, optimiser (AdamW), clipping, schedules, and bookkeeping intervals.

    Attributes:
        steps: number of optimiser steps; exactly one of ``steps`` and ``epochs`` is set.
        epochs: number of passes over the batch source.
        batch_size: samples per batch; handed to a callable batch source, checked against a DataLoader's.
        lr: AdamW learning rate (times ``lr_schedule(step)`` when that is set).
        weight_decay: AdamW's decoupled weight decay (0 gives Adam).
        betas: AdamW's moment coefficients.
        grad_clip: the global gradient L2 norm is clipped to this value (``None``: no clipping).
        schedules: name -> schedule; at step ``s`` the loss function receives ``{name: schedule(s)}``.
        lr_schedule: optional factor on ``lr`` per step (e.g. a warm-up ``LinearRamp(0, 200, 0.0, 1.0)``).
        val_every: validate every this many steps (and always at the end, when validation data is given).
        log_every: the progress bar shows term means over this many steps.
        checkpoint_every: write the resumable state every this many steps (``None``: only on interruption).
        seed: seeds the global RNGs at the start and the order of the batches of every epoch.

    ``log_every`` and ``checkpoint_every`` do not change the trained weights and stay out of
    :meth:`identity`, so changing them does not invalidate a cached model.
    """

    steps: int | None = None
    epochs: int | None = None
    batch_size: int = 64
    lr: float = 1e-3
    weight_decay: float = 0.0
    betas: tuple[float, float] = (0.9, 0.999)
    grad_clip: float | None = 1.0
    schedules: dict[str, Schedule] = field(default_factory=dict)
    lr_schedule: Schedule | None = None
    val_every: int | None = None
    log_every: int = 50
    checkpoint_every: int | None = 500
    seed: int = 0

    def __post_init__(self) -> None:
        if (self.steps is None) == (self.epochs is None):
            raise ValueError(
                f"TrainConfig: set exactly one of steps and epochs, got steps={self.steps}, "
                f"epochs={self.epochs}"
            )
        _check_positive_int("steps", self.steps, allow_none=True)
        _check_positive_int("epochs", self.epochs, allow_none=True)
        _check_positive_int("batch_size", self.batch_size)
        _check_positive_int("val_every", self.val_every, allow_none=True)
        _check_positive_int("log_every", self.log_every)
        _check_positive_int("checkpoint_every", self.checkpoint_every, allow_none=True)
        if not _is_int(self.seed) or self.seed < 0:
            raise ValueError(f"TrainConfig.seed must be a non-negative int, got {self.seed!r}")
        if not isinstance(self.lr, (int, float)) or not math.isfinite(self.lr) or self.lr <= 0:
            raise ValueError(f"TrainConfig.lr must be a finite positive number, got {self.lr!r}")
        if (
            not isinstance(self.weight_decay, (int, float))
            or not math.isfinite(self.weight_decay)
            or self.weight_decay < 0
        ):
            raise ValueError(
                f"TrainConfig.weight_decay must be a finite number >= 0, got {self.weight_decay!r}"
            )
        if len(self.betas) != 2 or not all(isinstance(b, (int, float)) and 0 <= b < 1 for b in self.betas):
            raise ValueError(f"TrainConfig.betas must be two numbers in [0, 1), got {self.betas!r}")
        if self.grad_clip is not None and (
            not isinstance(self.grad_clip, (int, float))
            or not math.isfinite(self.grad_clip)
            or self.grad_clip <= 0
        ):
            raise ValueError(
                f"TrainConfig.grad_clip must be a finite positive number or None, got {self.grad_clip!r}"
            )
        if not isinstance(self.schedules, dict):
            raise TypeError(
                f"TrainConfig.schedules must be a dict name -> schedule, got {type(self.schedules).__name__}"
            )
        for name, schedule in self.schedules.items():
            if not isinstance(name, str) or not name:
                raise ValueError(f"TrainConfig.schedules: names must be non-empty strings, got {name!r}")
            _check_schedule(f"schedules[{name!r}]", schedule)
        if self.lr_schedule is not None:
            _check_schedule("lr_schedule", self.lr_schedule)

    def identity(self) -> dict[str, Any]:
        """The fields that decide the trained weights, as a JSON-ready dict (the part of the cache key)."""
        skipped = {"log_every", "checkpoint_every", "schedules", "lr_schedule"}
        identity = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in skipped}
        identity["betas"] = list(self.betas)
        identity["schedules"] = {name: schedule_config(s) for name, s in sorted(self.schedules.items())}
        identity["lr_schedule"] = None if self.lr_schedule is None else schedule_config(self.lr_schedule)
        return identity
