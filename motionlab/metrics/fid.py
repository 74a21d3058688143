r"""Fréchet Inception Distance (FID) between two feature sets: float64, finite, never complex.

FID fits a Gaussian to each set of features (classifier activations, one row per motion) and measures
the Fréchet (2-Wasserstein) distance between the two Gaussians:

.. math::
    \mathrm{FID} = \lVert \mu_1 - \mu_2 \rVert^2
        + \operatorname{tr}\bigl(\Sigma_1 + \Sigma_2 - 2\,(\Sigma_1^{1/2} \Sigma_2
        \Sigma_1^{1/2})^{1/2}\bigr).

The common implementation takes ``scipy.linalg.sqrtm`` of the non-symmetric product
:math:`\Sigma_1 \Sigma_2`, which has the same trace of square root but returns complex numbers or NaN
when a covariance is singular (fewer samples than dimensions, constant features). Here the cross term is a
nuclear norm (sum of singular values), from ``numpy.linalg.svd``:

.. math::
    \operatorname{tr}(\Sigma_1^{1/2} \Sigma_2 \Sigma_1^{1/2})^{1/2} = \lVert \Sigma_2^{1/2} \Sigma_1^{1/2}
    \rVert_*
        = \lVert F_1 F_2^\top \rVert_* \quad\text{for any factors } \Sigma_k = F_k^\top F_k,

because :math:`M^\top M = \Sigma_1^{1/2} \Sigma_2 \Sigma_1^{1/2}` for :math:`M = \Sigma_2^{1/2}
\Sigma_1^{1/2}`, and :math:`M` and :math:`F_1 F_2^\top` have the same singular values. Why not the eigenvalues
of :math:`\Sigma_1^{1/2} \Sigma_2 \Sigma_1^{1/2}` (the textbook route): they are products of variances and
span twice as many decades, and an eigen-decomposition resolves them only to round-off of the largest. For
256 features with variances from 100 down to 1e-6 the products run from 1e4 down to 1e-12, the round-off
level is ``D · ε · 1e4 ≈ 6e-10``, and the square roots of the products below it (up to 2e-5 each) are real
signal: dropping them overstates that FID by 6e-4. The singular values of the factor product are the square
roots themselves, spanning only the variances' range, and the SVD resolves them to round-off of the largest.

:func:`fid` has the features and uses the centred rows over ``√(N - 1)`` (or the ``R`` of their QR
decomposition) as factors: no matrix square root at all, so a direction a singular covariance lacks adds a
singular value at round-off level, not at the square root of it. :func:`frechet_distance` has only the
covariances and uses their symmetric square roots from ``numpy.linalg.eigh``, with the eigenvalues of each
covariance below its own round-off (``λ ≤ D · ε · max λ``) set to 0: clipping only the negative ones would
let square roots of round-off (``~1e-8 · √max λ``) pair with the other covariance's variances in the
directions the first one lacks. The result is always a finite real number; it is clipped at 0 against
round-off.

Covariances use the unbiased estimator (divide by ``N - 1``), like ``numpy.cov``.
"""

from __future__ import annotations

import numpy as np

from motionlab.validation import ArrayLike, as_float_array, check_same_shape


def _psd_sqrt(matrix: np.ndarray) -> np.ndarray:
    """Symmetric square root of a symmetric positive semi-definite ``(D, D)`` matrix.

    Eigenvalues at round-off level of the largest (``λ ≤ D · ε · max λ``, negative ones included) count as 0:
    they are indistinguishable from 0 in the matrix, and their square roots would not be.
    """
    eigenvalues, eigenvectors = np.linalg.eigh(0.5 * (matrix + matrix.T))
    tolerance = matrix.shape[0] * np.finfo(np.float64).eps * max(float(eigenvalues.max()), 0.0)
    roots = np.sqrt(np.where(eigenvalues > tolerance, eigenvalues, 0.0))
    return (eigenvectors * roots) @ eigenvectors.T


def _nuclear_norm(matrix: np.ndarray) -> float:
    """Sum of the singular values of a 2-D ``matrix``."""
    return float(np.linalg.svd(matrix, compute_uv=False).sum())


def feature_statistics(features: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Mean ``(D,)`` and unbiased covariance ``(D, D)`` of a feature set ``(N, D)`` with ``N >= 2``.

    Compute these once for the real data and pass them to :func:`frechet_distance` to compare many
    generated sets against it.
    """
    x = as_float_array(features, "features", "feature_statistics", ndim=2, layout="(N, D)")
    return _statistics(x, "features", "feature_statistics")


def _centred(x: np.ndarray, name: str, func: str) -> tuple[np.ndarray, np.ndarray]:
    """Mean ``(D,)`` and centred rows ``(N, D)`` of ``x``, which needs ``N >= 2`` for a covariance."""
    if x.shape[0] < 2:
        raise ValueError(f"{func}: {name} needs at least 2 rows to estimate a covariance, got {x.shape[0]}")
    mean = x.mean(axis=0)
    return mean, x - mean


def _statistics(x: np.ndarray, name: str, func: str) -> tuple[np.ndarray, np.ndarray]:
    mean, centred = _centred(x, name, func)
    return mean, centred.T @ centred / (x.shape[0] - 1)


def _covariance_factor(x: np.ndarray, name: str, func: str) -> tuple[np.ndarray, np.ndarray]:
    """Mean ``(D,)`` and a factor ``F`` ``(min(N, D), D)`` of the unbiased covariance: ``Σ = Fᵀ F``.

    ``F`` is the centred rows divided by ``√(N - 1)``, replaced by the triangular ``R`` of their QR
    decomposition when ``N > D`` (same ``Fᵀ F``, fewer rows).
    """
    mean, centred = _centred(x, name, func)
    factor = centred / np.sqrt(x.shape[0] - 1)
    if x.shape[0] > x.shape[1]:
        factor = np.linalg.qr(factor, mode="r")
    return mean, factor


def _check_covariance(sigma: np.ndarray, name: str) -> None:
    asymmetry = float(np.abs(sigma - sigma.T).max())
    scale = max(float(np.abs(sigma).max()), 1e-300)
    if asymmetry > 1e-8 * scale:
        raise ValueError(f"frechet_distance: {name} is not symmetric (max |Σ - Σᵀ| = {asymmetry:.3g})")
    smallest = float(np.linalg.eigvalsh(0.5 * (sigma + sigma.T)).min())
    if smallest < -1e-8 * scale:
        raise ValueError(
            f"frechet_distance: {name} is not positive semi-definite (eigenvalue {smallest:.3g})"
        )


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


def _distance(mean_difference: np.ndarray, trace1: float, trace2: float, cross: float) -> float:
    """``|μ1 - μ2|² + tr Σ1 + tr Σ2 - 2 · cross``, clipped at 0 against round-off."""
    return max(float(mean_difference @ mean_difference + trace1 + trace2 - 2.0 * cross), 0.0)


def _frechet(m1: np.ndarray, s1: np.ndarray, m2: np.ndarray, s2: np.ndarray) -> float:
    cross = _nuclear_norm(_psd_sqrt(s2) @ _psd_sqrt(s1))
    return _distance(m1 - m2, float(np.trace(s1)), float(np.trace(s2)), cross)


def fid(a: ArrayLike, b: ArrayLike) -> float:
    """FID between feature sets ``a`` ``(N_a, D)`` and ``b`` ``(N_b, D)``, each with at least 2 rows.

    Symmetric in its arguments, ``>= 0``, 0 for identical sets, and unchanged when both sets are rotated
    or translated together. The sets may have different sizes; ``D`` must match. Works on the features
    rather than their covariances: the cross term is the nuclear norm of ``F_a F_bᵀ`` (see the module).
    """
    x = as_float_array(a, "a", "fid", ndim=2, layout="(N, D)")
    y = as_float_array(b, "b", "fid", ndim=2, layout="(N, D)")
    if x.shape[1] != y.shape[1]:
        raise ValueError(
            f"fid: a and b must have the same feature dimension D, got {x.shape[1]} and {y.shape[1]}"
        )
    m1, f1 = _covariance_factor(x, "a", "fid")
    m2, f2 = _covariance_factor(y, "b", "fid")
    return _distance(m1 - m2, float((f1 * f1).sum()), float((f2 * f2).sum()), _nuclear_norm(f1 @ f2.T))
