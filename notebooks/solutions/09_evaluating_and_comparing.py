"""Worked solutions to chapter 09's "your turn" exercises (checked by tests/test_exercises.py)."""

from __future__ import annotations

import numpy as np
import scipy.linalg
import torch


def my_apd(samples: torch.Tensor) -> torch.Tensor:
    """Average pairwise distance of K samples (K, T, D): each sample flattened, mean over pairs i != j."""
    flat = samples.reshape(samples.shape[0], -1)
    distances = torch.cdist(flat, flat)  # (K, K), zero diagonal
    count = flat.shape[0]
    return distances.sum() / (count * (count - 1))


def my_fid(a: torch.Tensor, b: torch.Tensor) -> float:
    """FID of feature sets (N, D) and (M, D): |mu_a - mu_b|^2 + tr(S_a + S_b - 2 (S_a S_b)^(1/2))."""
    x, y = a.double().numpy(), b.double().numpy()
    mu_a, mu_b = x.mean(0), y.mean(0)
    cov_a, cov_b = np.cov(x, rowvar=False), np.cov(y, rowvar=False)
    cross = scipy.linalg.sqrtm(cov_a @ cov_b).real
    return float(((mu_a - mu_b) ** 2).sum() + np.trace(cov_a + cov_b - 2 * cross))
