"""Training several runs on both cores: the one entry point every chapter uses.

A *run* is one training of one model: a small picklable object (every model family defines its own, e.g.
``MotionCellRun``) that says whether the checkpoint cache already holds it and how to train it or load it::

    class Run(Protocol):
        def is_cached(self) -> bool: ...
        def train(self, progress: bool | None = None) -> tuple[nn.Module, TrainResult]: ...

:func:`train_many` trains the runs that are not cached in worker processes, one thread each (see
:mod:`motionlab.train.parallel`), optionally measures every model in a worker as soon as it is trained
(``then``), and finally loads every model here from the cache. Runs are seeded by their own configs, so a
model's weights do not depend on which process trained it, or when. :func:`start_training` does the same
without waiting, so a chapter can go on with its own work while the workers train.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any, Generic, Protocol, TypeVar

from torch import nn

from motionlab.train.loop import TrainResult
from motionlab.train.parallel import outcome, run_chains, shared_pool, submit

M = TypeVar("M")


class Run(Protocol):
    """One training run of one model (picklable, so that a worker process can run it)."""

    def is_cached(self) -> bool:
        """Whether :meth:`train` would load the model from the checkpoint cache instead of training it."""
        ...

    def train(self, progress: bool | None = None) -> tuple[nn.Module, TrainResult]:
        """Train the model (or load it from the cache); return it and its :class:`TrainResult`."""
        ...


@dataclass
class Trained(Generic[M]):
    """A trained model, as every model family's ``train_all`` returns it.

    Attributes:
        model: the model, loaded from the checkpoint cache (eval mode is the caller's choice).
        result: its :class:`TrainResult` (history and metrics of the run that trained it).
        seconds: training seconds if this call trained it, ``None`` if it came from the cache.
        measured: what ``then`` returned for it (see :func:`train_many`), or ``None``.
    """

    model: nn.Module
    result: TrainResult
    seconds: float | None = None
    measured: M | None = None


def _train_run(run: Run) -> float:
    """Body of a worker call: train ``run`` into the checkpoint cache, return its training seconds."""
    _, result = run.train(progress=False)
    return result.metrics["train_seconds"]


def _measure_run(run: Run, name: str, then: Callable[[str, nn.Module], Any]) -> Any:
    """Body of a worker call: load ``run``'s model from the cache (trained before) and measure it."""
    model, _ = run.train(progress=False)
    return then(name, model)


def _load_all(
    runs: Mapping[str, Run], seconds: Mapping[str, float], measured: Mapping[str, Any], progress: bool | None
) -> dict[str, Trained]:
    trained = {}
    for name, run in runs.items():
        model, result = run.train(progress=progress)
        if name not in seconds and not result.loaded_from_cache:  # trained here, now (one process)
            seconds = {**seconds, name: result.metrics["train_seconds"]}
        trained[name] = Trained(model, result, seconds.get(name), measured.get(name))
    return trained


class PendingTraining:
    """Runs that :func:`start_training` handed to the workers; :meth:`result` waits for them."""

    def __init__(self, runs: Mapping[str, Run], futures: dict[str, Future[bytes]]) -> None:
        self._runs = dict(runs)
        self._futures = futures

    def done(self) -> bool:
        """Whether every run handed to the workers has finished."""
        return all(future.done() for future in self._futures.values())

    def result(self, progress: bool | None = None) -> dict[str, Trained]:
        """Wait for the workers (raising the first failed run's exception), then load every model here."""
        seconds = {name: outcome(future) for name, future in self._futures.items()}
        return _load_all(self._runs, seconds, {}, progress)


def start_training(runs: Mapping[str, Run], processes: int = 2) -> PendingTraining:
    """Hand the runs that are not cached to ``processes`` workers and return at once.

    Runs start in the order given (put the longest first). With one process nothing starts now: the runs
    train in this process when :meth:`PendingTraining.result` is called.
    """
    futures = {}
    if processes > 1:
        pool = shared_pool(processes)
        futures = {name: submit(pool, _train_run, run) for name, run in runs.items() if not run.is_cached()}
    return PendingTraining(runs, futures)


def train_many(
    runs: Mapping[str, Run],
    then: Callable[[str, nn.Module], M] | None = None,
    processes: int = 2,
    progress: bool | None = None,
) -> dict[str, Trained[M]]:
    """Train (or load) every run, ``processes`` at a time in worker processes, and return them by name.

    Args:
        runs: ``{name: run}``; runs start in this order (put the longest first, so the last to finish is
            short).
        then: ``then(name, model)`` measures a trained model in a worker as soon as its run is done, filling
            the cores that the last trainings leave idle. It must be picklable (a module-level function or
            a ``functools.partial`` of one) and seeded by its arguments alone, so its result does not depend
            on where or when it ran. Its result is :attr:`Trained.measured`.
        processes: worker processes (one thread each); with 1 everything runs here, in order.
        progress: progress bars while loading the models here (the workers show none).

    Returns:
        ``{name: Trained}`` in the order of ``runs``, every model loaded here from the cache.
    """
    if then is None:
        return start_training(runs, processes).result(progress)
    names = list(runs)
    pending = {name for name in names if not runs[name].is_cached()}
    chains = [
        ([(_train_run, (runs[name],))] if name in pending else [])
        + [(_measure_run, (runs[name], name, then))]
        for name in names
    ]
    outcomes = run_chains(chains, processes)
    seconds = {name: outcome[0] for name, outcome in zip(names, outcomes) if name in pending}
    measured = {name: outcome[-1] for name, outcome in zip(names, outcomes)}
    return _load_all(runs, seconds, measured, progress)
