"""MDM's noise schedule against independent oracles: the cosine formula in NumPy, the one-step forward
process iterated, Bayes' rule on a grid with torch.distributions, respacing, and the DDIM step."""

import math

import numpy as np
import pytest
import torch
from scipy import stats

from motionlab.models.diffusion.schedule import NoiseSchedule, cosine_betas, evenly_spaced


@pytest.fixture(scope="module")
def schedule() -> NoiseSchedule:
    return NoiseSchedule.cosine(1000)


def test_cosine_betas_follow_nichol_and_dhariwal():
    n = 1000
    s = np.arange(n + 1) / n
    alpha_bar = np.cos((s + 0.008) / 1.008 * np.pi / 2) ** 2
    betas = np.minimum(1 - alpha_bar[1:] / alpha_bar[:-1], 0.999)
    assert np.allclose(cosine_betas(n).numpy(), betas, rtol=1e-12, atol=0)
    # away from the cap, the cumulative product is the continuous alpha-bar at (i + 1) / S over its value at 0
    product = NoiseSchedule.cosine(n).alphas_cumprod.numpy()
    assert np.allclose(product[:-1], (alpha_bar[1:] / alpha_bar[0])[:-1], rtol=1e-9)
    assert betas[-1] == 0.999 and np.all(betas[:-1] < 0.999)


def test_closed_form_marginal_equals_the_one_step_process_iterated(schedule):
    # exactly, in mean and variance: m <- sqrt(1 - b) m, v <- (1 - b) v + b, from x0 = 1.7 (variance 0)
    x0 = 1.7
    mean, variance = x0, 0.0
    means, variances = [], []
    for beta in schedule.betas.tolist():
        mean, variance = math.sqrt(1 - beta) * mean, (1 - beta) * variance + beta
        means.append(mean)
        variances.append(variance)
    alpha_bar = schedule.alphas_cumprod
    assert np.allclose(means, (alpha_bar.sqrt() * x0).numpy(), rtol=1e-9, atol=1e-12)
    assert np.allclose(variances, (1 - alpha_bar).numpy(), rtol=1e-9, atol=1e-12)


def test_q_sample_draws_match_iterated_draws_statistically():
    schedule = NoiseSchedule.cosine(50)
    generator = torch.Generator().manual_seed(0)
    n, step = 20_000, 30
    x0 = torch.full((n, 1), -0.8, dtype=torch.float64)
    iterated = x0.clone()
    for beta in schedule.betas[: step + 1].tolist():
        iterated = math.sqrt(1 - beta) * iterated + math.sqrt(beta) * torch.randn(
            n, 1, generator=generator, dtype=torch.float64
        )
    t = torch.full((n,), step)
    direct = schedule.q_sample(x0, t, torch.randn(n, 1, generator=generator, dtype=torch.float64))
    result = stats.ks_2samp(iterated.flatten().numpy(), direct.flatten().numpy())
    assert result.pvalue > 1e-3


def test_posterior_is_bayes_rule_on_a_grid(schedule):
    # prior x_{t-1} | x0 ~ N(sqrt(ab_prev) x0, 1 - ab_prev)
    # likelihood x_t | x_{t-1} ~ N(sqrt(a_t) x_{t-1}, b_t)
    grid = torch.linspace(-8, 8, 400_001, dtype=torch.float64)
    x0, xt = 0.6, -0.4
    for step in (1, 10, 500, 998):
        alpha_bar_prev = float(schedule.alphas_cumprod[step - 1])
        beta = float(schedule.betas[step])
        prior = torch.distributions.Normal(math.sqrt(alpha_bar_prev) * x0, math.sqrt(1 - alpha_bar_prev))
        likelihood = torch.distributions.Normal(math.sqrt(1 - beta) * grid, math.sqrt(beta))
        log_density = prior.log_prob(grid) + likelihood.log_prob(torch.tensor(xt, dtype=torch.float64))
        weights = torch.softmax(log_density, dim=0)
        mean = float((weights * grid).sum())
        variance = float((weights * (grid - mean) ** 2).sum())
        got_mean, got_variance = schedule.posterior(
            torch.tensor([[x0]], dtype=torch.float64),
            torch.tensor([[xt]], dtype=torch.float64),
            torch.tensor([step]),
        )
        assert got_mean.item() == pytest.approx(mean, abs=1e-6)
        assert got_variance.item() == pytest.approx(variance, rel=1e-4)


def test_posterior_at_the_first_step_is_x0_without_variance(schedule):
    x0, xt = torch.randn(3, 5, 2), torch.randn(3, 5, 2)
    mean, variance = schedule.posterior(x0, xt, torch.zeros(3, dtype=torch.int64))
    assert torch.allclose(mean, x0, atol=1e-6) and torch.all(variance == 0)


def test_respacing_keeps_the_chosen_alphas_cumprod(schedule):
    for count in (1, 10, 50, 999, 1000):
        spaced = schedule.respace(count)
        kept = evenly_spaced(1000, count)
        assert spaced.n_steps == count and spaced.timesteps.tolist() == kept
        # the recomputed betas multiply back to exactly the kept cumulative products
        assert torch.allclose(spaced.alphas_cumprod, schedule.alphas_cumprod[kept], rtol=1e-9, atol=0)
    assert evenly_spaced(1000, 10)[0] == 0 and evenly_spaced(1000, 10)[-1] == 999
    full = schedule.respace(1000)
    assert torch.allclose(full.betas, schedule.betas, rtol=1e-10, atol=0)


def test_ddim_without_noise_retraces_the_forward_noise(schedule):
    # eta = 0: with the exact x0, a step from q_sample(x0, t, eps) lands on q_sample(x0, t - 1, eps)
    spaced = schedule.respace(20)
    x0, eps = torch.randn(4, 6, 3, dtype=torch.float64), torch.randn(4, 6, 3, dtype=torch.float64)
    t = torch.tensor([19, 12, 5, 1])
    xt = spaced.q_sample(x0, t, eps)
    stepped = spaced.ddim_step(xt, t, x0, torch.randn_like(x0), eta=0.0)
    assert torch.allclose(stepped, spaced.q_sample(x0, t - 1, eps), atol=1e-10)
    last = spaced.ddim_step(xt, torch.zeros(4, dtype=torch.int64), x0, torch.randn_like(x0))
    assert torch.allclose(last, x0, atol=1e-12)


def test_ddim_with_eta_one_has_the_posterior_variance(schedule):
    x0, xt = torch.randn(2, 4, dtype=torch.float64), torch.randn(2, 4, dtype=torch.float64)
    t = torch.tensor([300, 7])
    quiet = schedule.ddim_step(xt, t, x0, torch.zeros_like(x0), eta=1.0)
    noisy = schedule.ddim_step(xt, t, x0, torch.ones_like(x0), eta=1.0)
    _, variance = schedule.posterior(x0, xt, t)
    assert torch.allclose((noisy - quiet) ** 2, variance.expand_as(x0), rtol=1e-9)


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda s: NoiseSchedule.cosine(0), ValueError, "n_steps"),
        (lambda s: NoiseSchedule(torch.tensor([0.1, 1.5]), torch.arange(2)), ValueError, "betas"),
        (lambda s: NoiseSchedule(torch.tensor([0.1, 0.2]), torch.tensor([0.0, 1.0])), TypeError, "timesteps"),
        (lambda s: NoiseSchedule(torch.tensor([0.1, 0.2]), torch.tensor([1, 1])), ValueError, "timesteps"),
        (lambda s: s.respace(0), ValueError, "count"),
        (lambda s: s.respace(1001), ValueError, "count"),
        (
            lambda s: s.q_sample(torch.zeros(2, 3), torch.tensor([0.0, 1.0]), torch.zeros(2, 3)),
            TypeError,
            "t must",
        ),
        (
            lambda s: s.q_sample(torch.zeros(2, 3), torch.tensor([0, 1000]), torch.zeros(2, 3)),
            ValueError,
            "steps",
        ),
        (lambda s: s.q_sample(torch.zeros(2, 3), torch.tensor([0]), torch.zeros(2, 3)), ValueError, "t must"),
        (
            lambda s: s.q_sample(torch.zeros(2, 3), torch.tensor([0, 1]), torch.zeros(2, 4)),
            ValueError,
            "noise",
        ),
        (lambda s: s.posterior(torch.zeros(2, 3), torch.zeros(3, 3), torch.tensor([0, 1])), ValueError, "xt"),
        (
            lambda s: s.ddim_step(
                *[torch.zeros(1, 2)] * 1, torch.tensor([1]), torch.zeros(1, 2), torch.zeros(1, 2), eta=2.0
            ),
            ValueError,
            "eta",
        ),
        (lambda s: s.q_sample([0.0], torch.tensor([0]), torch.zeros(1)), TypeError, "x0"),
    ],
)
def test_bad_inputs_raise_clear_errors(schedule, call, error, match):
    with pytest.raises(error, match=match):
        call(schedule)
