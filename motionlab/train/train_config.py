"""The training configuration: everything that decides the trained weights, validated when built."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from motionlab import config
from motionlab.checkpoints import config_dict
from motionlab.train.schedules import Schedule
from motionlab.validation import Checked, instance, integer, real, tuple_of

#: The types of the numeric fields: plain Python numbers, since the fields go into the cache key (JSON).
_NUMBER = (int, float)


def _check_schedule(name: str, schedule: Any) -> None:
    if not (dataclasses.is_dataclass(schedule) and not isinstance(schedule, type) and callable(schedule)):
        raise TypeError(
            f"TrainConfig.{name} must be a schedule dataclass from motionlab.train.schedules (or one "
            "like them), "
            f"got {type(schedule).__name__}"
        )


#: Validation passes over a run that validates (:func:`validation_every`): enough points for its held-out
#: curve and for :func:`~motionlab.train.reference.levelling`'s tenths and fifths.
VALIDATIONS = 40

#: The fewest steps between two validation passes. A pass covers every validation window, a step one batch,
#: so a run of a few dozen steps (the quick profile's) that validated at every step would spend most of its
#: time validating; runs of 160 steps or more are not affected.
MIN_VALIDATION_SPACING = 4


def validation_every(steps: int, passes: int = VALIDATIONS) -> int:
    """The ``val_every`` that spreads ``passes`` validation passes evenly over a run of ``steps``, but no
    closer than :data:`MIN_VALIDATION_SPACING` steps apart (a shorter run validates once, at its end)."""
    for value, name in ((steps, "steps"), (passes, "passes")):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"validation_every: {name} must be an integer >= 1, got {value!r}")
    return max(steps // passes, min(steps, MIN_VALIDATION_SPACING))


def schedule_config(schedule: Schedule) -> dict[str, Any]:
    """A schedule as a hashable dict: its class name and its fields."""
    return {"kind": type(schedule).__name__, **config_dict(schedule)}


@dataclass(frozen=True)
class TrainConfig(Checked):
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
        val_every: validate every this many steps (and always at the end, when validation data is given),
            each pass with the schedules at their last values (the objective the run ends with).
        log_every: the progress bar shows term means over this many steps.
        checkpoint_every: write the resumable state every this many steps (``None``: only on interruption).
        seed: seeds the global RNGs at the start and the order of the batches of every epoch.

    ``log_every`` and ``checkpoint_every`` do not change the trained weights and stay out of
    :meth:`identity`, so changing them does not invalidate a cached model.
    """

    steps: int | None = integer(None, minimum=1, kind=int, optional=True)
    epochs: int | None = integer(None, minimum=1, kind=int, optional=True)
    batch_size: int = integer(64, minimum=1, kind=int)
    lr: float = real(1e-3, above=0, kind=_NUMBER)
    weight_decay: float = real(0.0, minimum=0, kind=_NUMBER)
    betas: tuple[float, float] = tuple_of((0.9, 0.999), minimum=0, below=1, kind=_NUMBER, length=2)
    grad_clip: float | None = real(1.0, above=0, kind=_NUMBER, optional=True)
    schedules: dict[str, Schedule] = instance(dict, default_factory=dict)
    lr_schedule: Schedule | None = None
    val_every: int | None = integer(None, minimum=1, kind=int, optional=True)
    log_every: int = integer(50, minimum=1, kind=int)
    checkpoint_every: int | None = integer(500, minimum=1, kind=int, optional=True)
    seed: int = config.seed_field()

    def __post_init__(self) -> None:
        super().__post_init__()
        if (self.steps is None) == (self.epochs is None):
            raise ValueError(
                f"TrainConfig: set exactly one of steps and epochs, got steps={self.steps}, "
                f"epochs={self.epochs}"
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
