"""Course-wide settings: the profile switch, seeding, thread count and build paths.

Everything that differs between a quick test run and the full course goes through
:func:`choose`, so a notebook reads the same in both profiles::

    from motionlab import config
    epochs = config.choose(quick=2, full=40)

The profile comes from the environment variable ``MOTIONLAB_PROFILE`` (``quick`` or ``full``,
default ``full``). Tests and nbval set ``quick``; ``make course`` sets ``full``.

Every trained model's seed starts from one base, ``MOTIONLAB_SEED`` (default 0; :func:`base_seed`), so
``MOTIONLAB_SEED=1 make course`` builds the whole course on models of another training seed: a verdict that
holds only for one seed shows itself.
"""

from __future__ import annotations

import os
import random
from collections.abc import Iterator
from contextlib import contextmanager
from numbers import Integral
from pathlib import Path
from typing import TypeVar

import numpy as np
import torch
from threadpoolctl import threadpool_limits

from motionlab import paths
from motionlab.validation import Checked, check_scalar, integer

T = TypeVar("T")

PROFILES = ("quick", "full")

#: Threads torch uses for the course's small models. Measured on the 2-core course machine
#: (README, "Threads"; ``make bench``, entry ``threads``): a second thread speeds up one training step of
#: the Motion Cell (hidden 64, batch 32) by only 5-10 %, because its kernels are too small to split
#: well, while a second *process* on the other core doubles the throughput. So every run uses one
#: thread and the chapters with several models train two at a time (:mod:`motionlab.train.parallel`).
DEFAULT_THREADS = 1

REPO_ROOT = paths.REPO_ROOT


def profile() -> str:
    """The active profile, ``"quick"`` or ``"full"``, read from ``MOTIONLAB_PROFILE``."""
    value = os.environ.get("MOTIONLAB_PROFILE", "full").strip().lower()
    if value not in PROFILES:
        raise ValueError(f"MOTIONLAB_PROFILE must be one of {PROFILES}, got {value!r}")
    return value


#: The environment variable holding the base training seed (:func:`base_seed`).
SEED_VARIABLE = "MOTIONLAB_SEED"


def base_seed() -> int:
    """The seed every training run starts from unless its config names one: ``MOTIONLAB_SEED`` (default 0).

    It seeds the initial weights and the batches of every model the course trains (the training configs'
    and model configs' ``seed`` fields default to it, :func:`seed_field`); data, evaluation draws and the
    chapters' small foreground models keep their own fixed seeds. Any other value gives other cache keys, so
    models of two base seeds never mix.
    """
    text = os.environ.get(SEED_VARIABLE, "0").strip() or "0"
    if not text.isdigit():
        raise ValueError(f"{SEED_VARIABLE} must be an integer >= 0, got {text!r}")
    return int(text)


def seed_field() -> int:
    """A config dataclass's ``seed`` field: an integer >= 0 that defaults to :func:`base_seed` (read when
    the config is built)."""
    return integer(minimum=0, kind=int, default_factory=base_seed)


#: The environment variable holding the default number of worker processes (:func:`processes`).
PROCESSES_VARIABLE = "MOTIONLAB_PROCESSES"


def processes() -> int:
    """Worker processes for training and measuring several runs at once (``train_many``, ``train_meanwhile``)
    when a caller names none: ``MOTIONLAB_PROCESSES`` (default 2, one per core of the course machine).

    ``make test`` sets 1: its two pytest workers already keep both cores busy, and each worker process a
    notebook starts costs 3-4 s of a core (a new interpreter importing torch). Results do not depend on it:
    every run and measurement is seeded by its own arguments.
    """
    text = os.environ.get(PROCESSES_VARIABLE, "2").strip() or "2"
    if not text.isdigit() or int(text) < 1:
        raise ValueError(f"{PROCESSES_VARIABLE} must be an integer >= 1, got {text!r}")
    return int(text)


#: The environment variables that put torch and MKL on another CPU's numerical path.
NUMERICS_VARIABLES = ("ATEN_CPU_CAPABILITY", "MKL_CBWR")


def numerical_path() -> dict[str, str]:
    """The numerical path forced through the environment (:data:`NUMERICS_VARIABLES` that are set); empty for
    the machine's own."""
    return {key: os.environ[key] for key in NUMERICS_VARIABLES if key in os.environ}


def is_quick() -> bool:
    """True in the quick (test) profile."""
    return profile() == "quick"


def choose(quick: T, full: T) -> T:
    """Pick the value for the active profile."""
    return quick if is_quick() else full


build_dir = paths.build_dir


class ProfileConfig(Checked):
    """Base of an experiment's config dataclass with ``quick()`` and ``full()`` constructors: :meth:`current`
    is the one of the active profile (:func:`profile`); the fields' declared limits are checked when it is
    built (:class:`motionlab.validation.Checked`)."""

    @classmethod
    def current(cls):  # -> the subclass
        """:meth:`quick` or :meth:`full`, for the active :func:`profile`."""
        return cls.quick() if is_quick() else cls.full()

    @classmethod
    def full(cls):  # -> the subclass
        """The reported runs: the fields' defaults (a subclass whose defaults are not its full profile
        overrides this)."""
        return cls()


def checkpoint_dir() -> Path:
    """Where trained models are cached, keyed by a hash of their configuration."""
    return build_dir() / "checkpoints"


def course_dir() -> Path:
    """Where the executed chapters, ``index.html`` and ``results.json`` go.

    The full profile writes ``build/course``; the quick profile writes ``build/course-quick`` so that a
    test run never mixes its numbers into the report.
    """
    return build_dir() / ("course-quick" if is_quick() else "course")


def set_threads(n: int | None = None) -> int:
    """Set torch's intra-op thread count and the threads of NumPy's and SciPy's BLAS (default
    :data:`DEFAULT_THREADS`); returns it.

    The BLAS follows torch: with two processes side by side on two cores, a BLAS of two threads per process
    oversubscribes the cores (OpenBLAS's idle threads spin), and a course build's chapters 09 and 10 took
    10 to 14 % longer than with one thread each, every claim's value the same to the last bit.
    """
    if n is None:
        n = DEFAULT_THREADS
    n = int(check_scalar(n, "n (the thread count)", "set_threads", kind=Integral, minimum=1))
    if torch.get_num_threads() != n:
        torch.set_num_threads(n)
    threadpool_limits(limits=n, user_api="blas")
    return n


@contextmanager
def threads(n: int) -> Iterator[int]:
    """Run a block with ``n`` threads (torch's and the BLAS's, :func:`set_threads`), then restore the count.

    For the few runs that gain from both cores while nothing else runs (e.g. chapter 04's convolutional
    denoiser, 1.4x faster on 2 threads); the count is fixed by the caller, not by the machine, so the run
    stays reproducible.
    """
    previous = torch.get_num_threads()
    set_threads(n)
    try:
        yield n
    finally:
        set_threads(previous)


def seed_everything(seed: int) -> torch.Generator:
    """Seed Python, NumPy and torch; return a fresh ``torch.Generator`` seeded with ``seed``.

    Prefer passing the returned generator (or a ``numpy.random.default_rng(seed)``) explicitly;
    the global seeds are set too so that library code that draws from them is reproducible.
    """
    seed = int(check_scalar(seed, "seed", "seed_everything", kind=Integral, minimum=0))
    random.seed(seed)
    np.random.seed(seed % 2**32)
    torch.manual_seed(seed)
    return torch.Generator().manual_seed(seed)


def setup(seed: int = 0, threads: int | None = None) -> torch.Generator:
    """One call at the top of every notebook: thread count, seeds; returns a seeded generator."""
    set_threads(threads)
    return seed_everything(seed)
