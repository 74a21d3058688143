"""Multi-scale Glow, squeeze along time, prior and the diagonal-Gaussian baseline."""

import math

import numpy as np
import pytest
import torch
from scipy import stats

from motionlab.models.flows import (
    DiagonalGaussian,
    Glow,
    GlowConfig,
    StandardNormal,
    logdet_error,
    perturb_parameters_,
    roundtrip_error,
    squeeze_time,
    unsqueeze_time,
)


def test_squeeze_time_layout_and_inverse():
    x = torch.arange(2 * 3 * 4, dtype=torch.float32).reshape(2, 3, 4)
    s = squeeze_time(x)
    assert s.shape == (2, 6, 2)
    # channel 2c holds channel c of the even frames, 2c + 1 of the odd ones
    assert torch.equal(s[:, 0], x[:, 0, 0::2]) and torch.equal(s[:, 1], x[:, 0, 1::2])
    assert torch.equal(s[:, 4], x[:, 2, 0::2]) and torch.equal(s[:, 5], x[:, 2, 1::2])
    assert torch.equal(unsqueeze_time(s), x)


def _small_glow(dtype=torch.float64) -> Glow:
    torch.manual_seed(0)
    glow = Glow(GlowConfig(channels=4, length=8, cond_channels=2, levels=2, steps_per_level=2, hidden=8)).to(
        dtype
    )
    return perturb_parameters_(glow, 0.2, torch.Generator().manual_seed(1)).eval()


def test_multiscale_glow_logdet_and_roundtrip():
    glow = _small_glow()
    generator = torch.Generator().manual_seed(2)
    x = torch.randn(2, 4, 8, dtype=torch.float64, generator=generator)
    cond = torch.randn(2, 2, 8, dtype=torch.float64, generator=generator)
    assert logdet_error(glow, x, cond) < 1e-9
    assert roundtrip_error(glow, x, cond) < 1e-12
    z, logdet = glow(x, cond)
    assert z.shape == x.shape
    expected = torch.distributions.Normal(0.0, 1.0).log_prob(z).sum(dim=(1, 2)) + logdet
    assert torch.allclose(glow.log_prob(x, cond), expected)


def test_glow_levels_see_the_conditioning():
    glow = _small_glow()
    x = torch.randn(1, 4, 8, dtype=torch.float64)
    cond = torch.randn(1, 2, 8, dtype=torch.float64)
    assert not torch.allclose(glow.log_prob(x, cond), glow.log_prob(x, cond + 1.0))


def test_sampling_is_deterministic_by_seed_and_temperature_zero_is_the_mode_path():
    glow = _small_glow(torch.float32)
    cond = torch.randn(3, 2, 8)
    a = glow.sample(cond, temperature=0.7, generator=torch.Generator().manual_seed(5))
    b = glow.sample(cond, temperature=0.7, generator=torch.Generator().manual_seed(5))
    c = glow.sample(cond, temperature=0.7, generator=torch.Generator().manual_seed(6))
    assert torch.equal(a, b) and not torch.equal(a, c)
    zero = glow.sample(cond, temperature=0.0, generator=torch.Generator().manual_seed(5))
    assert torch.allclose(zero, glow.inverse(torch.zeros(3, 4, 8), cond))


def test_glow_config_and_input_errors():
    with pytest.raises(ValueError, match="divisible"):
        GlowConfig(channels=4, length=6, levels=2)
    with pytest.raises(ValueError, match="odd"):
        GlowConfig(channels=4, length=8, kernel_size=2)
    glow = _small_glow()
    with pytest.raises(ValueError, match="8 frames"):
        glow.log_prob(torch.randn(1, 4, 16, dtype=torch.float64), torch.randn(1, 2, 16, dtype=torch.float64))
    with pytest.raises(ValueError, match="Glow.sample: temperature must be at least 0, got -1.0"):
        glow.sample(torch.randn(1, 2, 8, dtype=torch.float64), temperature=-1.0)
    with pytest.raises(TypeError, match="Glow.sample: temperature must be a real number"):
        glow.sample(torch.randn(1, 2, 8, dtype=torch.float64), temperature="hot")
    with pytest.raises(TypeError, match="GlowConfig: levels must be an integer, got 2.0"):
        GlowConfig(channels=4, length=8, levels=2.0)
    with pytest.raises(
        ValueError, match=r"Glow.forward: x contains NaN or infinite values \(first at index \(0, 0, 0\)\)"
    ):
        nan = torch.full((1, 4, 8), float("nan"), dtype=torch.float64)
        glow.log_prob(nan, torch.zeros(1, 2, 8, dtype=torch.float64))


def test_standard_normal_matches_torch_distributions():
    prior = StandardNormal()
    z = torch.randn(5, 3, 4, dtype=torch.float64)
    expected = torch.distributions.Normal(0.0, 1.0).log_prob(z).sum(dim=(1, 2))
    assert torch.allclose(prior.log_prob(z), expected)
    sample = prior.sample((20000, 2), temperature=0.5, generator=torch.Generator().manual_seed(0))
    assert abs(float(sample.std()) - 0.5) < 0.01
    with pytest.raises(
        ValueError, match="StandardNormal.sample: temperature must be a finite number, got nan"
    ):
        prior.sample((2,), temperature=float("nan"))
    with pytest.raises(TypeError, match="StandardNormal.log_prob: z must be a torch.Tensor"):
        prior.log_prob([0.0, 1.0])


def test_diagonal_gaussian_matches_scipy():
    generator = torch.Generator().manual_seed(0)
    x = (
        torch.randn(40, 3, 7, generator=generator, dtype=torch.float64)
        * torch.tensor([1.0, 2.0, 0.1], dtype=torch.float64)[:, None]
    )
    model = DiagonalGaussian(3).fit(x)
    values = x.transpose(0, 1).reshape(3, -1).numpy()
    np.testing.assert_allclose(model.mean.numpy(), values.mean(1))
    np.testing.assert_allclose(model.std.numpy(), values.std(1))
    test = torch.randn(4, 3, 7, dtype=torch.float64)
    expected = stats.norm.logpdf(
        test.numpy(), model.mean.numpy()[None, :, None], model.std.numpy()[None, :, None]
    )
    np.testing.assert_allclose(model.log_prob(test).numpy(), expected.sum(axis=(1, 2)), rtol=1e-6)
    assert math.isfinite(float(model.log_prob(test).sum()))
    with pytest.raises(
        ValueError, match=r"DiagonalGaussian.log_prob: x must have shape \(\.\.\., 3, \*\), got \(1, 2, 7\)"
    ):
        model.log_prob(torch.randn(1, 2, 7))
