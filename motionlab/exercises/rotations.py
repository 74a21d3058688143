"""Chapter 01's exercises: the Hamilton product and slerp, checked against :mod:`motionlab.geometry`."""

from __future__ import annotations

import math
from collections.abc import Callable

import torch

from motionlab import geometry as geo
from motionlab.exercises.checking import (
    CheckResult,
    Diagnosis,
    as_result,
    checker,
    close,
    random_unit_quaternions,
)

QuatMul = Callable[[torch.Tensor, torch.Tensor], torch.Tensor]
Slerp = Callable[[torch.Tensor, torch.Tensor, torch.Tensor | float], torch.Tensor]

_COMPONENTS = ("w", "x", "y", "z")


def _product_values(fn: QuatMul) -> None:
    q1, q2 = random_unit_quaternions((6,), 1), random_unit_quaternions((6,), 2)
    got = as_result(fn(q1, q2), "quat_mul")
    if got.shape != (6, 4):
        raise Diagnosis(
            f"for inputs of shape (6, 4) it returned shape {tuple(got.shape)}: keep the leading (batch) "
            "dimensions, e.g. take components with q[..., 0] and torch.stack(..., dim=-1)"
        )
    want = geo.quat_mul(q1, q2)
    if close(got, want):
        return
    if close(got, geo.quat_mul(q2, q1)):
        raise Diagnosis(
            "you computed q2 ⊗ q1: the Hamilton product is not commutative; q1 ⊗ q2 applies q2 first, "
            "then q1 (check the signs of the cross-product terms)"
        )
    if close(got, -want):
        raise Diagnosis("every component has the wrong sign (the same rotation, but not the product's value)")
    if close(got[0], want[0]):
        raise Diagnosis(
            "the first pair is right but not the others: compute every leading (batch) index the same way, "
            "with q[..., i] rather than q[i]"
        )
    wrong = [name for i, name in enumerate(_COMPONENTS) if not close(got[:, i], want[:, i])]
    raise Diagnosis(
        f"component(s) {', '.join(wrong)} are wrong (w comes first: q = (w, x, y, z)); e.g. for the first "
        f"pair you gave {got[0].tolist()} instead of {[round(v, 6) for v in want[0].tolist()]}"
    )


def _product_broadcasts(fn: QuatMul) -> None:
    q1, q2 = random_unit_quaternions((3, 1), 3), random_unit_quaternions((1, 5), 4)
    expected = "inputs of shapes (3, 1, 4) and (1, 5, 4) should broadcast to (3, 5, 4)"
    try:
        got = as_result(fn(q1, q2), "quat_mul")
    except (NotImplementedError, Diagnosis):
        raise
    except Exception as error:
        raise Diagnosis(f"{expected}; your function raised {type(error).__name__}: {error}") from error
    if got.shape != (3, 5, 4) or not close(got, geo.quat_mul(q1, q2)):
        raise Diagnosis(
            f"{expected}, got {tuple(got.shape)}" + (" with wrong values" if got.shape == (3, 5, 4) else "")
        )


def _product_keeps_dtype_and_gradient(fn: QuatMul) -> None:
    q1 = random_unit_quaternions((4,), 5, torch.float32).requires_grad_(True)
    q2 = random_unit_quaternions((4,), 6, torch.float32)
    got = as_result(fn(q1, q2), "quat_mul")
    if got.dtype != torch.float32:
        raise Diagnosis(f"float32 inputs gave {got.dtype}: keep the inputs' dtype")
    if not got.requires_grad:
        raise Diagnosis(
            "no gradient flows to q1: compute with torch operations (no .item(), .numpy() or floats)"
        )
    got.sum().backward()
    if q1.grad is None or not torch.isfinite(q1.grad).all():
        raise Diagnosis("the gradient with respect to q1 is missing or not finite")


@checker(
    [_product_values, _product_broadcasts, _product_keeps_dtype_and_gradient],
    "matches motionlab.geometry.quat_mul on random, broadcast and float32 inputs, with gradients",
)
def check_quat_mul(fn: QuatMul) -> CheckResult:
    """Check a Hamilton product ``fn(q1, q2)`` of ``(..., 4)`` quaternions, w first."""


def _pair_at_angle(angle: float, seed: int) -> tuple[torch.Tensor, torch.Tensor]:
    """Two unit quaternions whose rotations differ by ``angle`` radians (positive dot product)."""
    q0 = random_unit_quaternions((), seed)
    axis = torch.randn(3, generator=torch.Generator().manual_seed(seed + 1), dtype=torch.float64)
    step = geo.axis_angle_to_quat(axis / axis.norm() * angle)
    return q0, geo.quat_mul(step, q0)


def _slerp_endpoints_and_path(fn: Slerp) -> None:
    q0, q1 = _pair_at_angle(2.0, 10)
    for w, want, name in ((0.0, q0, "q0"), (1.0, q1, "q1")):
        got = as_result(fn(q0, q1, w), "slerp")
        if got.shape != (4,):
            raise Diagnosis(
                f"single quaternions (4,) and w = {w} should give shape (4,), got {tuple(got.shape)}"
            )
        if not close(got, want, 1e-7):
            raise Diagnosis(f"at w = {w} slerp should return {name}, got {got.tolist()}")
    w = torch.linspace(0, 1, 9, dtype=torch.float64)
    got = as_result(fn(q0, q1, w), "slerp")
    if got.shape != (9, 4):
        raise Diagnosis(
            f"w of shape (9,) with single quaternions (4,) should give (9, 4), got {tuple(got.shape)}"
        )
    norms = got.norm(dim=-1)
    if not close(norms, torch.ones_like(norms), 1e-7):
        raise Diagnosis("the path leaves the unit sphere: slerp of unit quaternions has norm 1 at every w")
    want = geo.quat_slerp(q0, q1, w)
    if close(got, want, 1e-7):
        return
    if close(got, geo.quat_nlerp(q0, q1, w), 1e-7):
        raise Diagnosis(
            "this is nlerp (normalised linear interpolation): same great circle, but not at constant speed; "
            "weight q0 and q1 by sin((1 - w)Ω)/sin Ω and sin(wΩ)/sin Ω"
        )
    travelled = geo.quat_geodesic(q0.expand(9, 4), got)
    raise Diagnosis(
        "the path is not slerp's: the angle from q0 should grow evenly with w, got "
        f"{[round(math.degrees(a), 1) for a in travelled.tolist()]} degrees"
    )


def _slerp_takes_the_short_way(fn: Slerp) -> None:
    q0, q1 = _pair_at_angle(2.0, 20)
    got = as_result(fn(q0, -q1, 0.5), "slerp")
    want = geo.quat_slerp(q0, -q1, 0.5)
    if not (close(got, want, 1e-7) or close(got, -want, 1e-7)):
        raise Diagnosis(
            "with q1 replaced by -q1 (the same rotation) the midpoint changed: when <q0, q1> < 0, flip q1 "
            "first, so that the path takes the shorter arc"
        )


def _slerp_near_equal(fn: Slerp) -> None:
    q0, q1 = _pair_at_angle(1e-9, 30)
    got = as_result(fn(q0, q1, 0.3), "slerp")
    if not torch.isfinite(got).all():
        raise Diagnosis(
            "for almost equal quaternions the result is NaN or infinite: sin Ω is ~0 there; use the limit "
            "(e.g. torch.sinc, or nlerp below a small angle)"
        )
    if not close(got, geo.quat_slerp(q0, q1, 0.3), 1e-7):
        raise Diagnosis("for almost equal quaternions the result should be (almost) q0")


@checker(
    [_slerp_endpoints_and_path, _slerp_takes_the_short_way, _slerp_near_equal],
    "matches motionlab.geometry.quat_slerp: end points, constant speed, the short arc, almost equal inputs",
)
def check_slerp(fn: Slerp) -> CheckResult:
    """Check a slerp ``fn(q0, q1, w)`` of unit quaternions ``(..., 4)`` with an interpolation weight ``w``, a
    number or a tensor."""
