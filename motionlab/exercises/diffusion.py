"""Chapter 11's exercise: one ancestral step of a diffusion sampler from a predicted clean sample, checked
against the posterior of :mod:`motionlab.models.diffusion.schedule`."""

from __future__ import annotations

from collections.abc import Callable

import torch

from motionlab.exercises.checking import CheckResult, Diagnosis, as_result, checker, close
from motionlab.models.diffusion.schedule import NoiseSchedule

#: ``fn(x0_hat (B, D), x_t (B, D), t, betas (S,), noise (B, D)) -> x_{t-1} (B, D)``, ``t`` a 0-based int.
AncestralStep = Callable[[torch.Tensor, torch.Tensor, int, torch.Tensor, torch.Tensor], torch.Tensor]

#: The schedule the checks run on (few steps, so that every coefficient differs visibly).
N_STEPS = 8


def _inputs(seed: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, NoiseSchedule]:
    generator = torch.Generator().manual_seed(seed)
    x0_hat, x_t, noise = torch.randn(3, 5, 2, generator=generator, dtype=torch.float64)
    return x0_hat, x_t, noise, NoiseSchedule.cosine(N_STEPS)


def _reference(x0_hat: torch.Tensor, x_t: torch.Tensor, t: int, schedule: NoiseSchedule, noise: torch.Tensor):
    """The package's step and, for naming mistakes, the posterior's parts."""
    steps = torch.full((x0_hat.shape[0],), t, dtype=torch.int64)
    mean, variance = schedule.posterior(x0_hat, x_t, steps)
    return mean + (variance.sqrt() * noise if t > 0 else 0), mean, variance


def _call(fn: AncestralStep, x0_hat, x_t, t: int, schedule: NoiseSchedule, noise) -> torch.Tensor:
    got = as_result(fn(x0_hat, x_t, t, schedule.betas.clone(), noise), "your step")
    if got.shape != x_t.shape:
        raise Diagnosis(f"x_(t-1) should have x_t's shape {tuple(x_t.shape)}, got {tuple(got.shape)}")
    return got


def _mistake(got, x0_hat, x_t, t: int, schedule: NoiseSchedule, noise) -> str:
    """A sentence naming the mistake behind a wrong step at ``t > 0``."""
    _, mean, variance = _reference(x0_hat, x_t, t, schedule, noise)
    betas, alpha_bar = schedule.betas, schedule.alphas_cumprod
    if close(got, mean):
        return "no noise was added: at t > 0 the step is a draw, mean + sqrt(variance) * noise"
    if close(got, mean + variance * noise):
        return "the noise is scaled by the variance: scale it by the standard deviation"
    if close(got, mean + betas[t].sqrt() * noise):
        return "the noise has the forward step's variance beta_t, not the posterior's"
    if close(got, x0_hat):
        return "the step returns x0_hat: that is only the last step (t = 0); before it, go to x_(t-1)"
    # the means of common slips, each with the right noise
    scale = variance.sqrt() * noise
    a_t, a_prev = alpha_bar[t], alpha_bar[t - 1]
    swapped = (1 - a_prev) * (1 - betas[t]).sqrt() / (1 - a_t) * x0_hat + betas[t] * a_prev.sqrt() / (
        1 - a_t
    ) * x_t
    if close(got, swapped + scale):
        return "the two coefficients of the mean are swapped between x0_hat and x_t"
    shifted = betas[t] * a_t.sqrt() / (1 - a_t) * x0_hat + (1 - a_t) * (1 - betas[t]).sqrt() / (1 - a_t) * x_t
    if close(got, shifted + scale):
        return "the mean uses alpha_bar at t where it needs alpha_bar at t - 1"
    return "the mean of q(x_(t-1) | x_t, x0_hat) is wrong: check both coefficients against the formula"


def _middle_step(fn: AncestralStep) -> None:
    x0_hat, x_t, noise, schedule = _inputs(1)
    for t in (5, 2, 1):
        got = _call(fn, x0_hat, x_t, t, schedule, noise)
        if not close(got, _reference(x0_hat, x_t, t, schedule, noise)[0]):
            raise Diagnosis(f"at t = {t}: " + _mistake(got, x0_hat, x_t, t, schedule, noise))


def _last_step(fn: AncestralStep) -> None:
    x0_hat, x_t, noise, schedule = _inputs(2)
    got = _call(fn, x0_hat, x_t, 0, schedule, noise)
    if close(got, x0_hat):
        return
    if close(got, x0_hat + schedule.betas[0].sqrt() * noise):
        raise Diagnosis("at t = 0 noise was added: the last step returns the clean prediction, no noise")
    raise Diagnosis(
        "at t = 0 the step must return x0_hat itself: before the first step alpha_bar is 1 (not the entry at "
        "index t - 1 = -1), so the posterior's mean is x0_hat and its variance 0"
    )


def _schedule_of_any_length(fn: AncestralStep) -> None:
    generator = torch.Generator().manual_seed(3)
    x0_hat, x_t, noise = torch.randn(3, 4, 3, generator=generator, dtype=torch.float64)
    schedule = NoiseSchedule.cosine(1000)
    got = _call(fn, x0_hat, x_t, 999, schedule, noise)
    if not close(got, _reference(x0_hat, x_t, 999, schedule, noise)[0], 1e-7):
        raise Diagnosis("right on 8 steps, wrong on the last of 1,000: read every coefficient from betas")


@checker(
    [_middle_step, _last_step, _schedule_of_any_length],
    "one ancestral step: the posterior mean, its own variance, and no noise at the last step",
)
def check_ancestral_step(fn: AncestralStep) -> CheckResult:
    """Check ``fn(x0_hat, x_t, t, betas, noise) -> x_(t-1)``: a draw of ``q(x_(t-1) | x_t, x0_hat)`` with
    the given standard normal ``noise``, ``t`` the 0-based step index into ``betas`` ``(S,)``."""
