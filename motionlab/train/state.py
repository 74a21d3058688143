"""Resumable training state: global random-number states, the ``.resume.pt`` file, deferred Ctrl-C.

The resume file sits next to the run's cache entry (``<name>-<hash>.resume.pt``) and holds only what
``torch.load(..., weights_only=True)`` accepts: tensors, numbers, strings, lists, tuples, dicts and ``None``.
"""

from __future__ import annotations

import os
import random
import signal
import tempfile
import threading
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

RESUME_FORMAT = 1


def rng_state() -> dict[str, Any]:
    """The global states of torch (CPU), NumPy's legacy generator and Python's ``random``."""
    kind, keys, pos, has_gauss, cached_gaussian = np.random.get_state()
    version, internal, gauss_next = random.getstate()
    return {
        "torch": torch.get_rng_state(),
        "numpy": (
            kind,
            torch.from_numpy(keys.astype(np.int64)),
            int(pos),
            int(has_gauss),
            float(cached_gaussian),
        ),
        "python": (version, torch.tensor(internal, dtype=torch.int64), gauss_next),
    }


def set_rng_state(state: dict[str, Any]) -> None:
    """Restore what :func:`rng_state` returned."""
    torch.set_rng_state(state["torch"])
    kind, keys, pos, has_gauss, cached_gaussian = state["numpy"]
    np.random.set_state((kind, keys.numpy().astype(np.uint32), pos, has_gauss, cached_gaussian))
    version, internal, gauss_next = state["python"]
    random.setstate((version, tuple(int(x) for x in internal.tolist()), gauss_next))


@contextmanager
def rng_isolated() -> Iterator[None]:
    """Run a block without leaving a trace on the global random states (they are restored afterwards)."""
    saved = rng_state()
    try:
        yield
    finally:
        set_rng_state(saved)


def atomic_save(payload: dict[str, Any], path: Path) -> None:
    """``torch.save`` through a temporary file and a rename: a crash never leaves half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile(dir=path.parent, delete=False, suffix=".tmp") as handle:
        tmp = handle.name
    try:
        torch.save(payload, tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


@dataclass(frozen=True)
class ResumeFile:
    """The periodic state of one training run, valid only for the run ``identity`` (its hashed config)."""

    path: Path
    identity: dict[str, Any]

    def save(self, state: dict[str, Any]) -> None:
        """Write ``state`` (model, optimiser, position, history, RNG) with the run identity."""
        atomic_save({"format": RESUME_FORMAT, "identity": self.identity, "state": state}, self.path)

    def load(self) -> dict[str, Any] | None:
        """The saved state, or ``None`` (with a warning when a file exists but is unusable)."""
        if not self.path.exists():
            return None
        try:
            payload = torch.load(self.path, map_location="cpu", weights_only=True)
        except Exception as exc:  # corrupt or foreign file: start over
            warnings.warn(f"ignoring unreadable resume file {self.path.name}: {exc}", stacklevel=2)
            return None
        if not isinstance(payload, dict) or payload.get("format") != RESUME_FORMAT:
            warnings.warn(f"ignoring resume file {self.path.name}: unknown format", stacklevel=2)
            return None
        if payload.get("identity") != self.identity:
            warnings.warn(
                f"ignoring resume file {self.path.name}: it belongs to another configuration", stacklevel=2
            )
            return None
        return payload["state"]

    def remove(self) -> None:
        self.path.unlink(missing_ok=True)


class DeferredInterrupt:
    """Holds Ctrl-C (SIGINT, also Jupyter's "interrupt kernel") until the loop reaches a step boundary.

    Inside ``with DeferredInterrupt() as interrupt:`` a first SIGINT only sets ``interrupt.requested``; the
    loop checks it after each step, saves its state and raises ``KeyboardInterrupt``. A second SIGINT
    raises at once. Outside the main thread signals cannot be caught, and the block runs unchanged.
    """

    def __init__(self) -> None:
        self.requested = False
        self._previous: Any = None

    def _handle(self, signum: int, frame: Any) -> None:
        if self.requested:
            raise KeyboardInterrupt("second interrupt: stopping at once")
        self.requested = True

    def __enter__(self) -> DeferredInterrupt:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handle)
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            self._previous = None
