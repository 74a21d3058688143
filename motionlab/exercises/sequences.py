"""Chapters 07 and 08's exercises: the DCT basis of TrajeVAE, its masked-joint input, the KL of its posterior
from its learned prior and ODMO's contrastive loss, checked against :mod:`motionlab.models.trajevae.dct`,
:mod:`motionlab.models.trajevae.masks`, :mod:`motionlab.models.gaussian` and
:mod:`motionlab.models.odmo.losses`."""

from __future__ import annotations

import math
from collections.abc import Callable

import torch

from motionlab.exercises.checking import CheckResult, Diagnosis, as_result, checker, close, close_each
from motionlab.models.gaussian import gaussian_kl
from motionlab.models.odmo.losses import contrastive_loss
from motionlab.models.trajevae.dct import dct_matrix
from motionlab.models.trajevae.masks import given_trajectories, hidden_poses

DCTMatrix = Callable[[int], torch.Tensor]
GivenTrajectories = Callable[[torch.Tensor, torch.Tensor], torch.Tensor]
ContrastiveLoss = Callable[[torch.Tensor, torch.Tensor, torch.Tensor, float], torch.Tensor]
PriorKL = Callable[[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor], torch.Tensor]


def _dct_values(fn: DCTMatrix) -> None:
    n = 8
    got = as_result(fn(n), "the DCT matrix").to(torch.float64)
    want = dct_matrix(n, dtype=torch.float64)
    if got.shape != (n, n):
        raise Diagnosis(
            f"dct_matrix({n}) should be ({n}, {n}) (frequency u, frame t), got {tuple(got.shape)}"
        )
    if close(got, want, 1e-6):
        return
    if close(got, want.T, 1e-6):
        raise Diagnosis("the matrix is transposed: row u should be frequency u, column t frame t (a = U h)")
    rows_right = [u for u in range(n) if close(got[u], want[u], 1e-6)]
    if rows_right == list(range(1, n)):
        raise Diagnosis("row 0 (the constant) is off: its scale is sqrt(1/T), the other rows' sqrt(2/T)")
    ratio = got / want
    if torch.allclose(ratio[1:], ratio[1, 0].expand_as(ratio[1:]), rtol=1e-6):
        raise Diagnosis(
            "the cosines are right but not their scale: s_0 = sqrt(1/T) and s_u = sqrt(2/T) make the rows "
            "orthonormal"
        )
    gram = got @ got.T
    orthonormal = close(gram, torch.eye(n, dtype=gram.dtype), 1e-6)
    raise Diagnosis(
        "the cosines are wrong: U[u, t] = s_u cos(pi (2t + 1) u / (2T))"
        + ("" if orthonormal else "; your rows are not orthonormal either (U U^T should be I)")
    )


def _dct_other_sizes(fn: DCTMatrix) -> None:
    for n in (1, 5, 31):
        got = as_result(fn(n), "the DCT matrix").to(torch.float64)
        if got.shape != (n, n) or not close(got, dct_matrix(n, dtype=torch.float64), 1e-6):
            raise Diagnosis(
                f"dct_matrix({n}) is wrong (right for 8 frames): use T = n_frames, not a constant"
            )


@checker(
    [_dct_values, _dct_other_sizes],
    "matches the orthonormal DCT-II (scipy's dct(norm='ortho')) for 1, 5, 8 and 31 frames",
)
def check_dct_matrix(fn: DCTMatrix) -> CheckResult:
    """Check ``fn(n_frames) -> (n_frames, n_frames)``, the orthonormal DCT-II matrix (rows: frequencies)."""


def _pairs(seed: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    generator = torch.Generator().manual_seed(seed)
    mu_a = torch.randn(12, 3, generator=generator, dtype=torch.float64) * 2
    mu_b = torch.randn(12, 3, generator=generator, dtype=torch.float64) * 2
    same = torch.arange(12) % 2 == 0
    return mu_a, mu_b, same


def _contrastive_values(fn: ContrastiveLoss) -> None:
    mu_a, mu_b, same = _pairs(1)
    margin = 3.0
    got = as_result(fn(mu_a, mu_b, same, margin), "the contrastive loss")
    want = contrastive_loss(mu_a, mu_b, same, margin)
    if got.shape != want.shape:
        if got.numel() == 1:
            raise Diagnosis("return one loss per pair, shape (P,), not their sum or mean")
        raise Diagnosis(f"12 pairs should give losses of shape (12,), got {tuple(got.shape)}")
    if close(got, want):
        return
    d = (mu_a - mu_b).norm(dim=-1)
    for wrong, text in (
        (2 * want, "you forgot the factor 1/2"),
        (
            0.5 * torch.where(same, torch.relu(margin - d) ** 2, d**2),
            "same- and different-class terms are swapped",
        ),
        (0.5 * torch.where(same, d**2, torch.relu(margin - d)), "the hinge is squared: max(0, m - d)^2"),
        (
            0.5 * torch.where(same, d**2, torch.relu(margin - d**2) ** 2),
            "the hinge compares the distance d, not d^2",
        ),
        (
            0.5 * torch.where(same, d, torch.relu(margin - d) ** 2),
            "the same-class term is the squared distance",
        ),
    ):
        if close(got, wrong):
            raise Diagnosis(text)
    wrong_same = bool((~close_each(got, want))[same].any())
    raise Diagnosis(
        f"the {'same' if wrong_same else 'different'}-class losses are wrong: 1/2 d^2 for the same class, "
        "1/2 max(0, m - d)^2 for different classes"
    )


def _contrastive_gradient_at_zero(fn: ContrastiveLoss) -> None:
    mu_a = torch.zeros(2, 3, dtype=torch.float64, requires_grad=True)
    loss = as_result(
        fn(mu_a, torch.zeros(2, 3, dtype=torch.float64), torch.tensor([True, False]), 1.0), "loss"
    )
    if not loss.requires_grad:
        raise Diagnosis("no gradient reaches the codes: compute with torch operations only")
    loss.sum().backward()
    if mu_a.grad is None or not torch.isfinite(mu_a.grad).all():
        raise Diagnosis(
            "for two equal codes the gradient is NaN: sqrt has an infinite slope at 0; take the square root "
            "of a clamped square, e.g. d = sq.clamp_min(1e-12).sqrt()"
        )
    if not math.isclose(float(loss[1].detach()), 0.5, rel_tol=1e-4):
        raise Diagnosis("two equal codes of different classes should cost 1/2 m^2")


@checker(
    [_contrastive_values, _contrastive_gradient_at_zero],
    "matches ODMO's eq. 1 per pair (without slack), with finite gradients for equal codes",
)
def check_contrastive_loss(fn: ContrastiveLoss) -> CheckResult:
    """Check ``fn(mu_a, mu_b, same, margin) -> (P,)``: ODMO's eq. 1 per pair of codes ``(P, D)``."""


def _masked_inputs(batch: tuple[int, ...], seed: int) -> tuple[torch.Tensor, torch.Tensor]:
    generator = torch.Generator().manual_seed(seed)
    poses = torch.randn(*batch, 9, 5 * 3, generator=generator, dtype=torch.float64)
    mask = torch.rand(*batch, 5, generator=generator) < 0.5
    mask[..., 0], mask[..., 1] = True, False  # at least one given and one hidden joint
    return poses, mask


def _given_problem(got: torch.Tensor, poses: torch.Tensor, mask: torch.Tensor) -> str | None:
    want = given_trajectories(poses, mask)
    if close(got, want):
        return None
    if got.shape != want.shape:
        return (
            f"keep the shape of poses {tuple(want.shape)}, with zeros for the joints to complete (got "
            f"{tuple(got.shape)}): the model reads fixed-size frames"
        )
    if close(got, hidden_poses(poses, mask)):
        return "you kept the joints to complete and zeroed the given ones: Y = X ⊙ M keeps those with m_j = 1"
    tiled = mask.repeat(*[1] * (mask.dim() - 1), 3)[..., None, :]
    if close(got, poses * tiled):
        return (
            "the channels are x, y, z of joint 0, then of joint 1, ...: repeat each joint's flag three times "
            "in place (repeat_interleave), not the whole mask"
        )
    return "Y is wrong: the given joints' x, y, z as they are, every other channel 0"


def _given_one_mask(fn: GivenTrajectories) -> None:
    poses, mask = _masked_inputs((), 1)
    problem = _given_problem(as_result(fn(poses, mask), "given_trajectories"), poses, mask)
    if problem is not None:
        raise Diagnosis(f"with poses (9, 15) and mask (5,): {problem}")


def _given_per_sequence(fn: GivenTrajectories) -> None:
    poses, mask = _masked_inputs((4,), 2)
    poses.requires_grad_(True)
    try:
        got = as_result(fn(poses, mask), "given_trajectories")
    except RuntimeError as error:
        raise Diagnosis(
            f"with a mask per sequence, poses (4, 9, 15) and mask (4, 5), your function raised: {error}; the "
            "mask has no frame axis, add one (mask[..., None, :]) so that it applies to every frame"
        ) from None
    problem = _given_problem(got, poses.detach(), mask)
    if problem is not None:
        raise Diagnosis(f"with poses (4, 9, 15) and a mask per sequence (4, 5): {problem}")
    if not got.requires_grad:
        raise Diagnosis("no gradient flows to the poses: compute with torch operations only")


@checker(
    [_given_one_mask, _given_per_sequence],
    "matches motionlab.models.trajevae.masks.given_trajectories, for one mask and a mask per sequence",
)
def check_given_trajectories(fn: GivenTrajectories) -> CheckResult:
    """Check ``fn(poses (..., T, J * 3), mask (..., J) bool) -> Y (..., T, J * 3)``: ``Y = X ⊙ M``, the given
    joints' trajectories and zeros elsewhere."""


def _latents(seed: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """A posterior's and a learned prior's means and log-variances, each (4, 3, 5): (B, C, L)."""
    generator = torch.Generator().manual_seed(seed)
    mu_q, logvar_q, mu_p, logvar_p = torch.randn(4, 4, 3, 5, generator=generator, dtype=torch.float64)
    return mu_q, logvar_q, mu_p + 1.0, logvar_p - 0.5


def _prior_kl_values(fn: PriorKL) -> None:
    mu_q, logvar_q, mu_p, logvar_p = _latents(6)
    got = as_result(fn(mu_q, logvar_q, mu_p, logvar_p), "the KL")
    per_number = gaussian_kl(mu_q, logvar_q, mu_p, logvar_p)
    want = per_number.sum(dim=(1, 2))
    if got.shape == per_number.shape and close(got, per_number):
        raise Diagnosis("return one KL per sequence (B,): sum over the C components and L latent numbers")
    if got.numel() == 1 and close(got.reshape(()), want.mean()):
        raise Diagnosis("return one KL per sequence (B,), not its mean over the batch (the loss averages it)")
    if got.shape != want.shape:
        raise Diagnosis(
            f"latents of shape (4, 3, 5) should give one KL per sequence, (4,), got {tuple(got.shape)}"
        )
    if close(got, want):
        return
    for wrong, text in (
        (
            gaussian_kl(mu_p, logvar_p, mu_q, logvar_q).sum(dim=(1, 2)),
            "the two Gaussians are swapped: the loss is KL(q_pose || p_traj), the posterior's divergence "
            "from the prior",
        ),
        (
            gaussian_kl(mu_q, logvar_q).sum(dim=(1, 2)),
            "this is the KL from N(0, I): TrajeVAE's prior is learned, use mu_p and logvar_p",
        ),
        (per_number.mean(dim=(1, 2)), "you averaged over the latent numbers: sum them"),
        (2 * want, "you forgot the factor 1/2"),
        (want + 0.5 * per_number[0].numel(), "you forgot the -1 inside the bracket (KL(q || q) is 0)"),
    ):
        if close(got, wrong):
            raise Diagnosis(text)
    raise Diagnosis(
        f"for the first sequence you gave {got[0].item():.4f}, the KL is {want[0].item():.4f}: "
        "1/2 sum (log sigma_p^2 - log sigma_q^2 + (sigma_q^2 + (mu_q - mu_p)^2) / sigma_p^2 - 1)"
    )


def _prior_kl_is_zero_when_they_agree(fn: PriorKL) -> None:
    mu, logvar, _, _ = _latents(7)
    mu.requires_grad_(True)
    got = as_result(fn(mu, logvar, mu.detach().clone(), logvar.clone()), "the KL")
    if got.shape != (4,) or not close(got, torch.zeros_like(got)):
        raise Diagnosis("when the posterior equals the prior the KL should be 0 for every sequence")
    again = fn(mu, logvar, mu.detach() + 0.1, logvar)
    if not again.requires_grad:
        raise Diagnosis("no gradient reaches the posterior's mean: compute with torch operations only")


@checker(
    [_prior_kl_values, _prior_kl_is_zero_when_they_agree],
    "matches KL(q_pose || p_traj) (motionlab.models.gaussian.gaussian_kl) summed per sequence, 0 when equal",
)
def check_prior_kl(fn: PriorKL) -> CheckResult:
    """Check ``fn(mu_q, logvar_q, mu_p, logvar_p) -> (B,)``: the KL of the posterior N(mu_q, exp(logvar_q))
    from the learned prior N(mu_p, exp(logvar_p)), latents ``(B, C, L)``, summed over ``C`` and ``L``."""
