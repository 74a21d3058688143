"""Training several independent runs at once, one per core, each on one torch thread.

The course's models are small: one thread trains each of them fastest (see ``motionlab.config``), so the
second core of the course machine is best used by a second *run*. :func:`run_in_workers` calls a function
on each of several argument tuples in fresh worker processes (``spawn``: a new interpreter, safe with
torch's thread pools) and returns the results in order. Runs that go through
:func:`~motionlab.train.train_or_load` are seeded by their own configs, so their weights do not depend on
which process trained them; the caller then loads every model from the checkpoint cache.
:class:`InBackground` runs one call on the second core while the notebook goes on with its own work.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any, TypeVar

from motionlab import config

R = TypeVar("R")


def _in_worker(function: Callable[..., R], arguments: tuple[Any, ...]) -> R:
    """Body of a worker process: the course's thread count and seeds, then ``function(*arguments)``."""
    config.setup(seed=0)
    return function(*arguments)


def _check_processes(processes: int, where: str) -> None:
    if isinstance(processes, bool) or not isinstance(processes, int) or processes < 1:
        raise ValueError(f"{where}: processes must be a positive integer, got {processes!r}")


def worker_pool(processes: int = 2) -> ProcessPoolExecutor:
    """A pool of ``processes`` fresh (``spawn``) worker processes; submit work with :func:`submit`."""
    _check_processes(processes, "worker_pool")
    return ProcessPoolExecutor(max_workers=processes, mp_context=multiprocessing.get_context("spawn"))


def submit(pool: ProcessPoolExecutor, function: Callable[..., R], *arguments: Any) -> Future[R]:
    """Run ``function(*arguments)`` in ``pool`` after the course's set-up (one thread, seed 0).

    ``function`` must be importable (a module-level function) and the arguments picklable.
    """
    return pool.submit(_in_worker, function, arguments)


def run_in_workers(function: Callable[..., R], calls: Sequence[tuple[Any, ...]], processes: int = 2) -> list[R]:
    """``[function(*args) for args in calls]``, ``processes`` at a time in fresh worker processes.

    Calls start in the order given (put the longest first, so the last one to finish is short). With one
    process, or one call, everything runs here, in this process. An exception in a call is raised here.
    """
    _check_processes(processes, "run_in_workers")
    if processes == 1 or len(calls) <= 1:
        return [function(*arguments) for arguments in calls]
    with worker_pool(min(processes, len(calls))) as pool:
        futures = [submit(pool, function, *arguments) for arguments in calls]
        return [future.result() for future in futures]


class InBackground:
    """One call, ``function(*arguments)``, running in a worker process while this process goes on.

    ``wait()`` returns its result (raising its exception, if any) and ends the worker. Use it for work a
    later chapter needs, so that it costs no wall time now, e.g. training a classifier on the second core
    while the first trains the chapter's own models.
    """

    def __init__(self, function: Callable[..., Any], *arguments: Any) -> None:
        self._pool = worker_pool(1)
        self._future = submit(self._pool, function, *arguments)

    def done(self) -> bool:
        """Whether the call has finished."""
        return self._future.done()

    def wait(self) -> Any:
        """The call's result, once it has finished."""
        try:
            return self._future.result()
        finally:
            self._pool.shutdown()
