r"""MDM's training objective (§3): the simple loss on :math:`\hat x_0` and three geometric losses.

One training step draws, for every clip :math:`x_0` of the batch (standardised, :mod:`.data`), a step
:math:`t` uniformly from the ``S`` steps and a noise :math:`\epsilon \sim \mathcal N(0, I)`, noises the clip
in one draw (:meth:`~.schedule.NoiseSchedule.q_sample`) and asks the network for :math:`\hat x_0 = G(x_t, t,
c)` (the action dropped to the null condition for 10 % of the clips, :class:`~.model.MDM`). With ``N``
frames, :math:`FK` the forward kinematics of :func:`~.data.joint_positions` (the identity for a model on
joint positions, :class:`~.model.PositionMDMConfig`) and :math:`f_i` the foot-contact
mask of frame ``i``:

.. math::
    \mathcal L_\text{simple} &= \lVert x_0 - \hat x_0 \rVert^2 && \text{(simple)} \\
    \mathcal L_\text{pos} &= \tfrac1N \textstyle\sum_i \lVert FK(x_0^i) - FK(\hat x_0^i) \rVert^2
        && \text{(positions)} \\
    \mathcal L_\text{foot} &= \tfrac1{N-1} \textstyle\sum_i \lVert (FK(\hat x_0^{i+1}) - FK(\hat x_0^i))
        \cdot f_i \rVert^2 && \text{(foot contact)} \\
    \mathcal L_\text{vel} &= \tfrac1{N-1} \textstyle\sum_i \lVert (x_0^{i+1} - x_0^i)
        - (\hat x_0^{i+1} - \hat x_0^i) \rVert^2 && \text{(velocities)} \\
    \mathcal L &= \mathcal L_\text{simple} + \lambda_\text{pos} \mathcal L_\text{pos}
        + \lambda_\text{vel} \mathcal L_\text{vel} + \lambda_\text{foot} \mathcal L_\text{foot}
        && \text{(the total)}

Each squared norm is averaged over its channels (joints × coordinates), as the repository's ``masked_l2``
does, and over the clips of the batch. :math:`f_i` is 1 for a foot joint (:data:`~.model.FOOT_JOINTS`: both
ankles and both feet) whose *real* speed from frame ``i`` to ``i + 1`` is at most ``contact_threshold``
metres per frame, 0 otherwise (the repository's rule, which reads contact off the real feet's speed; the
paper calls :math:`f_i` the binary foot-contact mask of frame ``i``): the predicted feet are penalised for
moving where the real feet stand still.

**Paper and repository.**

* Positions: the repository's ``rot2xyz`` (``vertstrans=False``) returns joints relative to the root, without
  the root's translation, for both :math:`\mathcal L_\text{pos}` and :math:`\mathcal L_\text{foot}`; the paper
  writes :math:`FK` of the whole motion. We follow the paper: world positions, so a foot that stands on the
  floor while the body moves over it is what :math:`\mathcal L_\text{foot}` asks for.
* Velocities: the paper's :math:`\mathcal L_\text{vel}` is on the representation itself; the repository's
  (``vel_mse``) leaves out the translation "joint". We follow the paper (all channels), on the standardised
  channels the network predicts, like :math:`\mathcal L_\text{simple}`.
* The contact threshold, 0.01 m per frame, is the repository's, set for its 20 fps data (0.2 m/s); at the
  chapter's 15 fps the same number means 0.15 m/s. The paper does not give one.
* The repository masks padded frames of shorter clips; our clips all have ``T`` frames.
"""

from __future__ import annotations

import torch
from torch import Tensor

from motionlab.models.diffusion.model import FOOT_JOINTS, MDM
from motionlab.validation import check_scalar, check_tensor


def _check_pair(prediction: Tensor, target: Tensor, where: str) -> None:
    check_tensor(prediction, "prediction", where, min_leading=2, finite=False)
    if prediction.shape != target.shape:
        raise ValueError(
            f"{where}: prediction and target must have the same shape, got {tuple(prediction.shape)} and "
            f"{tuple(target.shape)}"
        )


def frame_error(prediction: Tensor, target: Tensor) -> Tensor:
    """Squared error of each clip ``(B,)``, averaged over frames and channels of ``(B, T, ...)``."""
    _check_pair(prediction, target, "frame_error")
    return (prediction - target).pow(2).flatten(1).mean(dim=1)


def velocity_error(prediction: Tensor, target: Tensor) -> Tensor:
    r"""The velocity loss :math:`\mathcal L_\text{vel}` for each clip ``(B,)``: the squared error of the
    frame-to-frame differences of ``(B, T, ...)``."""
    _check_pair(prediction, target, "velocity_error")
    return frame_error(prediction.diff(dim=1), target.diff(dim=1))


def foot_contact_mask(positions: Tensor, threshold: float, feet: tuple[int, ...] = FOOT_JOINTS) -> Tensor:
    """The contact mask :math:`f_i` ``(B, T - 1, len(feet))`` bool of real joint positions ``(B, T, J, 3)``:
    True where a foot joint moves at most ``threshold`` metres to the next frame."""
    check_tensor(positions, "positions", "foot_contact_mask", trailing=(None, 3), ndim=4)
    check_scalar(threshold, "threshold", "foot_contact_mask", minimum=0, include_minimum=False)
    return positions[:, :, list(feet)].diff(dim=1).norm(dim=-1) <= threshold


def foot_contact_error(positions: Tensor, contact: Tensor, feet: tuple[int, ...] = FOOT_JOINTS) -> Tensor:
    r"""The foot-contact loss :math:`\mathcal L_\text{foot}` for each clip ``(B,)``: the squared velocity of
    the predicted foot joints ``(B, T, J, 3)`` where ``contact`` ``(B, T - 1, len(feet))`` is set, averaged
    over frames and channels."""
    check_tensor(positions, "positions", "foot_contact_error", trailing=(None, 3), ndim=4, finite=False)
    velocity = positions[:, :, list(feet)].diff(dim=1)
    if contact.shape != velocity.shape[:-1] or contact.dtype != torch.bool:
        raise ValueError(
            f"foot_contact_error: contact must be a {tuple(velocity.shape[:-1])} bool tensor, got "
            f"{contact.dtype} {tuple(contact.shape)}"
        )
    return frame_error(velocity * contact[..., None], torch.zeros_like(velocity))


def diffusion_objective(
    model: MDM, batch: tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
) -> dict[str, Tensor]:
    """MDM's total loss on one batch ``(features (B, T, F), action (B,))`` for the training loop (features
    in the units of :mod:`.data`; no coefficient is read from ``coeffs``).

    Returns the total as ``"loss"`` and the terms ``"simple"``, ``"position"``, ``"velocity"`` and
    ``"foot_contact"`` (batch means); the geometric terms are computed only when one of their weights is
    positive.
    """
    features, action = batch
    cfg = model.cfg
    check_tensor(features, "features", "diffusion_objective", trailing=(cfg.n_frames, cfg.n_features), ndim=3)
    x0 = model.standardizer.transform(features)
    t = torch.randint(0, model.schedule.n_steps, (x0.shape[0],))
    x_t = model.schedule.q_sample(x0, t, torch.randn_like(x0))
    predicted = model(x_t, model.schedule.timesteps[t], action)
    terms = {"simple": frame_error(predicted, x0).mean()}
    total = terms["simple"]
    if max(cfg.lambda_pos, cfg.lambda_vel, cfg.lambda_foot) > 0:
        real = model.joint_positions(features)
        generated = model.joint_positions(model.standardizer.inverse(predicted))
        contact = foot_contact_mask(real, cfg.contact_threshold, cfg.feet)
        terms["position"] = frame_error(generated, real).mean()
        terms["velocity"] = velocity_error(predicted, x0).mean()
        terms["foot_contact"] = foot_contact_error(generated, contact, cfg.feet).mean()
        total = (
            total
            + cfg.lambda_pos * terms["position"]
            + cfg.lambda_vel * terms["velocity"]
            + cfg.lambda_foot * terms["foot_contact"]
        )
    return {"loss": total, **terms}
