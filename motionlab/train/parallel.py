"""Training several independent runs at once, one per core, each on one torch thread.

The course's models are small: one thread trains each of them fastest (see ``motionlab.config``), so the
second core of the course machine is best used by a second *run*. :func:`run_in_workers` calls a function
on each of several argument tuples in worker processes (``spawn``: a new interpreter, safe with torch's
thread pools; started once per notebook and reused, each call set up as in a fresh worker) and returns
the results in order. Runs that go through
:func:`~motionlab.train.train_or_load` are seeded by their own configs, so their weights do not depend on
which process trained them; the caller then loads every model from the checkpoint cache.
The course's chapters do not call this module: :mod:`motionlab.train.many` is their entry point.
"""

from __future__ import annotations

import atexit
import multiprocessing
import numbers
import os
import pickle
import signal
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, TypeVar

from motionlab import config
from motionlab.validation import check_scalar

R = TypeVar("R")

#: Environment variables that configure the package (profile, build directory); every call carries the
#: caller's values to the worker, so a reused worker behaves like one started now.
_ENV_PREFIX = "MOTIONLAB_"

_shared_pools: dict[int, ProcessPoolExecutor] = {}


def _in_worker(function: Callable[..., Any], arguments: bytes, environment: dict[str, str]) -> bytes:
    """Body of a worker call: the caller's package settings, the course's thread count and seeds, then
    ``function(*arguments)`` (so a call does not depend on what the worker ran before). Arguments and result
    travel as plain pickles (:func:`submit`)."""
    for name in [name for name in os.environ if name.startswith(_ENV_PREFIX)]:
        del os.environ[name]
    os.environ.update(environment)
    config.setup(seed=0)
    return pickle.dumps(function(*pickle.loads(arguments)), protocol=pickle.HIGHEST_PROTOCOL)


def _package_environment() -> dict[str, str]:
    return {name: value for name, value in os.environ.items() if name.startswith(_ENV_PREFIX)}


#: How often a worker checks that the process that started it is still there (seconds).
PARENT_CHECK_SECONDS = 0.5


def _exit_with_parent(parent: int) -> None:
    """Body of a worker's watch thread: end the worker as soon as ``parent`` is gone (the worker is then
    re-parented, so its parent id changes). A kernel that is killed runs no clean-up of its own, and its
    idle workers would otherwise wait on their task queue for ever."""
    while os.getppid() == parent:
        time.sleep(PARENT_CHECK_SECONDS)
    os._exit(1)


def _start_worker(parent: int) -> None:
    """Worker start-up. Ctrl-C (SIGINT, which Jupyter sends to the kernel's whole process group, and again
    when it shuts the kernel down) is for the notebook, not for idle workers; a training run still catches it
    at a step boundary (:func:`~motionlab.train.train_or_load` installs its own handler while it runs). And
    the worker ends with ``parent``, the process that started it, however that one ends
    (:func:`_exit_with_parent`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_exit_with_parent, args=(parent,), name="exit-with-parent", daemon=True).start()


def worker_pool(processes: int = 2) -> ProcessPoolExecutor:
    """A pool of ``processes`` fresh (``spawn``) worker processes that end with this process; submit work with
    :func:`submit`."""
    check_scalar(processes, "processes", "worker_pool", kind=numbers.Integral, minimum=1)
    return ProcessPoolExecutor(
        max_workers=processes,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_start_worker,
        initargs=(os.getpid(),),
    )


def shared_pool(processes: int = 2) -> ProcessPoolExecutor:
    """This process's long-lived pool of ``processes`` workers, started at the first use.

    Starting a worker (a new interpreter importing torch and the package) costs 3-4 s of a core, so the
    calls of a chapter share one pool instead of starting a pool each. Every call still runs as in a
    fresh worker (:func:`submit`); the pool ends when this process does, or with :func:`close_shared_pools`.
    """
    check_scalar(processes, "processes", "shared_pool", kind=numbers.Integral, minimum=1)
    if processes not in _shared_pools:
        _shared_pools[processes] = worker_pool(processes)
    return _shared_pools[processes]


def close_shared_pools() -> None:
    """Shut the shared pools down: calls still waiting are cancelled, the workers exit after their current
    one."""
    while _shared_pools:
        _shared_pools.popitem()[1].shutdown(cancel_futures=True)


def _drop_broken_pool(processes: int) -> None:
    """Forget the shared pool of ``processes`` after a worker died, so the next call starts a new one."""
    pool = _shared_pools.pop(processes, None)
    if pool is not None:
        pool.shutdown(wait=False, cancel_futures=True)


atexit.register(close_shared_pools)


def submit(pool: ProcessPoolExecutor, function: Callable[..., Any], *arguments: Any) -> Future[bytes]:
    """Run ``function(*arguments)`` in ``pool`` after the course's set-up (the caller's ``MOTIONLAB_*``
    settings, one thread, seed 0), as a fresh worker would; :func:`outcome` of the future is its result.

    ``function`` must be importable (a module-level function) and the arguments picklable. Arguments and
    result are copied as plain pickles: the pool's own queues would pass tensors through torch's
    shared-memory reductions, which move a tensor's storage into shared memory, so a worker that changed
    an argument in place would change the caller's tensor too.
    """
    payload = pickle.dumps(arguments, protocol=pickle.HIGHEST_PROTOCOL)
    return pool.submit(_in_worker, function, payload, _package_environment())


def outcome(future: Future[bytes]) -> Any:
    """The result of a call started with :func:`submit` (waits; raises the call's exception)."""
    return pickle.loads(future.result())


def run_in_workers(
    function: Callable[..., R], calls: Sequence[tuple[Any, ...]], processes: int = 2
) -> list[R]:
    """``[function(*args) for args in calls]``, ``processes`` at a time in worker processes (the
    :func:`shared_pool`), each call set up as in a fresh worker.

    Calls start in the order given (put the longest first, so the last one to finish is short). With one
    process, or one call, everything runs here, in this process. An exception in a call is raised here.
    """
    check_scalar(processes, "processes", "run_in_workers", kind=numbers.Integral, minimum=1)
    if processes == 1 or len(calls) <= 1:
        return [function(*arguments) for arguments in calls]
    return [results[0] for results in run_chains([[(function, arguments)] for arguments in calls], processes)]


#: One call of a chain: ``(function, arguments)``.
Step = tuple[Callable[..., Any], tuple[Any, ...]]


def run_chains(chains: Sequence[Sequence[Step]], processes: int = 2) -> list[list[Any]]:
    """Chains of dependent calls in worker processes (the :func:`shared_pool`): the calls of one chain one
    after another, different chains side by side, ``processes`` calls at a time.

    The first call of every chain is queued first, in the order given; the next call of a chain is queued
    when its previous one has finished, behind the calls already waiting. So the later calls of the chains
    (e.g. measuring a model that the chain's first call trained into the checkpoint cache) fill the cores
    that would otherwise idle while the last first calls run. Calls of one chain pass nothing to each
    other but what they leave on disk. Returns the results of each chain's calls. If calls fail, no new call
    starts, the calls still waiting are cancelled (the pool may already have handed one more to a worker:
    that one runs), the running ones finish, and the exception of the first failed call (in the order
    given) is raised here. With one process everything runs here, in order.
    """
    check_scalar(processes, "processes", "run_chains", kind=numbers.Integral, minimum=1)
    if processes == 1:
        return [[function(*arguments) for function, arguments in chain] for chain in chains]
    results: list[list[Any]] = [[None] * len(chain) for chain in chains]
    pool = shared_pool(processes)
    running: dict[Future[Any], tuple[int, int]] = {}

    def start(chain: int, index: int) -> None:
        function, arguments = chains[chain][index]
        running[submit(pool, function, *arguments)] = (chain, index)

    for chain in range(len(chains)):
        if chains[chain]:
            start(chain, 0)
    failed: dict[tuple[int, int], BaseException] = {}
    try:
        while running:
            finished, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in sorted(finished, key=running.__getitem__):
                chain, index = running.pop(future)
                if future.cancelled():
                    continue
                if future.exception() is not None:
                    failed[chain, index] = future.exception()
                    for waiting in running:  # nothing new starts; the calls already running finish
                        waiting.cancel()
                elif not failed:
                    results[chain][index] = outcome(future)
                    if index + 1 < len(chains[chain]):
                        start(chain, index + 1)
    except BaseException:  # e.g. Ctrl-C while waiting: leave nothing queued in the shared pool
        for waiting in running:
            waiting.cancel()
        raise
    if failed:
        if any(
            isinstance(error, BrokenProcessPool) for error in failed.values()
        ):  # a worker died (e.g. killed)
            _drop_broken_pool(processes)
        raise failed[min(failed)]  # the first failed call in the order given, whichever failed first in time
    return results
