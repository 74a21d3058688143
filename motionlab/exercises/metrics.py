"""Chapter 09's exercises: APD of a sample set and FID from features, checked against
:mod:`motionlab.metrics`.

The reader's functions take and return torch tensors (a 0-d tensor or a Python float for the number); the
checkers compare them in float64 with the package's :func:`~motionlab.metrics.apd` and
:func:`~motionlab.metrics.fid` and recognise the usual slips.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import torch
from scipy.spatial.distance import pdist

from motionlab.exercises.checking import CheckResult, Diagnosis, checker
from motionlab.metrics import apd, fid, frechet_distance

APD = Callable[[torch.Tensor], Any]
FID = Callable[[torch.Tensor, torch.Tensor], Any]


def _number(value: Any, what: str) -> float:
    """A returned number (a 0-d or one-element tensor, or a float) as a float, else a :class:`Diagnosis`."""
    if isinstance(value, torch.Tensor):
        if value.numel() != 1:
            raise Diagnosis(f"{what} should return one number, got a tensor of shape {tuple(value.shape)}")
        return float(value.detach().reshape(()))
    if isinstance(value, (int, float, np.floating)):
        return float(value)
    raise Diagnosis(f"{what} should return a number (a 0-d tensor or a float), got {type(value).__name__}")


def _near(a: float, b: float, tolerance: float = 1e-6) -> bool:
    return math.isclose(a, b, rel_tol=tolerance, abs_tol=tolerance)


def _samples(seed: int, k: int = 6) -> torch.Tensor:
    return torch.randn(k, 10, 9, generator=torch.Generator().manual_seed(seed), dtype=torch.float64)


def _apd_values(fn: APD) -> None:
    x = _samples(0)
    got, want = _number(fn(x), "apd"), apd(x)
    if _near(got, want):
        return
    flat = x.reshape(x.shape[0], -1).numpy()
    k = x.shape[0]
    per_frame = float(
        np.mean([np.linalg.norm(x[i] - x[j], axis=-1).mean() for i in range(k) for j in range(k) if i != j])
    )
    for wrong, text in (
        (want * (k - 1) / k, "you divided by K² (counting each sample with itself): divide by K(K - 1)"),
        (
            float((pdist(flat) ** 2).mean()),
            "you averaged squared distances: take the L2 norm, not its square",
        ),
        (per_frame, "you averaged per-frame distances: flatten each whole sample to one vector first"),
        (want / 2, "you counted each unordered pair once but divided by K(K - 1)"),
    ):
        if _near(got, wrong):
            raise Diagnosis(text)
    raise Diagnosis(f"for 6 random samples (6, 10, 9) you gave {got:.6g}, the APD is {want:.6g}")


def _apd_edges(fn: APD) -> None:
    same = _samples(1, 1).expand(4, -1, -1).clone()
    if not _near(_number(fn(same), "apd"), 0.0):
        raise Diagnosis("four identical samples have APD 0")
    x = _samples(2, 3)
    if not _near(_number(fn(3.0 * x), "apd"), 3.0 * apd(x)):
        raise Diagnosis("APD should scale with the motion: apd(3 x) = 3 apd(x)")
    two = _samples(3, 2)
    want = float((two[0] - two[1]).norm())
    if not _near(_number(fn(two), "apd"), want):
        raise Diagnosis(f"two samples: APD is their distance {want:.6g}")


@checker(
    [_apd_values, _apd_edges],
    "matches motionlab.metrics.apd on random sample sets, 0 for identical samples, linear in scale",
)
def check_apd(fn: APD) -> CheckResult:
    """Check ``fn(samples) -> number``, the average pairwise distance of samples ``(K, T, D)``."""


def _features(seed: int, n: int, d: int, shift: float = 0.0, scale: float = 1.0) -> torch.Tensor:
    generator = torch.Generator().manual_seed(seed)
    return shift + scale * torch.randn(n, d, generator=generator, dtype=torch.float64)


def _fid_values(fn: FID) -> None:
    a, b = _features(0, 200, 5), _features(1, 150, 5, shift=0.5, scale=1.5)
    got, want = _number(fn(a, b), "fid"), fid(a, b)
    if _near(got, want, 1e-5):
        return
    mean_term = float(((a.mean(0) - b.mean(0)) ** 2).sum())
    cov_a, cov_b = np.cov(a.numpy(), rowvar=False), np.cov(b.numpy(), rowvar=False)
    biased = frechet_distance(a.mean(0), cov_a * 199 / 200, b.mean(0), cov_b * 149 / 150)
    no_sqrt = mean_term + float(np.trace(cov_a + cov_b - 2 * (cov_a @ cov_b)))
    for wrong, text in (
        (mean_term, "only the means: add the covariance term tr(Σ₁ + Σ₂ - 2 (Σ₁ Σ₂)^{1/2})"),
        (math.sqrt(want), "you returned the square root: FID is the squared Fréchet distance"),
        (
            no_sqrt,
            "the cross term needs the matrix square root of Σ₁ Σ₂ (scipy.linalg.sqrtm), not the product",
        ),
        (biased, "you divided the covariances by N: use the unbiased estimate (N - 1), like numpy.cov"),
        (want - mean_term + math.sqrt(mean_term), "the mean term is the squared distance ‖μ₁ - μ₂‖²"),
    ):
        if _near(got, wrong, 1e-4):
            raise Diagnosis(text)
    raise Diagnosis(f"for two random feature sets you gave {got:.6g}, the FID is {want:.6g}")


def _fid_edges(fn: FID) -> None:
    a = _features(2, 100, 4)
    if not _near(_number(fn(a, a.clone()), "fid"), 0.0, 1e-5):
        raise Diagnosis("the FID of a set with itself is 0 (take the real part of sqrtm, it may be complex)")
    b = a + torch.tensor([1.0, 0.0, 2.0, 0.0], dtype=torch.float64)
    if not _near(_number(fn(a, b), "fid"), 5.0, 1e-5):
        raise Diagnosis("shifting every feature by (1, 0, 2, 0) should give FID ‖shift‖² = 5")
    if not _near(_number(fn(a, _features(3, 40, 4)), "fid"), fid(a, _features(3, 40, 4)), 1e-5):
        raise Diagnosis(
            "sets of different sizes (100 and 40 rows) should work: only the means and covariances meet"
        )


@checker(
    [_fid_values, _fid_edges],
    "matches motionlab.metrics.fid on random feature sets, 0 for a set with itself, ‖shift‖² for a shift",
)
def check_fid(fn: FID) -> CheckResult:
    """Check ``fn(a, b) -> number``, the FID between feature sets ``(N, D)`` and ``(M, D)``."""
