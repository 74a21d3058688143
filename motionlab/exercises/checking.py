"""The machinery every checker shares: run the reader's function, compare, and say what is wrong."""

from __future__ import annotations

import functools
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import torch

#: A check: given the reader's function, ``None`` when it passes, else a sentence saying what is wrong.
Check = Callable[[Callable[..., Any]], str | None]


#: The reader's function a checker takes (each exercise names its own signature).
F = TypeVar("F", bound=Callable[..., Any])


class Diagnosis(Exception):
    """Raised inside a check to stop it with a sentence for the reader."""


@dataclass(frozen=True)
class CheckResult:
    """The outcome of a checker: ``status`` is ``"passed"``, ``"not done"`` or ``"wrong"``."""

    exercise: str
    status: str
    message: str

    @property
    def passed(self) -> bool:
        return self.status == "passed"

    def __str__(self) -> str:
        mark = {"passed": "✓", "not done": "…", "wrong": "✗"}[self.status]
        return f"{mark} {self.exercise}: {self.message}"

    def _repr_markdown_(self) -> str:
        return f"**{self}**" if self.passed else str(self)


def run_checks(exercise: str, fn: Callable[..., Any], checks: Sequence[Check], success: str) -> CheckResult:
    """Run ``checks`` in order (the most basic first) and stop at the first failure.

    ``NotImplementedError`` from ``fn`` means "not done yet"; any other exception from ``fn`` is reported
    with its type, message and the line of the reader's code it came from.
    """
    if not callable(fn):
        return CheckResult(exercise, "wrong", f"expected a function, got {type(fn).__name__}")
    for check in checks:
        try:
            problem = check(fn)
        except NotImplementedError as error:
            hint = f" ({error})" if str(error) else ""
            return CheckResult(
                exercise, "not done", f"not done yet{hint}; the chapter uses the package's version"
            )
        except Diagnosis as diagnosis:
            problem = str(diagnosis)
        except Exception as error:  # the reader's code failed: say where
            frames = [f for f in traceback.extract_tb(error.__traceback__) if "motionlab" not in f.filename]
            where = f" (line: {frames[-1].line})" if frames and frames[-1].line else ""
            problem = f"your function raised {type(error).__name__}: {error}{where}"
        if problem is not None:
            return CheckResult(exercise, "wrong", problem)
    return CheckResult(exercise, "passed", success)


def checker(
    checks: Sequence[Callable[[F], str | None]], success: str
) -> Callable[[Callable[[F], CheckResult]], Callable[[F], CheckResult]]:
    """Make a declared ``check_<name>(fn)`` (a signature and a docstring, no body) the checker of exercise
    ``<name>``: it runs ``checks`` through :func:`run_checks` and reports ``success`` when all pass."""

    def make(declared: Callable[[F], CheckResult]) -> Callable[[F], CheckResult]:
        exercise = declared.__name__.removeprefix("check_")

        @functools.wraps(declared)
        def check(fn: F) -> CheckResult:
            return run_checks(exercise, fn, checks, success)

        return check

    return make


def as_result(value: Any, what: str) -> torch.Tensor:
    """``value`` if it is a tensor, else a :class:`Diagnosis` naming what came back."""
    if not isinstance(value, torch.Tensor):
        raise Diagnosis(f"{what} should return a torch.Tensor, got {type(value).__name__}")
    return value


def close(a: torch.Tensor, b: torch.Tensor, tolerance: float = 1e-9) -> bool:
    """Whether two tensors of the same shape agree to ``tolerance`` (absolute and relative)."""
    return a.shape == b.shape and bool(torch.allclose(a, b, atol=tolerance, rtol=tolerance))


def close_each(a: torch.Tensor, b: torch.Tensor, tolerance: float = 1e-9) -> torch.Tensor:
    """Element-wise agreement of two same-shaped tensors."""
    return torch.isclose(a, b, atol=tolerance, rtol=tolerance)


def random_unit_quaternions(
    shape: tuple[int, ...], seed: int, dtype: torch.dtype = torch.float64
) -> torch.Tensor:
    """Uniformly random unit quaternions ``(*shape, 4)``, w first, from ``seed``."""
    q = torch.randn(*shape, 4, generator=torch.Generator().manual_seed(seed), dtype=dtype)
    return q / q.norm(dim=-1, keepdim=True)
