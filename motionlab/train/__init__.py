"""The one training loop of the course, its coefficient schedules, history and checkpoint cache.

Typical use in a chapter::

    from motionlab.train import KLAnneal, TensorBatches, TrainConfig, plot_history, train_or_load

    cfg = TrainConfig(steps=config.choose(quick=20, full=3000), batch_size=64, lr=1e-3, grad_clip=1.0,
                      schedules={"beta": KLAnneal(max_value=1.0, warmup=300, anneal=1000)})
    result = train_or_load("vae", model_cfg, model, loss_fn, TensorBatches((train_x,)), cfg)
    plot_history(result.history)

Modules: :mod:`~motionlab.train.schedules` (schedules), :mod:`~motionlab.train.train_config`
(:class:`TrainConfig`), :mod:`~motionlab.train.batches` (batch sources and their seeded order),
:mod:`~motionlab.train.loop` (:func:`train`), :mod:`~motionlab.train.state` (resumable state),
:mod:`~motionlab.train.cache` (:func:`train_or_load`), :mod:`~motionlab.train.history` and
:mod:`~motionlab.train.plot` (records and the figure), :mod:`~motionlab.train.runtime` (device, mixed
precision and data-parallel processes of a run), :mod:`~motionlab.train.run` (:class:`~.run.Run`, the one
description of a training run: its model, loss, batches, training config and cache key),
:mod:`~motionlab.train.many` (training several runs on both cores) and :mod:`~motionlab.train.live` (a run's
first steps trained in front of the reader, drawn over its reference model's record).
"""

from motionlab.train.batches import TensorBatches
from motionlab.train.cache import build_seeded, is_cached, resume_path, run_identity, train_or_load
from motionlab.train.history import History
from motionlab.train.loop import NonFiniteLossError, TrainResult, loss_terms, train
from motionlab.train.plot import plot_history
from motionlab.train.schedules import Constant, KLAnneal, LinearRamp, PiecewiseLinear, Schedule
from motionlab.train.train_config import VALIDATIONS, TrainConfig, validation_every

__all__ = [
    "build_seeded",
    "Constant",
    "History",
    "KLAnneal",
    "LinearRamp",
    "NonFiniteLossError",
    "PiecewiseLinear",
    "Schedule",
    "TensorBatches",
    "TrainConfig",
    "TrainResult",
    "VALIDATIONS",
    "is_cached",
    "loss_terms",
    "plot_history",
    "resume_path",
    "run_identity",
    "train",
    "train_or_load",
    "validation_every",
]
