"""Chapter 05's exercises: the affine coupling's transform, its log-determinant and its inverse, checked
against :mod:`motionlab.models.flows.coupling`."""

from __future__ import annotations

from collections.abc import Callable

import torch

from motionlab.exercises.checking import CheckResult, Diagnosis, as_result, checker, close
from motionlab.models.flows.coupling import SCALE_OFFSET, affine_forward, affine_inverse

AffineForward = Callable[[torch.Tensor, torch.Tensor], tuple[torch.Tensor, torch.Tensor]]
AffineInverse = Callable[[torch.Tensor, torch.Tensor], torch.Tensor]


def _inputs(seed: int, raw_scale: float = 1.0) -> tuple[torch.Tensor, torch.Tensor]:
    generator = torch.Generator().manual_seed(seed)
    x_b = torch.randn(2, 3, 5, generator=generator, dtype=torch.float64)
    params = torch.randn(2, 6, 5, generator=generator, dtype=torch.float64) * raw_scale
    return x_b, params


def _forward_values(fn: AffineForward) -> None:
    x_b, params = _inputs(1)
    out = fn(x_b, params)
    if not (isinstance(out, tuple) and len(out) == 2):
        raise Diagnosis("return a pair (y_b, logdet)")
    y_b, logdet = as_result(out[0], "the transform"), as_result(out[1], "the log-determinant")
    want_y, want_logdet = affine_forward(x_b, params)
    shift, raw = params.chunk(2, dim=1)
    if not close(y_b, want_y):
        scale = torch.sigmoid(raw + SCALE_OFFSET)
        for wrong, text in (
            (x_b * scale + shift, "shift first, then scale: y_b = (x_b + t) * s"),
            (
                (x_b + raw) * torch.sigmoid(shift + SCALE_OFFSET),
                "params hold the shift t first, then the raw scale r",
            ),
            (
                (x_b + shift) * torch.sigmoid(raw),
                f"the scale is sigmoid(r + {SCALE_OFFSET:g}) (Glow's offset)",
            ),
            ((x_b + shift) * torch.exp(raw), "the scale is a sigmoid, sigmoid(r + 2), not exp(r)"),
            (
                (x_b + shift) * torch.exp(raw + SCALE_OFFSET),
                "the scale is a sigmoid, sigmoid(r + 2), not exp",
            ),
        ):
            if close(y_b, wrong):
                raise Diagnosis(text)
        raise Diagnosis("y_b is wrong: y_b = (x_b + t) * sigmoid(r + 2) with t, r = params.chunk(2, dim=1)")
    if logdet.shape != want_logdet.shape:
        raise Diagnosis(
            f"the log-determinant should have one value per sequence, shape (2,), got {tuple(logdet.shape)}: "
            "sum log s over channels and time"
        )
    if close(logdet, -want_logdet):
        raise Diagnosis(
            "the log-determinant has the wrong sign: it is sum(log s), and s < 1 makes it negative"
        )
    if not close(logdet, want_logdet):
        raise Diagnosis("the log-determinant is wrong: sum log sigmoid(r + 2) over channels and time")


def _forward_is_stable(fn: AffineForward) -> None:
    x_b, params = _inputs(2, raw_scale=1000.0)
    _, logdet = fn(x_b, params)
    if not torch.isfinite(as_result(logdet, "the log-determinant")).all():
        raise Diagnosis(
            "the log-determinant is -inf for very negative r: log(sigmoid(r)) underflows; use "
            "torch.nn.functional.logsigmoid"
        )


@checker(
    [_forward_values, _forward_is_stable],
    "matches the package's affine coupling transform and log-determinant, stable for large scales",
)
def check_affine_forward(fn: AffineForward) -> CheckResult:
    """Check ``fn(x_b, params) -> (y_b, logdet)``: ``x_b (B, C, T)``, ``params (B, 2C, T)`` = (shift, raw
    scale), ``logdet (B,)``."""


def _inverse_undoes_forward(fn: AffineInverse) -> None:
    x_b, params = _inputs(3)
    y_b, _ = affine_forward(x_b, params)
    got = as_result(fn(y_b, params), "the inverse")
    if close(got, x_b):
        return
    shift, raw = params.chunk(2, dim=1)
    if close(got, y_b / torch.sigmoid(raw + SCALE_OFFSET) + shift):
        raise Diagnosis("undo the shift by subtracting t: x_b = y_b / s - t")
    if close(got, (y_b - shift) / torch.sigmoid(raw + SCALE_OFFSET)):
        raise Diagnosis("undo the steps in reverse order: first divide by s, then subtract t")
    raise Diagnosis("inverse(forward(x_b)) is not x_b")


@checker(
    [_inverse_undoes_forward],
    f"undoes the transform (as {affine_inverse.__module__}.affine_inverse does)",
)
def check_affine_inverse(fn: AffineInverse) -> CheckResult:
    """Check ``fn(y_b, params) -> x_b``, the inverse of the affine coupling transform."""
