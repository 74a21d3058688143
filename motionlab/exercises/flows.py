"""Chapter 05's exercises: a masked affine coupling layer on points, its log-determinant and its inverse,
checked against :mod:`motionlab.models.flows.coupling`.

The reader's layer takes points ``x (N, D)``, a mask ``(D,)`` with 1 on the conditioning half (passed
unchanged) and 0 on the transformed half, and a network ``net`` mapping ``(N, D)`` to ``(N, 2D)``: the shift
``u`` (MoGlow's ``t``) and then the raw scale ``r`` of every coordinate (only the transformed ones are used).
"""

from __future__ import annotations

from collections.abc import Callable

import torch
import torch.nn.functional as F
from torch import nn

from motionlab.exercises.checking import CheckResult, Diagnosis, as_result, checker, close
from motionlab.models.flows.coupling import SCALE_OFFSET, affine_forward, affine_inverse

Net = Callable[[torch.Tensor], torch.Tensor]  # (N, D) -> (N, 2D), e.g. an nn.Module
CouplingForward = Callable[[torch.Tensor, torch.Tensor, Net], tuple[torch.Tensor, torch.Tensor]]
CouplingInverse = Callable[[torch.Tensor, torch.Tensor, Net], torch.Tensor]

#: The test mask: coordinates 0 and 2 condition, 1 and 3 are transformed.
_MASK = torch.tensor([1.0, 0.0, 1.0, 0.0], dtype=torch.float64)


def _inputs(seed: int, weight_scale: float = 1.0) -> tuple[torch.Tensor, nn.Linear]:
    """Points ``(5, 4)`` and a random linear network ``(N, 4) -> (N, 8)`` that reads every coordinate."""
    generator = torch.Generator().manual_seed(seed)
    x = torch.randn(5, 4, generator=generator, dtype=torch.float64)
    net = nn.Linear(4, 8, dtype=torch.float64).requires_grad_(False)
    net.weight.copy_(torch.randn(8, 4, generator=generator, dtype=torch.float64) * weight_scale)
    net.bias.copy_(torch.randn(8, generator=generator, dtype=torch.float64))
    return x, net


def _reference(x: torch.Tensor, net: Net) -> tuple[torch.Tensor, torch.Tensor]:
    """The package's transform on the coordinates where the mask is 0: ``y (N, D)``, ``logdet (N,)``."""
    moved = _MASK == 0
    shift, raw = net(x * _MASK).chunk(2, dim=-1)
    params = torch.cat([shift[:, moved], raw[:, moved]], dim=1)[:, :, None]
    out = x.clone()
    y_b, logdet = affine_forward(x[:, moved][:, :, None], params)
    out[:, moved] = y_b[:, :, 0]
    return out, logdet


def _forward_values(fn: CouplingForward) -> None:
    x, net = _inputs(1)
    out = fn(x, _MASK, net)
    if not (isinstance(out, tuple) and len(out) == 2):
        raise Diagnosis("return a pair (y, logdet)")
    y, logdet = as_result(out[0], "the layer"), as_result(out[1], "the log-determinant")
    want_y, want_logdet = _reference(x, net)
    shift, raw = net(x * _MASK).chunk(2, dim=-1)
    keep = _MASK == 1
    if y.shape != x.shape:
        raise Diagnosis(f"y should have the shape of x, {tuple(x.shape)}, got {tuple(y.shape)}")
    if not close(y[:, keep], x[:, keep]):
        raise Diagnosis(
            "the conditioning half (mask = 1) must leave the layer unchanged: only the coordinates where "
            "mask = 0 are transformed"
        )
    if not close(y, want_y):
        wrong_shift, wrong_raw = net(x).chunk(2, dim=-1)
        for scale_of, text in (
            (
                lambda u, r: (x + wrong_shift) * torch.sigmoid(wrong_raw + SCALE_OFFSET),
                "the network may read only the conditioning half, net(x * mask): if it reads the coordinates "
                "it transforms, the layer cannot be inverted and its Jacobian is not triangular",
            ),
            (lambda u, r: x * torch.sigmoid(r + SCALE_OFFSET) + u, "shift first, then scale: (x + u) * s"),
            (
                lambda u, r: (x + r) * torch.sigmoid(u + SCALE_OFFSET),
                "the network's output holds the shift u first, then the raw scale r",
            ),
            (
                lambda u, r: (x + u) * torch.sigmoid(r),
                f"the scale is sigmoid(r + {SCALE_OFFSET:g}) (Glow's offset)",
            ),
            (lambda u, r: (x + u) * torch.exp(r), "the scale is a sigmoid, sigmoid(r + 2), not exp(r)"),
            (
                lambda u, r: (x + u) * torch.exp(r + SCALE_OFFSET),
                "the scale is a sigmoid, sigmoid(r + 2), not exp",
            ),
            (
                lambda u, r: (x + u) * (r + SCALE_OFFSET),
                "multiply by the scale s = sigmoid(r + 2), not by r + 2",
            ),
        ):
            wrong = scale_of(shift, raw) * (1 - _MASK) + x * _MASK
            if close(y, wrong):
                raise Diagnosis(text)
        raise Diagnosis("the transformed half is wrong: y = (x + u) * sigmoid(r + 2) where mask = 0")
    if logdet.shape == x.shape:
        raise Diagnosis(
            f"the log-determinant should have one value per point, shape ({x.shape[0]},), got "
            f"{tuple(logdet.shape)}: sum over the coordinates"
        )
    if logdet.shape != want_logdet.shape:
        raise Diagnosis(f"the log-determinant should have shape ({x.shape[0]},), got {tuple(logdet.shape)}")
    if close(logdet, -want_logdet):
        raise Diagnosis("the log-determinant has the wrong sign: every scale is below 1, so it is negative")
    if close(logdet, F.logsigmoid(raw + SCALE_OFFSET).sum(dim=-1)):
        raise Diagnosis(
            "the log-determinant counts the conditioning half too: the passed coordinates have derivative 1, "
            "log 1 = 0"
        )
    if close(logdet, (torch.sigmoid(raw + SCALE_OFFSET) * (1 - _MASK)).sum(dim=-1)):
        raise Diagnosis("the log-determinant sums the logs of the scales, not the scales")
    if close(logdet, (raw * (1 - _MASK)).sum(dim=-1)):
        raise Diagnosis("the log-determinant is the sum of log sigmoid(r + 2), not of r (that is exp's)")
    if not close(logdet, want_logdet):
        raise Diagnosis("the log-determinant is wrong: the sum of the log-scales over the transformed half")


def _forward_is_stable(fn: CouplingForward) -> None:
    x, net = _inputs(2, weight_scale=1000.0)
    _, logdet = fn(x, _MASK, net)
    if not torch.isfinite(as_result(logdet, "the log-determinant")).all():
        raise Diagnosis(
            "the log-determinant is -inf for very negative r: log(sigmoid(r)) underflows; use "
            "torch.nn.functional.logsigmoid"
        )


@checker(
    [_forward_values, _forward_is_stable],
    "matches the package's affine coupling and its log-determinant, stable for large scales",
)
def check_coupling_forward(fn: CouplingForward) -> CheckResult:
    """Check ``fn(x, mask, net) -> (y, logdet)``: ``x (N, D)``, ``mask (D,)``, ``net (N, D) -> (N, 2D)``,
    ``y (N, D)``, ``logdet (N,)``."""


def _inverse_undoes_forward(fn: CouplingInverse) -> None:
    x, net = _inputs(3)
    y, _ = _reference(x, net)
    got = as_result(fn(y, _MASK, net), "the inverse")
    if close(got, x):
        return
    if got.shape == x.shape and not close(got[:, _MASK == 1], y[:, _MASK == 1]):
        raise Diagnosis("the conditioning half (mask = 1) passes through the inverse unchanged too")
    shift, raw = net(y * _MASK).chunk(2, dim=-1)
    scale = torch.sigmoid(raw + SCALE_OFFSET)
    for wrong, text in (
        (y / scale + shift, "undo the shift by subtracting u"),
        ((y - shift) / scale, "undo the steps in reverse order: first the scale, then the shift"),
    ):
        if close(got, wrong * (1 - _MASK) + y * _MASK):
            raise Diagnosis(text)
    raise Diagnosis("inverse(forward(x)) is not x")


@checker(
    [_inverse_undoes_forward],
    f"undoes the layer (as {affine_inverse.__module__}.affine_inverse does on the transformed half)",
)
def check_coupling_inverse(fn: CouplingInverse) -> CheckResult:
    """Check ``fn(y, mask, net) -> x``, the inverse of the masked affine coupling."""
