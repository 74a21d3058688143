r"""Loss functions of the completion models, in the training loop's form ``loss_fn(model, batch, step,
coeffs)``.

A batch is ``(windows (B, T, J * 3), mask (B, J))`` from
:class:`~motionlab.models.trajevae.data.CompletionBatches`. The paper's objective (§3.2) is a reconstruction
term, eq. 2, that *sums* the squared errors over the ``F`` completed frames and the ``3J`` coordinates, plus
β = 0.01 times the KL, which is summed over latent steps and numbers (nats); both are averaged over the ``B``
sequences:

.. math::
    \mathcal L = \frac1B \sum_b \Big( \sum_{t, c} (\hat x_{btc} - x_{btc})^2
                 + \beta \, \mathrm{KL}\big(q_\text{pose}(z \mid X \odot (1 - M)) \,\|\, p_\text{traj}(z \mid
                 Y)\big) \Big).

That is the default (``reconstruction="sum"`` in the model's config). The variant ``"mean"`` divides the
squared errors by ``F * 3J`` as well (a per-number mean squared error); with the same β it weights the KL
``F * 3J`` times more (3894 times for our 59 frames of 22 joints), so it equals the paper's objective with
β = 0.01 · 3894 ≈ 39, up to the overall scale.

Besides ``loss`` every function logs the terms: ``recon`` (the per-number mean squared error of all joints,
m², whatever the reduction, so that runs can be compared), ``recon_given`` and ``recon_hidden`` (the parts of
``recon`` from the joints whose trajectory was given / hidden; they add up to ``recon``), and ``kl`` for the
latent-variable models.
"""

from __future__ import annotations

from torch import Tensor

from motionlab.models.gaussian import gaussian_kl
from motionlab.models.trajevae.baselines import CVAERNN, GRUCompletion
from motionlab.models.trajevae.masks import channel_mask
from motionlab.models.trajevae.model import CompletionOutput, TrajeVAE


def squared_error_terms(predicted: Tensor, target: Tensor, mask: Tensor) -> dict[str, Tensor]:
    """Mean squared error ``recon`` over all elements, split into ``recon_given`` + ``recon_hidden`` by the
    mask, and ``recon_sum``: the squared errors summed over frames and coordinates, averaged over the batch
    (eq. 2).

    Args:
        predicted, target: ``(B, F, J * 3)``; mask: ``(B, J)`` bool, True where the trajectory was given.
    """
    if predicted.shape != target.shape:
        raise ValueError(
            f"squared_error_terms: predicted {tuple(predicted.shape)} and target {tuple(target.shape)} differ"
        )
    squared = (predicted - target) ** 2
    given = channel_mask(mask)[:, None, :].to(squared.dtype)
    count = squared.numel()
    return {
        "recon": squared.sum() / count,
        "recon_given": (squared * given).sum() / count,
        "recon_hidden": (squared * (1.0 - given)).sum() / count,
        "recon_sum": squared.sum() / squared.shape[0],
    }


def reconstruction_loss(terms: dict[str, Tensor], reconstruction: str) -> Tensor:
    """The reconstruction term of the loss from :func:`squared_error_terms`' ``terms``: ``recon_sum`` (the
    paper's eq. 2, ``"sum"``) or ``recon`` (``"mean"``)."""
    if reconstruction == "sum":
        return terms["recon_sum"]
    if reconstruction == "mean":
        return terms["recon"]
    raise ValueError(f"reconstruction_loss: reconstruction must be 'sum' or 'mean', got {reconstruction!r}")


def latent_kl(output: CompletionOutput) -> Tensor:
    """``KL(q_pose || p_traj)`` summed over latent steps and numbers, averaged over the batch (nats).

    Without a posterior (the Base model) it is ``KL(q(z | Y) || N(0, I))``.
    """
    if output.posterior is None:
        kl = gaussian_kl(output.prior.mu, output.prior.logvar)
    else:
        kl = gaussian_kl(output.posterior.mu, output.posterior.logvar, output.prior.mu, output.prior.logvar)
    return kl.sum() / kl.shape[0]


def trajevae_loss(
    model: TrajeVAE, batch: tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    """TrajeVAE's loss: the reconstruction term (``model.cfg.reconstruction``) + ``model.cfg.beta`` · KL (see
    the module docstring)."""
    windows, mask = batch
    output = model(windows, mask)
    terms = squared_error_terms(output.poses, windows[:, 1:], mask)
    kl = latent_kl(output)
    return {
        "loss": reconstruction_loss(terms, model.cfg.reconstruction) + model.cfg.beta * kl,
        **terms,
        "kl": kl,
    }


def gru_loss(
    model: GRUCompletion, batch: tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    """The deterministic GRU's loss: the reconstruction term alone."""
    windows, mask = batch
    terms = squared_error_terms(model(windows, mask), windows[:, 1:], mask)
    return {"loss": reconstruction_loss(terms, model.cfg.reconstruction), **terms}


def cvae_rnn_loss(
    model: CVAERNN, batch: tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    """The CVAE-RNN's loss: the reconstruction term + ``model.cfg.beta`` · KL(q(z | X) || N(0, I))."""
    windows, mask = batch
    poses, posterior = model(windows, mask)
    terms = squared_error_terms(poses, windows[:, 1:], mask)
    kl = gaussian_kl(posterior.mu, posterior.logvar).sum() / poses.shape[0]
    return {
        "loss": reconstruction_loss(terms, model.cfg.reconstruction) + model.cfg.beta * kl,
        **terms,
        "kl": kl,
    }
