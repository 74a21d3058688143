"""FID against scipy's sqrtm formula and against closed forms for Gaussians with known distance."""

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import sqrtm
from scipy.stats import special_ortho_group

from motionlab.metrics import feature_statistics, fid, frechet_distance

PROPERTY = settings(max_examples=25, deadline=None)


def scipy_fid(a: np.ndarray, b: np.ndarray) -> float:
    """The usual formula: ||mu1 - mu2||^2 + tr(S1 + S2 - 2 sqrtm(S1 S2)), np.cov statistics."""
    mu1, mu2 = a.mean(axis=0), b.mean(axis=0)
    s1, s2 = np.cov(a, rowvar=False), np.cov(b, rowvar=False)
    cross = sqrtm(s1 @ s2)
    return float(((mu1 - mu2) ** 2).sum() + np.trace(s1) + np.trace(s2) - 2 * np.trace(cross).real)


def with_exact_covariance(
    rng: np.random.Generator, n: int, variances: np.ndarray, mean: np.ndarray
) -> np.ndarray:
    """``n`` rows whose sample mean is ``mean`` and sample covariance is exactly ``diag(variances)``."""
    z = rng.normal(size=(n, variances.size))
    z -= z.mean(axis=0)
    q, _ = np.linalg.qr(z)  # orthonormal columns, each orthogonal to the all-ones vector
    return q * np.sqrt((n - 1) * variances) + mean


@pytest.mark.parametrize("seed", range(4))
def test_matches_scipy_sqrtm_formula_when_well_conditioned(seed):
    rng = np.random.default_rng(seed)
    dim = 6
    mix = rng.normal(size=(dim, dim))
    a = rng.normal(size=(400, dim)) @ mix
    b = rng.normal(size=(300, dim)) @ rng.normal(size=(dim, dim)) + rng.normal(size=dim)
    assert fid(a, b) == pytest.approx(scipy_fid(a, b), rel=1e-9, abs=1e-9)


def test_statistics_match_numpy():
    a = np.random.default_rng(0).normal(size=(50, 4))
    mu, sigma = feature_statistics(a)
    np.testing.assert_allclose(mu, a.mean(axis=0), rtol=1e-13)
    np.testing.assert_allclose(sigma, np.cov(a, rowvar=False), rtol=1e-12)


@pytest.mark.parametrize("n, dim, scale", [(200, 8, 1.0), (10, 64, 1.0), (500, 16, 1e3), (3, 3, 1e-3)])
def test_identical_sets_give_zero(n, dim, scale):
    a = np.random.default_rng(1).normal(size=(n, dim)) * scale
    assert fid(a, a) == pytest.approx(0.0, abs=1e-8)


@pytest.mark.parametrize("n, dim", [(300, 5), (8, 40)])
def test_shift_gives_squared_norm_of_the_shift(n, dim):
    rng = np.random.default_rng(2)
    a = rng.normal(size=(n, dim))
    shift = rng.normal(size=dim)
    assert fid(a, a + shift) == pytest.approx(float(shift @ shift), rel=1e-9, abs=1e-9)


def test_diagonal_covariances_closed_form():
    rng = np.random.default_rng(3)
    var_a, var_b = rng.uniform(0.1, 4.0, size=5), rng.uniform(0.1, 4.0, size=5)
    mean_a, mean_b = rng.normal(size=5), rng.normal(size=5)
    expected = ((mean_a - mean_b) ** 2).sum() + ((np.sqrt(var_a) - np.sqrt(var_b)) ** 2).sum()
    assert frechet_distance(mean_a, np.diag(var_a), mean_b, np.diag(var_b)) == pytest.approx(
        expected, rel=1e-12
    )
    a = with_exact_covariance(rng, 40, var_a, mean_a)
    b = with_exact_covariance(rng, 70, var_b, mean_b)
    assert fid(a, b) == pytest.approx(expected, rel=1e-9)


def test_one_dimensional_gaussians():
    # W2^2 between N(m1, s1^2) and N(m2, s2^2) is (m1 - m2)^2 + (s1 - s2)^2.
    assert frechet_distance([1.0], [[4.0]], [-2.0], [[9.0]]) == pytest.approx(9.0 + 1.0)


def test_sets_in_disjoint_coordinates_have_no_cross_term():
    rng = np.random.default_rng(4)
    a = np.zeros((30, 6))
    b = np.zeros((25, 6))
    a[:, :3] = rng.normal(size=(30, 3))
    b[:, 3:] = rng.normal(size=(25, 3)) * 2 + 1
    s1, s2 = np.cov(a, rowvar=False), np.cov(b, rowvar=False)
    diff = a.mean(axis=0) - b.mean(axis=0)
    assert fid(a, b) == pytest.approx(diff @ diff + np.trace(s1) + np.trace(s2), rel=1e-10)


def test_low_rank_sets_equal_their_fid_in_the_subspace():
    """Fewer samples than dimensions: embed full-rank 4-D sets in 50-D; FID must not change."""
    rng = np.random.default_rng(5)
    small_a = rng.normal(size=(12, 4))
    small_b = rng.normal(size=(9, 4)) * 1.5 + 0.5
    basis = np.linalg.qr(rng.normal(size=(50, 4)))[0]  # (50, 4) orthonormal columns
    offset = rng.normal(size=50)
    value = fid(small_a @ basis.T + offset, small_b @ basis.T + offset)
    assert np.isfinite(value)
    assert value == pytest.approx(scipy_fid(small_a, small_b), rel=1e-8)


def test_constant_features_separate_from_the_rest():
    rng = np.random.default_rng(6)
    a, b = rng.normal(size=(40, 3)), rng.normal(size=(35, 3)) + 0.2
    a_const = np.column_stack([a, np.full(40, 2.0), np.zeros(40)])
    b_const = np.column_stack([b, np.full(35, -1.0), np.zeros(35)])
    assert fid(a_const, b_const) == pytest.approx(scipy_fid(a, b) + 9.0, rel=1e-9)
    assert fid(np.ones((5, 4)), np.ones((7, 4))) == 0.0


def test_accepts_torch_and_returns_float():
    rng = np.random.default_rng(7)
    a, b = rng.normal(size=(20, 3)), rng.normal(size=(30, 3))
    value = fid(torch.tensor(a, dtype=torch.float64, requires_grad=True), torch.from_numpy(b))
    assert isinstance(value, float)
    assert value == fid(a, b)


def _pair(seed: int, n_a: int, n_b: int, dim: int, scale: float) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n_a, dim)) @ rng.normal(size=(dim, dim)) * scale
    b = rng.normal(size=(n_b, dim)) * scale + rng.normal(size=dim)
    return a, b


sizes = dict(
    seed=st.integers(0, 2**31),
    n_a=st.integers(2, 40),
    n_b=st.integers(2, 40),
    dim=st.integers(1, 12),
    scale=st.sampled_from([1e-2, 1.0, 30.0]),
)


@PROPERTY
@given(**sizes)
def test_property_symmetric_and_non_negative(seed, n_a, n_b, dim, scale):
    a, b = _pair(seed, n_a, n_b, dim, scale)
    forward, backward = fid(a, b), fid(b, a)
    assert np.isfinite(forward) and forward >= 0.0
    assert forward == pytest.approx(backward, rel=1e-7, abs=1e-9 * scale**2 * dim)


@PROPERTY
@given(**sizes)
def test_property_invariant_to_a_common_rotation_and_translation(seed, n_a, n_b, dim, scale):
    a, b = _pair(seed, n_a, n_b, dim, scale)
    rng = np.random.default_rng(seed + 1)
    rotation = special_ortho_group.rvs(dim, random_state=rng) if dim > 1 else np.array([[-1.0]])
    offset = rng.normal(size=dim) * scale
    moved = fid(a @ rotation.T + offset, b @ rotation.T + offset)
    assert moved == pytest.approx(fid(a, b), rel=1e-7, abs=1e-9 * scale**2 * dim)


@pytest.mark.parametrize(
    "a, b, match",
    [
        (np.zeros(5), np.zeros((5, 1)), "fid: a must be 2-D"),
        (np.zeros((5, 2)), np.zeros((5, 3)), "fid: a and b must have the same feature dimension"),
        (np.zeros((1, 2)), np.zeros((5, 2)), "fid: a needs at least 2 rows"),
        (np.zeros((5, 2)), np.zeros((0, 2)), "fid: b is empty"),
        (
            np.zeros((5, 2)),
            [[0.0, 1.0], [np.nan, 0.0]],
            r"fid: b contains NaN or infinite values \(first at index \(1, 0\)\)",
        ),
    ],
)
def test_bad_inputs(a, b, match):
    with pytest.raises(ValueError, match=match):
        fid(a, b)


def test_frechet_distance_rejects_invalid_covariances():
    with pytest.raises(ValueError, match="sigma1 is not symmetric"):
        frechet_distance([0, 0], [[1, 0.5], [0, 1]], [0, 0], np.eye(2))
    with pytest.raises(ValueError, match="sigma2 is not positive semi-definite"):
        frechet_distance([0, 0], np.eye(2), [0, 0], [[1, 2], [2, 1]])
    with pytest.raises(ValueError, match=r"sigma2 must be \(2, 2\)"):
        frechet_distance([0, 0], np.eye(2), [0, 0], np.eye(3))


def spread_spectrum_pair(seed: int, dim: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Two ``(n, dim)`` samples of one Gaussian whose variances run from 100 down to 1e-6 in a random
    basis."""
    rng = np.random.default_rng(seed)
    scales = np.sqrt(np.geomspace(100.0, 1e-6, dim))
    basis = special_ortho_group.rvs(dim, random_state=rng)
    return (rng.normal(size=(n, dim)) * scales) @ basis.T, (rng.normal(size=(n, dim)) * scales) @ basis.T


def test_variances_over_eight_decades_keep_the_small_cross_terms():
    """Eigenvalues of Σ1^½ Σ2 Σ1^½ are products of variances (down to 1e-12 here): all of them count.

    Discarding those below round-off of the largest (1e4) biased this FID up by 6e-4; scipy's sqrtm formula
    is accurate to ~1e-8 relative on it.
    """
    a, b = spread_spectrum_pair(0, dim=256, n=3000)
    assert fid(a, b) == pytest.approx(scipy_fid(a, b), rel=1e-7)
    assert frechet_distance(*feature_statistics(a), *feature_statistics(b)) == pytest.approx(
        fid(a, b), rel=1e-10
    )


def test_commuting_covariances_over_eight_decades_closed_form():
    """Σ1 = U diag(v1) Uᵀ and Σ2 = U diag(v2) Uᵀ: the cross term is Σ √(v1 v2), exactly."""
    rng = np.random.default_rng(8)
    dim = 64
    basis = special_ortho_group.rvs(dim, random_state=rng)
    var_a = np.geomspace(100.0, 1e-6, dim)
    var_b = var_a * rng.uniform(0.25, 4.0, size=dim)
    mean_a, mean_b = rng.normal(size=dim), rng.normal(size=dim)
    expected = ((mean_a - mean_b) ** 2).sum() + ((np.sqrt(var_a) - np.sqrt(var_b)) ** 2).sum()
    sigma_a, sigma_b = (basis * var_a) @ basis.T, (basis * var_b) @ basis.T
    assert frechet_distance(basis @ mean_a, sigma_a, basis @ mean_b, sigma_b) == pytest.approx(
        expected, rel=1e-11
    )
    a = with_exact_covariance(rng, 200, var_a, mean_a) @ basis.T
    b = with_exact_covariance(rng, 300, var_b, mean_b) @ basis.T
    assert fid(a, b) == pytest.approx(expected, rel=1e-11)


@pytest.mark.parametrize("seed", range(3))
def test_frechet_distance_of_a_low_rank_and_a_full_rank_covariance_matches_fid(seed):
    """Σ1 of rank 4 in 50-D against a full-rank Σ2: Σ1's round-off eigenvalues must not pair with Σ2's
    variances."""
    rng = np.random.default_rng(seed)
    basis = np.linalg.qr(rng.normal(size=(50, 4)))[0]
    a = rng.normal(size=(12, 4)) @ basis.T * 3.0
    b = rng.normal(size=(200, 50)) @ rng.normal(size=(50, 50)) * 0.3
    from_statistics = frechet_distance(*feature_statistics(a), *feature_statistics(b))
    assert from_statistics == pytest.approx(fid(a, b), rel=1e-12)
