"""Chapter 03's exercises: the negative ELBO of one batch, checked against
:func:`motionlab.models.vae.losses.negative_elbo`, and (in its appendix) the reparameterisation trick and the
closed-form Gaussian KL, checked against :mod:`motionlab.models.gaussian`; and chapter 08's σ₀² prior on the
code covariance (ODMO's eq. 1), checked
against :func:`motionlab.models.odmo.losses.prior_term`."""

from __future__ import annotations

import math
from collections.abc import Callable

import torch

from motionlab.exercises.checking import CheckResult, Diagnosis, as_result, checker, close
from motionlab.models.gaussian import gaussian_kl
from motionlab.models.odmo.losses import prior_term
from motionlab.models.vae.losses import negative_elbo

Reparameterize = Callable[[torch.Tensor, torch.Tensor, torch.Generator], torch.Tensor]
GaussianKL = Callable[[torch.Tensor, torch.Tensor], torch.Tensor]
CovariancePrior = Callable[[torch.Tensor, torch.Tensor, float], torch.Tensor]


def _posterior(n: int, seed: int) -> tuple[torch.Tensor, torch.Tensor]:
    generator = torch.Generator().manual_seed(seed)
    mu = torch.randn(n, 3, generator=generator, dtype=torch.float64)
    logvar = torch.tensor([-1.5, 0.0, 1.0], dtype=torch.float64).expand(n, 3).clone()
    return mu, logvar


def _draws_have_the_right_moments(fn: Reparameterize) -> None:
    mu, logvar = _posterior(1, 1)
    mu, logvar = mu.expand(200_000, 3), logvar.expand(200_000, 3)
    z = as_result(fn(mu, logvar, torch.Generator().manual_seed(0)), "reparameterize")
    if z.shape != mu.shape:
        raise Diagnosis(
            f"mu and logvar of shape (200000, 3) should give z of the same shape, got {tuple(z.shape)}"
        )
    mean, std = z.mean(0), z.std(0)
    want_std = torch.exp(0.5 * logvar[0])
    if not torch.allclose(mean, mu[0], atol=0.02 * float(want_std.max())):
        raise Diagnosis(
            f"the draws' mean is {mean.tolist()}, not mu = {mu[0].tolist()}: z = mu + sigma * eps"
        )
    if torch.allclose(std, want_std, rtol=0.02):
        return
    for wrong, text in (
        (torch.exp(logvar[0]), "exp(logvar) is the variance, not the standard deviation"),
        (logvar[0].abs().sqrt(), "logvar is the log of the variance: sigma = exp(logvar / 2)"),
        (torch.ones(3, dtype=mu.dtype), "the spread ignores logvar: scale eps by sigma = exp(logvar / 2)"),
    ):
        if torch.allclose(std, wrong, rtol=0.02):
            raise Diagnosis(f"the draws' standard deviations are {std.tolist()}: {text}")
    raise Diagnosis(f"the draws' standard deviations are {std.tolist()}, not sigma = {want_std.tolist()}")


def _draws_are_differentiable_and_seeded(fn: Reparameterize) -> None:
    mu, logvar = _posterior(4, 2)
    mu.requires_grad_(True)
    logvar.requires_grad_(True)
    z = as_result(fn(mu, logvar, torch.Generator().manual_seed(5)), "reparameterize")
    if not z.requires_grad:
        raise Diagnosis(
            "no gradient reaches mu or logvar: draw eps ~ N(0, I) and compute z = mu + sigma * eps"
        )
    z.sum().backward()
    if logvar.grad is None or not bool(logvar.grad.abs().sum() > 0):
        raise Diagnosis(
            "no gradient reaches logvar (torch.normal(mu, std) does not pass one): draw eps ~ N(0, I) with "
            "torch.randn and compute z = mu + sigma * eps"
        )
    again = fn(mu.detach(), logvar.detach(), torch.Generator().manual_seed(5))
    if not close(z.detach(), again):
        raise Diagnosis("the same generator seed gave different draws: pass the generator to torch.randn")


@checker(
    [_draws_have_the_right_moments, _draws_are_differentiable_and_seeded],
    "right mean and spread over 200,000 draws, gradients reach mu and logvar, seeded by the generator",
)
def check_reparameterize(fn: Reparameterize) -> CheckResult:
    """Check ``fn(mu, logvar, generator) -> z`` drawing from N(mu, exp(logvar)) differentiably."""


def _kl_values(fn: GaussianKL) -> None:
    mu, logvar = _posterior(5, 3)
    got = as_result(fn(mu, logvar), "gaussian_kl")
    want = gaussian_kl(mu, logvar)
    if got.shape != want.shape:
        if got.shape in ((5,), (5, 1)) and close(got.reshape(5), want.sum(-1)):
            raise Diagnosis("you summed over dimensions: return the KL per dimension, shape (..., D)")
        raise Diagnosis(
            f"mu and logvar of shape (5, 3) should give a KL of shape (5, 3), got {tuple(got.shape)}"
        )
    if close(got, want):
        return
    for wrong, text in (
        (-want, "the sign is flipped: a KL is never negative"),
        (2 * want, "you forgot the factor 1/2"),
        (want + 0.5, "you forgot the -1 inside the bracket (the KL of a distribution with itself is 0)"),
        (0.5 * (mu**2 + logvar.exp() ** 2 - 1 - 2 * logvar), "exp(logvar) is already the variance"),
    ):
        if close(got, wrong):
            raise Diagnosis(text)
    raise Diagnosis(
        f"for mu = {mu[0, 0].item():.3f}, logvar = {logvar[0, 0].item():.1f} you gave "
        f"{got[0, 0].item():.4f}, the KL is {want[0, 0].item():.4f}: 1/2 (mu^2 + sigma^2 - 1 - log sigma^2)"
    )


def _kl_is_zero_at_the_prior(fn: GaussianKL) -> None:
    zero = torch.zeros(2, 4, dtype=torch.float64, requires_grad=True)
    got = as_result(fn(zero, torch.zeros(2, 4, dtype=torch.float64)), "gaussian_kl")
    if not close(got, torch.zeros_like(got)):
        raise Diagnosis("KL(N(0, 1) || N(0, 1)) should be 0 in every dimension")
    if not got.requires_grad:
        raise Diagnosis("no gradient reaches mu: compute with torch operations only")


@checker(
    [_kl_values, _kl_is_zero_at_the_prior],
    "matches motionlab.models.gaussian.gaussian_kl per dimension, 0 at the prior, with gradients",
)
def check_gaussian_kl(fn: GaussianKL) -> CheckResult:
    """Check ``fn(mu, logvar)``, the KL of N(mu, exp(logvar)) from N(0, I) per dimension, ``(..., D)``."""


def _covariance_reference(mu: torch.Tensor, logvar: torch.Tensor, prior_variance: float) -> torch.Tensor:
    """Eq. 1's term ``(B,)``: the package's ``prior_term(..., "covariance")`` plus its minimum,
    ``D (1 - ln σ₀²)``."""
    minimum = logvar.shape[-1] * (1.0 - math.log(prior_variance))
    return prior_term(mu, logvar, prior_variance, "covariance") + minimum


def _covariance_values(fn: CovariancePrior) -> None:
    generator = torch.Generator().manual_seed(4)
    mu = 3.0 * torch.randn(5, 6, generator=generator, dtype=torch.float64)
    logvar = torch.randn(5, 6, generator=generator, dtype=torch.float64) - 2.0
    sigma2 = 0.05
    got = as_result(fn(mu, logvar, sigma2), "covariance_prior")
    want = _covariance_reference(mu, logvar, sigma2)
    per_dimension = logvar.exp() / sigma2 - logvar
    if got.shape == per_dimension.shape and close(got, per_dimension):
        raise Diagnosis("return one value per clip (B,): sum over the D code dimensions")
    if got.shape != want.shape:
        raise Diagnosis(f"mu and logvar (5, 6) should give one value per clip, (5,), got {tuple(got.shape)}")
    if close(got, want):
        return
    variance = logvar.exp()
    for wrong, text in (
        (want + (mu**2).sum(-1) / sigma2, "the paper puts no prior on the means: drop the mu^2 / σ₀² term"),
        (want + (mu**2).sum(-1), "the paper puts no prior on the means: drop the mu^2 term"),
        ((variance / sigma2 + logvar).sum(-1), "wrong sign of the log-determinant: -ln det Σ = -sum logvar"),
        (
            (variance / sigma2**2 - logvar).sum(-1),
            "prior_variance is σ₀² already, a variance: divide by it, not its square",
        ),
        (
            (variance / sigma2**0.5 - logvar).sum(-1),
            "prior_variance is σ₀², a variance: divide by it, not its root",
        ),
        ((variance * sigma2 - logvar).sum(-1), "Tr Σ is divided by σ₀², not multiplied"),
        ((logvar / sigma2 - logvar).sum(-1), "logvar is log σ²: the trace needs the variances exp(logvar)"),
        (
            (logvar.exp().sqrt() / sigma2 - logvar).sum(-1),
            "Σ = diag(σ²): exp(logvar) is σ², not exp(logvar / 2)",
        ),
        (0.5 * want, "eq. 1's term has no factor 1/2: -ln det Σ + Tr Σ / σ₀²"),
        (
            want - logvar.shape[-1] * (1 - math.log(sigma2)),
            "that is the package's prior_term, the term minus its minimum; write eq. 1's term itself, "
            "-ln det Σ + Tr Σ / σ₀²",
        ),
    ):
        if close(got, wrong):
            raise Diagnosis(text)
    raise Diagnosis("the term is wrong: sum over the code coordinates i of exp(logvar_i) / σ₀² - logvar_i")


def _covariance_minimum_and_gradient(fn: CovariancePrior) -> None:
    sigma2 = 0.3
    logvar = torch.full((2, 4), math.log(sigma2), dtype=torch.float64, requires_grad=True)
    mu = torch.zeros(2, 4, dtype=torch.float64)
    got = as_result(fn(mu, logvar, sigma2), "covariance_prior")
    if not close(got, _covariance_reference(mu, logvar.detach(), sigma2)):
        raise Diagnosis(
            f"wrong for σ₀² = {sigma2} at its minimum σ² = σ₀²: use prior_variance, not a constant"
        )
    if not got.requires_grad:
        raise Diagnosis("no gradient reaches logvar: compute with torch operations only")
    (gradient,) = torch.autograd.grad(got.sum(), logvar)
    if not close(gradient, torch.zeros_like(gradient)):
        raise Diagnosis("the gradient should vanish at σ² = σ₀², the term's minimum")


@checker(
    [_covariance_values, _covariance_minimum_and_gradient],
    "matches eq. 1's covariance term (the package's prior_term plus its minimum), smallest at σ² = σ₀²",
)
def check_covariance_prior(fn: CovariancePrior) -> CheckResult:
    """Check ``fn(mu, logvar, prior_variance) -> (B,)``: ODMO's eq. 1 prior term ``-ln det Σ + Tr Σ / σ₀²``
    for ``Σ = diag(exp(logvar))``, codes ``(B, D)``, no term on ``mu``."""


NegativeElbo = Callable[
    [torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor, Callable[[torch.Tensor], torch.Tensor], float],
    tuple[torch.Tensor, torch.Tensor],
]


def _elbo_inputs(seed: int) -> tuple[torch.Tensor, ...]:
    """A batch of 5 examples ``(5, 4, 2)``, codes of 3 dimensions and a fixed nonlinear decoder's weights."""
    generator = torch.Generator().manual_seed(seed)
    x = torch.randn(5, 4, 2, generator=generator, dtype=torch.float64)
    mu = torch.randn(5, 3, generator=generator, dtype=torch.float64)
    logvar = torch.tensor([-1.5, 0.3, 1.0], dtype=torch.float64).expand(5, 3).clone()
    eps = torch.randn(5, 3, generator=generator, dtype=torch.float64)
    weight = torch.randn(3, 8, generator=generator, dtype=torch.float64)
    return x, mu, logvar, eps, weight


def _elbo_terms(fn: NegativeElbo, seed: int, obs_var: float) -> tuple[torch.Tensor, ...]:
    """The reader's two terms and the reference's, on the inputs of ``seed``."""
    x, mu, logvar, eps, weight = _elbo_inputs(seed)

    def decode(z: torch.Tensor) -> torch.Tensor:
        return torch.tanh(z @ weight).reshape(-1, 4, 2)

    result = fn(x, mu, logvar, eps, decode, obs_var)
    if not isinstance(result, tuple) or len(result) != 2:
        raise Diagnosis(f"return the two terms as a tuple (recon, kl), got {type(result).__name__}")
    recon, kl = (as_result(term, "negative_elbo") for term in result)
    want_recon, want_kl = negative_elbo(x, mu, logvar, eps, decode, obs_var)
    return recon, kl, want_recon, want_kl, x, mu, logvar, eps, decode


def _one_per_example(term: torch.Tensor, want: torch.Tensor, name: str) -> None:
    if term.shape == want.shape:
        return
    if term.shape == ():
        raise Diagnosis(f"{name} is one number: return one value per example, shape (B,), not the batch mean")
    raise Diagnosis(
        f"{name} should have one value per example, shape {tuple(want.shape)}, got {tuple(term.shape)}"
    )


def _elbo_kl(fn: NegativeElbo) -> None:
    _, kl, _, want, _, mu, logvar, _, _ = _elbo_terms(fn, 6, 0.5)
    if kl.shape == mu.shape and close(kl.sum(-1), want):
        raise Diagnosis("kl is per dimension: sum it over the latent dimensions, one value per example")
    _one_per_example(kl, want, "kl")
    if close(kl, want):
        return
    variance = logvar.exp()
    for wrong, text in (
        (-want, "the KL's sign is flipped: a KL is never negative, and the loss adds it"),
        (2 * want, "the KL lost its factor 1/2"),
        (want + 0.5 * mu.shape[-1], "the KL lost its -1 (the KL of the prior with itself is 0)"),
        (
            0.5 * (mu**2 + variance**2 - 1 - 2 * logvar).sum(-1),
            "exp(logvar) is already the variance σ², not σ",
        ),
        (0.5 * (mu**2 - 1).sum(-1), "logvar is log σ², not σ²: σ² = exp(logvar)"),
        (
            0.5 * (mu**2 + variance.sqrt() - 1 - 0.5 * logvar).sum(-1),
            "the KL uses the variance σ² = exp(logvar), not the standard deviation",
        ),
        (0.5 * (mu**2 + variance - 1 + logvar).sum(-1), "the sign of log σ² in the KL is flipped"),
    ):
        if wrong.shape == kl.shape and close(kl, wrong):
            raise Diagnosis(text)
    raise Diagnosis("kl is wrong: it should be the closed-form KL of N(mu, exp(logvar)) from N(0, 1), summed")


def _elbo_recon(fn: NegativeElbo) -> None:
    recon, _, want, _, x, mu, logvar, eps, decode = _elbo_terms(fn, 7, 0.5)
    _one_per_example(recon, want, "recon")
    if close(recon, want):
        return

    def squared_error(z: torch.Tensor) -> torch.Tensor:
        return ((x - decode(z)) ** 2).flatten(1).sum(-1)

    obs_var, sigma = 0.5, torch.exp(0.5 * logvar)
    constant = 0.5 * math.log(2 * math.pi * obs_var) * x[0].numel()
    for wrong, text in (
        (2 * want, "recon lost its factor 1/2: -log N(x; x̂, σ_x²) = |x - x̂|² / (2 σ_x²) + const"),
        (want * obs_var, "recon is not divided by σ_x² (obs_var)"),
        (want * obs_var**2, "recon is multiplied by σ_x² instead of divided by it"),
        (want + constant, "drop the constant 0.5 log(2π σ_x²) per number: it has no gradient"),
        (
            want / x[0].numel(),
            "recon is a mean over an example's numbers: sum them (the likelihood multiplies over all)",
        ),
        (0.5 * squared_error(mu) / obs_var, "the decoder got mu, not a draw: z = mu + σ * eps"),
        (0.5 * squared_error(mu + logvar.exp() * eps) / obs_var, "z used exp(logvar), the variance, as σ"),
        (0.5 * squared_error(mu + logvar * eps) / obs_var, "z used logvar as σ: σ = exp(logvar / 2)"),
        (0.5 * squared_error(eps) / obs_var, "the decoder got eps alone: z = mu + σ * eps"),
        (
            0.5 * squared_error(mu + sigma * eps).sqrt() / obs_var,
            "recon needs the squared error, not the norm",
        ),
    ):
        if close(recon, wrong):
            raise Diagnosis(text)
    raise Diagnosis(
        "recon is wrong: the squared error of decode(z) over 2 σ_x², summed over an example's numbers"
    )


def _elbo_gradients(fn: NegativeElbo) -> None:
    x, mu, logvar, eps, weight = _elbo_inputs(8)
    mu.requires_grad_(True)
    logvar.requires_grad_(True)
    recon, kl = fn(x, mu, logvar, eps, lambda z: torch.tanh(z @ weight).reshape(-1, 4, 2), 0.5)
    (through_recon,) = torch.autograd.grad(recon.sum(), logvar, allow_unused=True)
    if through_recon is None or not bool(through_recon.abs().sum() > 0):
        raise Diagnosis(
            "no gradient reaches logvar through recon: compute z = mu + σ * eps with torch operations"
        )
    if not kl.requires_grad:
        raise Diagnosis("no gradient reaches the KL: compute it with torch operations only")


@checker(
    [_elbo_kl, _elbo_recon, _elbo_gradients],
    "both terms match per example, with gradients through the draw z = mu + σ * eps",
)
def check_negative_elbo(fn: NegativeElbo) -> CheckResult:
    """Check ``fn(x, mu, logvar, eps, decode, obs_var) -> (recon, kl)``, the negative ELBO's two terms per
    example ``(B,)`` (:func:`motionlab.models.vae.losses.negative_elbo`)."""
