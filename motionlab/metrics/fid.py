r"""Fréchet Inception Distance (FID) between two feature sets: float64, finite, never complex.

FID fits a Gaussian to each set of features (classifier activations, one row per motion) and measures
the Fréchet (2-Wasserstein) distance between the two Gaussians:

.. math::
    \mathrm{FID} = \lVert \mu_1 - \mu_2 \rVert^2
        + \operatorname{tr}\bigl(\Sigma_1 + \Sigma_2 - 2\,(\Sigma_1^{1/2} \Sigma_2 \Sigma_1^{1/2})^{1/2}\bigr).

The common implementation takes ``scipy.linalg.sqrtm`` of the non-symmetric product
:math:`\Sigma_1 \Sigma_2`, which has the same trace of square root but returns complex numbers or NaN
when a covariance is singular (fewer samples than dimensions, constant features). Here both square roots
are of symmetric positive semi-definite matrices and go through ``numpy.linalg.eigh``: the inner matrix is
symmetrised, and eigenvalues below round-off (``|λ| ≤ D · ε · max|λ|``) count as 0. The result is always a
finite real number; it is clipped at 0 against round-off.

Covariances use the unbiased estimator (divide by ``N - 1``), like ``numpy.cov``.
"""

from __future__ import annotations

import numpy as np

from motionlab.metrics._inputs import ArrayLike, as_float_array, check_same_shape


def _clipped_eigh(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-decomposition of the symmetric part of ``matrix`` with round-off eigenvalues set to 0."""
    symmetric = 0.5 * (matrix + matrix.T)
    eigenvalues, eigenvectors = np.linalg.eigh(symmetric)
    tolerance = matrix.shape[0] * np.finfo(np.float64).eps * max(float(np.abs(eigenvalues).max()), 0.0)
    eigenvalues = np.where(eigenvalues > tolerance, eigenvalues, 0.0)
    return eigenvalues, eigenvectors


def _psd_sqrt(matrix: np.ndarray) -> np.ndarray:
    """Symmetric square root of a symmetric positive semi-definite ``(D, D)`` matrix."""
    eigenvalues, eigenvectors = _clipped_eigh(matrix)
    return (eigenvectors * np.sqrt(eigenvalues)) @ eigenvectors.T


def _trace_sqrt(matrix: np.ndarray) -> float:
    """``tr(matrix^{1/2})`` of a symmetric positive semi-definite ``(D, D)`` matrix."""
    eigenvalues, _ = _clipped_eigh(matrix)
    return float(np.sqrt(eigenvalues).sum())


def feature_statistics(features: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Mean ``(D,)`` and unbiased covariance ``(D, D)`` of a feature set ``(N, D)`` with ``N >= 2``.

    Compute these once for the real data and pass them to :func:`frechet_distance` to compare many
    generated sets against it.
    """
    x = as_float_array(features, "features", "feature_statistics", ndim=2, layout="(N, D)")
    return _statistics(x, "features", "feature_statistics")


def _statistics(x: np.ndarray, name: str, func: str) -> tuple[np.ndarray, np.ndarray]:
    if x.shape[0] < 2:
        raise ValueError(f"{func}: {name} needs at least 2 rows to estimate a covariance, got {x.shape[0]}")
    mean = x.mean(axis=0)
    centred = x - mean
    return mean, centred.T @ centred / (x.shape[0] - 1)


def _check_covariance(sigma: np.ndarray, name: str) -> None:
    asymmetry = float(np.abs(sigma - sigma.T).max())
    scale = max(float(np.abs(sigma).max()), 1e-300)
    if asymmetry > 1e-8 * scale:
        raise ValueError(f"frechet_distance: {name} is not symmetric (max |Σ - Σᵀ| = {asymmetry:.3g})")
    smallest = float(np.linalg.eigvalsh(0.5 * (sigma + sigma.T)).min())
    if smallest < -1e-8 * scale:
        raise ValueError(f"frechet_distance: {name} is not positive semi-definite (eigenvalue {smallest:.3g})")


def frechet_distance(mu1: ArrayLike, sigma1: ArrayLike, mu2: ArrayLike, sigma2: ArrayLike) -> float:
    r"""Fréchet distance between :math:`N(\mu_1, \Sigma_1)` and :math:`N(\mu_2, \Sigma_2)`.

    Args:
        mu1, mu2: means ``(D,)``.
        sigma1, sigma2: covariances ``(D, D)``, symmetric positive semi-definite (singular is fine).

    Returns:
        The squared 2-Wasserstein distance, a finite float ``>= 0``.
    """
    func = "frechet_distance"
    m1 = as_float_array(mu1, "mu1", func, ndim=1, layout="(D,)")
    m2 = as_float_array(mu2, "mu2", func, ndim=1, layout="(D,)")
    s1 = as_float_array(sigma1, "sigma1", func, ndim=2, layout="(D, D)")
    s2 = as_float_array(sigma2, "sigma2", func, ndim=2, layout="(D, D)")
    check_same_shape(m1, m2, ("mu1", "mu2"), func)
    dim = m1.shape[0]
    for name, sigma in (("sigma1", s1), ("sigma2", s2)):
        if sigma.shape != (dim, dim):
            raise ValueError(f"{func}: {name} must be ({dim}, {dim}) to match the means, got {sigma.shape}")
        _check_covariance(sigma, name)
    return _frechet(m1, s1, m2, s2)


def _frechet(m1: np.ndarray, s1: np.ndarray, m2: np.ndarray, s2: np.ndarray) -> float:
    root1 = _psd_sqrt(s1)
    cross = _trace_sqrt(root1 @ s2 @ root1)
    diff = m1 - m2
    value = float(diff @ diff + np.trace(s1) + np.trace(s2) - 2.0 * cross)
    return max(value, 0.0)


def fid(a: ArrayLike, b: ArrayLike) -> float:
    """FID between feature sets ``a`` ``(N_a, D)`` and ``b`` ``(N_b, D)``, each with at least 2 rows.

    Symmetric in its arguments, ``>= 0``, 0 for identical sets, and unchanged when both sets are rotated
    or translated together. The sets may have different sizes; ``D`` must match.
    """
    x = as_float_array(a, "a", "fid", ndim=2, layout="(N, D)")
    y = as_float_array(b, "b", "fid", ndim=2, layout="(N, D)")
    if x.shape[1] != y.shape[1]:
        raise ValueError(f"fid: a and b must have the same feature dimension D, got {x.shape[1]} and {y.shape[1]}")
    m1, s1 = _statistics(x, "a", "fid")
    m2, s2 = _statistics(y, "b", "fid")
    return _frechet(m1, s1, m2, s2)
