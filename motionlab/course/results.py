"""The one place where chapters record numbers: metrics and claims into ``results.json``.

A chapter opens a :class:`Chapter` once and records through it::

    from motionlab.course.results import Chapter
    chapter = Chapter("01_rotation_geometry")
    chapter.metric("geometry.scipy_max_err", err)
    chapter.claim("01.matches_scipy", value=err, threshold=1e-5, op="<=",
                  text="quat_to_matrix agrees with scipy")

The file (``build/course/results.json`` in the full profile, ``build/course-quick/results.json`` in the
quick one) has the layout of the design notes::

    {"profile": "full", "python": "3.11.7", "torch": "2.13.0",
     "notebooks": {"01_rotation_geometry": {"seconds": 12.3,
         "metrics": {"geometry.scipy_max_err": 1e-7},
         "claims": {"01.matches_scipy": {"holds": true, "value": 1e-7, "threshold": 1e-5,
                                          "op": "<=", "text": "...", "expected": true}}}}}

In the full profile a claim that does not hold raises :class:`ClaimFailed` (so the chapter, and
``make course``, fail) unless it was recorded as a known gap with ``expected=False`` and a ``why``.
In the quick profile claims are recorded but never asserted: the models are too small to mean anything.
"""

from __future__ import annotations

import json
import math
import operator
import os
import platform
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import torch

from motionlab import config
from motionlab.train import reference

try:
    import fcntl
except ImportError:  # Windows
    fcntl = None

_OPS: dict[str, Callable[[float, float], bool]] = {
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
}


class ClaimFailed(AssertionError):
    """A claim that should hold in the full profile did not."""


@dataclass(frozen=True)
class Claim:
    """One checked statement: ``value op threshold`` should be true."""

    holds: bool
    value: float
    threshold: float
    op: str
    text: str
    expected: bool = True
    why: str | None = None


def results_path() -> Path:
    """``results.json`` of the active profile."""
    return config.course_dir() / "results.json"


def _finite(name: str, value: Any) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name}: expected a number, got {type(value).__name__}") from exc
    if not math.isfinite(number):
        raise ValueError(f"{name}: value is not finite ({number})")
    return number


#: ``MOTIONLAB_CLAIMS=record``: a claim that does not hold is recorded and the chapter goes on (the course
#: build still fails, naming it); the default, ``assert``, stops the chapter at it.
CLAIMS_VARIABLE = "MOTIONLAB_CLAIMS"


def claims_asserted() -> bool:
    """Whether a full-profile claim that does not hold stops its chapter (``MOTIONLAB_CLAIMS=assert``, the
    default) or is only recorded (``record``: every claim of a chapter is checked, e.g. for a table of claims
    over training seeds)."""
    mode = os.environ.get(CLAIMS_VARIABLE, "assert").strip().lower() or "assert"
    if mode not in ("assert", "record"):
        raise ValueError(f"{CLAIMS_VARIABLE} must be 'assert' or 'record', got {mode!r}")
    return mode == "assert"


def failing_claims(name: str) -> list[str]:
    """The claims of notebook ``name`` recorded in ``results.json`` that should hold and do not."""
    claims = load_results().get("notebooks", {}).get(name, {}).get("claims", {})
    return sorted(cid for cid, c in claims.items() if c.get("expected", True) and not c.get("holds", True))


def build_settings() -> dict[str, Any]:
    """What else decides a build's numbers: the base training seed, whether the reference models were
    loaded or every model retrained here, and the numerical path forced through the environment
    (:func:`motionlab.config.numerical_path`)."""
    return {
        "base_seed": config.base_seed(),
        "models": "reference" if reference.in_use() else "retrained",
        "numerics": config.numerical_path(),
    }


def load_results(path: Path | None = None) -> dict[str, Any]:
    """Read ``results.json`` (an empty skeleton for the active profile when it does not exist)."""
    path = results_path() if path is None else Path(path)
    fresh = {
        "profile": config.profile(),
        "python": platform.python_version(),
        "torch": str(torch.__version__),
        **build_settings(),
        "notebooks": {},
    }
    if not path.exists():
        return fresh
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path} is not valid JSON (line {exc.lineno}): delete it and rebuild") from exc
    if data.get("profile") != config.profile():
        return fresh
    data.update({key: value for key, value in fresh.items() if key not in ("profile", "notebooks")})
    data.setdefault("notebooks", {})
    return data


def save_results(data: dict[str, Any], path: Path | None = None) -> None:
    """Write ``results.json`` atomically (a crash never leaves half a file)."""
    path = results_path() if path is None else Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", dir=path.parent, delete=False, suffix=".tmp") as handle:
        json.dump(data, handle, indent=2, sort_keys=True)
        tmp = handle.name
    os.replace(tmp, path)


@contextmanager
def _results_lock() -> Iterator[None]:
    """Hold ``results.json``'s lock file: the course runs two notebooks at a time
    (:data:`motionlab.course.run.PARALLEL`), and each read-modify-write of the file must see the other's."""
    if fcntl is None:  # no POSIX locks: the course runs one notebook at a time there
        yield
        return
    lock = results_path().with_suffix(".lock")
    lock.parent.mkdir(parents=True, exist_ok=True)
    with lock.open("a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def update_notebook(name: str, update: Callable[[dict[str, Any]], None]) -> None:
    """Apply ``update`` to the entry of notebook ``name`` and save (under the results' lock)."""
    with _results_lock():
        data = load_results()
        entry = data["notebooks"].setdefault(name, {"metrics": {}, "claims": {}})
        update(entry)
        save_results(data)


def record_wall_time(seconds: float, notebooks: int, trained_here: list[str] | None = None) -> None:
    """Record how long the last ``make course`` took from its first notebook's start to its last one's end
    (notebooks run two at a time, so this is less than the sum of their seconds), and the runs it trained
    although the reference models were in use (:func:`motionlab.train.reference.trained_here`)."""
    with _results_lock():
        data = load_results()
        data["build"] = {
            "wall_seconds": round(seconds, 1),
            "notebooks": notebooks,
            "trained_here": list(trained_here or []),
        }
        save_results(data)


class Chapter:
    """Records the metrics and claims of one notebook. Creating it clears that notebook's old entry."""

    def __init__(self, name: str) -> None:
        if not name or "/" in name:
            raise ValueError(
                f"chapter name must be a notebook stem like '01_rotation_geometry', got {name!r}"
            )
        self.name = name
        self.metrics: dict[str, float] = {}
        self.claims: dict[str, Claim] = {}

        def reset(entry: dict[str, Any]) -> None:
            entry["metrics"] = {}
            entry["claims"] = {}

        update_notebook(name, reset)

    def metric(self, key: str, value: Any, ci95: Any | None = None) -> float:
        """Record a metric (and optionally the half-width of its 95% interval as ``key + '.ci95'``)."""
        number = _finite(key, value)
        self.metrics[key] = number
        if ci95 is not None:
            self.metrics[f"{key}.ci95"] = _finite(f"{key}.ci95", ci95)
        metrics = dict(self.metrics)
        update_notebook(self.name, lambda entry: entry["metrics"].update(metrics))
        return number

    def claim(
        self,
        claim_id: str,
        value: Any,
        threshold: Any,
        op: str,
        text: str,
        expected: bool = True,
        why: str | None = None,
    ) -> Claim:
        """Check ``value op threshold``, record it, and in the full profile fail when it should hold but does
        not.

        ``expected=False`` marks a known gap: a claim that still does not hold after investigation. It is
        recorded and shown, never asserted, and needs a ``why``.
        """
        if op not in _OPS:
            raise ValueError(f"claim {claim_id}: op must be one of {sorted(_OPS)}, got {op!r}")
        if not expected and not why:
            raise ValueError(f"claim {claim_id}: a known gap (expected=False) needs a 'why'")
        number = _finite(claim_id, value)
        limit = _finite(f"{claim_id} threshold", threshold)
        holds = bool(_OPS[op](number, limit))
        claim = Claim(holds, number, limit, op, text, expected, why)
        self.claims[claim_id] = claim
        update_notebook(self.name, lambda entry: entry["claims"].update({claim_id: asdict(claim)}))
        if expected and not holds and not config.is_quick() and claims_asserted():
            raise ClaimFailed(
                f"claim {claim_id} does not hold: {text} (value {number:.6g} {op} {limit:.6g} is false)"
            )
        return claim

    def table(self) -> str:
        """The chapter's claims as a Markdown table (display it with ``IPython.display.Markdown``)."""
        rows = ["| claim | statement | value | threshold | holds |", "|---|---|---|---|---|"]
        for claim_id, c in self.claims.items():
            verdict = "yes" if c.holds else ("no (known gap)" if not c.expected else "**no**")
            rows.append(f"| `{claim_id}` | {c.text} | {c.value:.4g} | {c.op} {c.threshold:.4g} | {verdict} |")
        return "\n".join(rows)
