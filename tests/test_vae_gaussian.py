"""Gaussian helpers against torch.distributions and hand computations."""

from __future__ import annotations

import math

import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from torch.distributions import Normal, kl_divergence

from motionlab.models.gaussian import gaussian_kl, gaussian_nll, reparameterize
from motionlab.models.vae.evaluate import active_units, kl_per_dimension, unit_activity


def _random_params(seed: int, shape=(7, 5)):
    g = torch.Generator().manual_seed(seed)
    mu = torch.randn(shape, generator=g, dtype=torch.float64) * 2
    logvar = torch.randn(shape, generator=g, dtype=torch.float64)
    return mu, logvar


@given(seed=st.integers(0, 10_000))
@settings(max_examples=25, deadline=None)
def test_kl_standard_prior_matches_torch(seed):
    mu, logvar = _random_params(seed)
    ours = gaussian_kl(mu, logvar)
    ref = kl_divergence(Normal(mu, torch.exp(0.5 * logvar)), Normal(0.0, 1.0))
    assert torch.allclose(ours, ref, atol=1e-10)


@given(seed=st.integers(0, 10_000))
@settings(max_examples=25, deadline=None)
def test_kl_general_prior_matches_torch(seed):
    mu, logvar = _random_params(seed)
    p_mu, p_logvar = _random_params(seed + 1, shape=(5,))
    ours = gaussian_kl(mu, logvar, p_mu, p_logvar)
    ref = kl_divergence(Normal(mu, torch.exp(0.5 * logvar)), Normal(p_mu, torch.exp(0.5 * p_logvar)))
    assert ours.shape == mu.shape
    assert torch.allclose(ours, ref, atol=1e-10)


def test_kl_hand_values():
    # N(1, 1) against N(0, 1): mu^2 / 2.
    assert gaussian_kl(torch.tensor([1.0]), torch.tensor([0.0])).item() == pytest.approx(0.5)
    # N(0, e) against N(0, 1): 0.5 * (e - 1 - 1).
    assert gaussian_kl(torch.tensor([0.0]), torch.tensor([1.0])).item() == pytest.approx(0.5 * (math.e - 2))
    # Equal distributions: zero; float prior arguments work.
    assert gaussian_kl(torch.tensor([0.3]), torch.tensor([math.log(0.05)]), 0.3, math.log(0.05)).item() == (
        pytest.approx(0.0, abs=1e-7)
    )


def test_kl_per_dimension_and_active_units():
    mu = torch.zeros(100, 3)
    mu[:, 0] = torch.linspace(-1, 1, 100)  # variance ~0.34: active
    mu[:, 1] = torch.linspace(-0.05, 0.05, 100)  # variance ~0.0009: inactive
    logvar = torch.zeros(100, 3)
    kl = kl_per_dimension(mu, logvar)
    assert kl.shape == (3,)
    assert torch.allclose(kl, 0.5 * (mu**2).mean(0))
    assert torch.allclose(unit_activity(mu), mu.var(0))
    assert active_units(mu) == 1
    assert active_units(mu, threshold=1e-4) == 2


def test_reparameterize_moments_and_gradient():
    mu = torch.tensor([1.0, -2.0], requires_grad=True)
    logvar = torch.tensor([0.0, math.log(0.25)], requires_grad=True)
    z = reparameterize(mu.expand(200_000, 2), logvar.expand(200_000, 2), torch.Generator().manual_seed(0))
    assert torch.allclose(z.mean(0), mu.detach(), atol=0.01)
    assert torch.allclose(z.std(0), torch.tensor([1.0, 0.5]), atol=0.01)
    z.mean().backward()
    assert mu.grad is not None and logvar.grad is not None


def test_reparameterize_is_deterministic_by_seed():
    mu, logvar = _random_params(3)
    a = reparameterize(mu, logvar, torch.Generator().manual_seed(5))
    b = reparameterize(mu, logvar, torch.Generator().manual_seed(5))
    assert torch.equal(a, b)


def test_gaussian_nll_matches_torch():
    mu, logvar = _random_params(4)
    x = torch.randn(mu.shape, generator=torch.Generator().manual_seed(9), dtype=torch.float64)
    ref = -Normal(mu, torch.exp(0.5 * logvar)).log_prob(x)
    assert torch.allclose(gaussian_nll(x, mu, logvar), ref, atol=1e-10)
    assert torch.allclose(gaussian_nll(x, mu), -Normal(mu, 1.0).log_prob(x), atol=1e-10)


def test_bad_inputs_raise():
    mu = torch.zeros(4, 3)
    with pytest.raises(ValueError, match="gaussian_kl: mu and logvar must have the same shape"):
        gaussian_kl(mu, torch.zeros(4, 2))
    with pytest.raises(ValueError, match="gaussian_kl: logvar contains NaN"):
        gaussian_kl(mu, torch.full((4, 3), float("nan")))
    with pytest.raises(ValueError, match="prior_logvar of shape"):
        gaussian_kl(mu, mu, prior_logvar=torch.zeros(2))
    with pytest.raises(TypeError, match="reparameterize: mu must be a torch.Tensor"):
        reparameterize([0.0], torch.zeros(1))
    with pytest.raises(TypeError, match="gaussian_nll: x must have a floating-point dtype"):
        gaussian_nll(torch.zeros(3, dtype=torch.long), torch.zeros(3))
    with pytest.raises(ValueError, match="unit_activity: mu must be 2-dimensional"):
        active_units(torch.zeros(3))
    with pytest.raises(ValueError, match="unit_activity: mu must hold at least 2 rows"):
        active_units(torch.zeros(1, 3))
    with pytest.raises(ValueError, match="active_units: threshold must be greater than 0"):
        active_units(mu, threshold=0.0)
