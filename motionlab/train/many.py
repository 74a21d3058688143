"""Training several runs on both cores: the one entry point every chapter uses.

A *run* is one training of one model, a :class:`~motionlab.train.run.Run`: a frozen, picklable
description that says whether the checkpoint cache already holds it and how to train it or load it.

:func:`train_many` trains the runs that are not cached in worker processes, one thread each (see
:mod:`motionlab.train.parallel`), optionally measures every model in a worker as soon as it is trained
(``then``), and finally loads every model here from the cache. Runs are seeded by their own configs, so a
model's weights do not depend on which process trained it, or when. :func:`train_meanwhile` trains runs in
the workers while a function (a chapter's data preparation) runs here.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from torch import nn

from motionlab import config
from motionlab.train.loop import TrainResult
from motionlab.train.measurements import measure_once
from motionlab.train.parallel import outcome, run_chains, shared_pool, submit
from motionlab.train.run import Run

M = TypeVar("M")
T = TypeVar("T")


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
    """Body of a worker call: load ``run``'s model from the cache (trained before) and measure it, or read
    the measurement this build made of it before (:func:`~motionlab.train.measurements.measure_once`)."""
    model, _ = run.train(progress=False)
    return measure_once(then, name, model)


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


def train_meanwhile(runs: Mapping[str, Run], work: Callable[[], T], processes: int | None = None) -> T:
    """Train the runs that are not cached in ``processes`` workers while ``work()`` runs here; wait for both
    and return what ``work`` returned (the runs are in the cache then; load them with their ``train``).

    A chapter's data preparation uses it to train the evaluators it needs on the idle cores. With one
    process, ``work()`` runs first and the runs train here afterwards; when every run is cached, no worker
    starts.
    """
    processes = config.processes() if processes is None else processes
    pending = [run for run in runs.values() if not run.is_cached()]
    if processes == 1 or not pending:
        done = work()
        for run in pending:
            _train_run(run)
        return done
    pool = shared_pool(processes)
    futures = [submit(pool, _train_run, run) for run in pending]
    done = work()
    for future in futures:
        outcome(future)  # raises the first failed run's exception
    return done


def train_many(
    runs: Mapping[str, Run],
    then: Callable[[str, nn.Module], M] | None = None,
    processes: int | None = None,
    progress: bool | None = None,
    alongside: Mapping[str, Run] | None = None,
) -> dict[str, Trained[M]]:
    """Train (or load) every run, ``processes`` at a time in worker processes, and return them by name.

    Args:
        runs: ``{name: run}``; runs start in this order (put the longest first, so the last to finish is
            short).
        then: ``then(name, model)`` measures a trained model in a worker as soon as its run is done, filling
            the cores that the last trainings leave idle. It must be picklable (a module-level function or
            a ``functools.partial`` of one) and seeded by its arguments alone, so its result does not depend
            on where or when it ran. Its result is :attr:`Trained.measured`, kept for the rest of the build
            (:mod:`motionlab.train.measurements`): the same call again reads it.
        processes: worker processes (one thread each; default :func:`motionlab.config.processes`); with 1
            everything runs here, in order.
        progress: progress bars while loading the models here (the workers show none).
        alongside: more runs to train into the cache on the same workers after ``runs`` (e.g. the
            benchmark's evaluators that a later section loads), neither measured nor loaded here.

    Returns:
        ``{name: Trained}`` in the order of ``runs``, every model loaded here from the cache.
    """
    processes = config.processes() if processes is None else processes
    names = list(runs)
    pending = {name for name in names if not runs[name].is_cached()}
    chains = [
        ([(_train_run, (runs[name],))] if name in pending else [])
        + ([(_measure_run, (runs[name], name, then))] if then is not None else [])
        for name in names
    ]
    chains += [[(_train_run, (run,))] for run in (alongside or {}).values() if not run.is_cached()]
    outcomes = run_chains(chains, processes)
    seconds = {name: outcome[0] for name, outcome in zip(names, outcomes) if name in pending}
    measured = {name: outcome[-1] for name, outcome in zip(names, outcomes) if then is not None}
    return _load_all(runs, seconds, measured, progress)
