"""Chapter 04's exercise: one teacher-forced step of the Motion Cell, a VRNN step over a motion word,
checked against :func:`motionlab.models.motion_cell.model.cell_step`."""

from __future__ import annotations

from collections.abc import Callable

import torch
from torch import Tensor

from motionlab.exercises.checking import CheckResult, Diagnosis, as_result, checker, close
from motionlab.models.gaussian import gaussian_kl
from motionlab.models.motion_cell.model import cell_step

CellStep = Callable[..., tuple[Tensor, Tensor, Tensor]]

#: Batch, word, state and latent sizes (``D_w``, ``D_h``, ``D_z``) of the checker's small networks.
B, D_W, D_H, D_Z = 5, 4, 6, 3


def _pieces(seed: int) -> tuple[tuple[Tensor, Tensor, Tensor], dict[str, Callable[..., object]]]:
    """``(word (B, D_w), state (B, D_h), eps (B, D_z))`` and four small nonlinear networks of fixed weights
    (float64): ``prior(h)``, ``posterior(w, h)``, ``decode(z, h)``, ``transition(w, z, h)``."""
    g = torch.Generator().manual_seed(seed)

    def weights(n_in: int, n_out: int) -> Tensor:
        return torch.randn(n_in, n_out, generator=g, dtype=torch.float64) / n_in**0.5

    w_prior, w_post, w_dec, w_trans = (
        weights(D_H, 2 * D_Z),
        weights(D_W + D_H, 2 * D_Z),
        weights(D_Z + D_H, D_W),
        weights(D_W + D_Z + D_H, D_H),
    )

    def gaussian(x: Tensor, weight: Tensor, shift: float) -> tuple[Tensor, Tensor]:
        mu, logvar = (x @ weight).chunk(2, dim=-1)
        return mu, torch.tanh(logvar) + shift

    networks = {
        "prior": lambda h: gaussian(torch.tanh(h), w_prior, 0.4),
        "posterior": lambda w, h: gaussian(torch.cat([w, h], -1), w_post, -0.8),
        "decode": lambda z, h: torch.tanh(torch.cat([z, h], -1) @ w_dec),
        "transition": lambda w, z, h: torch.tanh(torch.cat([w, z, h], -1) @ w_trans),
    }
    inputs = tuple(torch.randn(B, n, generator=g, dtype=torch.float64) for n in (D_W, D_H, D_Z))
    return inputs, networks  # type: ignore[return-value]


def _call(fn: CellStep, seed: int) -> tuple[Tensor, Tensor, Tensor]:
    (word, state, eps), nets = _pieces(seed)
    result = fn(word, state, eps, nets["prior"], nets["posterior"], nets["decode"], nets["transition"])
    if not isinstance(result, tuple) or len(result) != 3:
        raise Diagnosis(f"return three tensors (word_hat, kl, next_state), got {type(result).__name__}")
    return tuple(as_result(part, "motion_cell_step") for part in result)  # type: ignore[return-value]


def _step_values(fn: CellStep) -> None:
    for seed in (0, 1):
        word_hat, kl, next_state = _call(fn, seed)
        (word, state, eps), nets = _pieces(seed)
        want_word, want_kl, want_state = cell_step(word, state, eps, **nets)
        mu_q, logvar_q = nets["posterior"](word, state)
        mu_p, logvar_p = nets["prior"](state)
        z_q = mu_q + torch.exp(0.5 * logvar_q) * eps
        z_p = mu_p + torch.exp(0.5 * logvar_p) * eps
        z_var = mu_q + torch.exp(logvar_q) * eps
        if not close(word_hat, want_word):
            for z, text in (
                (
                    z_p,
                    "z_t was drawn from the prior; in training it comes from the posterior q(z | w_t, h), "
                    "which has read the word it must rebuild",
                ),
                (z_var, "exp(logvar) is the variance; the draw scales eps by sigma = exp(logvar / 2)"),
                (mu_q, "the word was decoded from the posterior's mean: draw z = mu + sigma * eps"),
            ):
                if close(word_hat, nets["decode"](z, state)):
                    raise Diagnosis(text)
            if close(word_hat, nets["decode"](z_q, want_state)):
                raise Diagnosis(
                    "the decoder read the new state h_t; it reads h_{t-1}, the state before the word"
                )
            raise Diagnosis("the decoded word is wrong: decode(z, h_{t-1}) with z drawn from the posterior")
        if kl.shape == (B, D_Z):
            raise Diagnosis(
                "the KL is per latent dimension; sum over them: one value per example, shape (B,)"
            )
        if kl.shape != want_kl.shape:
            raise Diagnosis(f"the KL should have one value per example, shape ({B},), got {tuple(kl.shape)}")
        if not close(kl, want_kl):
            for wrong, text in (
                (
                    gaussian_kl(mu_p, logvar_p, mu_q, logvar_q).sum(-1),
                    "the KL is reversed: it runs from the posterior to the prior, KL(q || p)",
                ),
                (
                    gaussian_kl(mu_q, logvar_q).sum(-1),
                    "the prior is not N(0, I) here: it is learned, N(mu_p, sigma_p^2) from prior(h_{t-1})",
                ),
                (-want_kl, "the KL has the wrong sign: a KL is never negative"),
                (2 * want_kl, "the KL is twice too large: it has a factor 1/2"),
            ):
                if close(kl, wrong):
                    raise Diagnosis(text)
            raise Diagnosis("the KL is wrong: the closed-form KL between two diagonal Gaussians, q against p")
        if not close(next_state, want_state):
            for wrong, text in (
                (
                    nets["transition"](want_word, z_q, state),
                    "the transition read the decoded word; in training it reads the real word w_t "
                    "(teacher forcing)",
                ),
                (
                    nets["transition"](word, mu_q, state),
                    "the transition read the posterior's mean; it reads the drawn z_t",
                ),
                (
                    nets["transition"](word, z_p, state),
                    "the transition read a z drawn from the prior; use the one drawn from the posterior",
                ),
            ):
                if close(next_state, wrong):
                    raise Diagnosis(text)
            raise Diagnosis("the next state is wrong: transition(w_t, z_t, h_{t-1})")


def _gradients_reach_the_word(fn: CellStep) -> None:
    (word, state, eps), nets = _pieces(3)
    word.requires_grad_(True)
    word_hat, kl, _ = fn(
        word, state, eps, nets["prior"], nets["posterior"], nets["decode"], nets["transition"]
    )
    if not (
        as_result(word_hat, "motion_cell_step").requires_grad
        and as_result(kl, "motion_cell_step").requires_grad
    ):
        raise Diagnosis(
            "no gradient reaches the word through the posterior: compute with torch operations only"
        )


@checker(
    [_step_values, _gradients_reach_the_word],
    "matches motionlab.models.motion_cell.model.cell_step: the draw, the decoded word, KL(q || p) and the "
    "teacher-forced state",
)
def check_motion_cell_step(fn: CellStep) -> CheckResult:
    """Check ``fn(word (B, D_w), state (B, D_h), eps (B, D_z), prior, posterior, decode, transition) ->
    (word_hat, kl (B,), next_state (B, D_h))``, one teacher-forced step of a VRNN over motion words."""
