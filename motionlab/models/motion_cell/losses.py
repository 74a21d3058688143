r"""The terms of the Motion Cell objective (the paper's eq. 14), shared by the baselines and the denoiser.

Per frame, for predicted pose vectors against the data (all terms are means over clips and frames):

* hierarchical geodesic reconstruction (eq. 22): :math:`\sum_j \lambda_j\, d_1(q_j, \hat q_j)` over the
  non-root joints ``j``, with :math:`d_1` the rotation angle between the two quaternions and
  :math:`\lambda_j` the joint impact weights of :func:`motionlab.skeleton.joint_impact_weights` (eq. 23's
  :math:`\alpha_k`; rescaled to mean 1 over the non-root joints), or all ones for the NL ablation; plus the
  squared error of the 6 standardised root channels;
* KL of the posterior from the learned prior, summed over latent dimensions, per word divided by the
  word length (nats per frame, so SL and the word models are on one scale);
* classifier loss (eq. 24): for each training clip ``X`` and its reconstruction ``X~``, the squared l2
  distance between the frozen conv classifier's activations of the two on every intermediate layer
  (each layer ``l`` with a fixed weight ``λ_l``, the paper's ``β_(c,l)``), plus the cross-entropy of its
  action and body heads on ``X~`` against the clip's attribute labels (:class:`ClassifierLoss`). The
  classifier reads the joint positions of both (ours; eq. 24 applies it to the poses themselves, joint
  angles and root channels);
* quaternion-norm constraint (eq. 26 as printed, in our letters :math:`\sum_j (\lVert q_j\rVert^2 - 1)`,
  can be negative and is unbounded below; we penalise :math:`(\lVert q\rVert - 1)^2` of the raw
  quaternion outputs).
"""

from __future__ import annotations

import numbers
from collections.abc import Callable
from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from motionlab.evaluation.evaluator import Evaluator
from motionlab.geometry import quat_geodesic, quat_norm_penalty
from motionlab.models.gaussian import gaussian_kl
from motionlab.models.motion_cell.data import PoseCodec, WindowBatch
from motionlab.models.motion_cell.heads import OutputHead
from motionlab.skeleton import joint_impact_weights
from motionlab.validation import Checked, check_choice, check_scalar, choice, integer, real

#: Joint weights of the reconstruction loss: eq. 23's impact weights, or all ones (the NL ablation).
JOINT_WEIGHTINGS = ("impact", "uniform")

LossFn = Callable[[nn.Module, WindowBatch, int, dict[str, float]], dict[str, Tensor]]


@dataclass(frozen=True)
class LossConfig(Checked):
    """Fixed weights of the Motion Cell objective (eq. 14); the scheduled ones live in the ``TrainConfig``.

    The schedules the loss reads (``coeffs``): ``"beta"`` (lambda_KL, :class:`~motionlab.train.KLAnneal`),
    ``"classifier"`` (lambda_CL, a :class:`~motionlab.train.LinearRamp` that starts after a while) and
    ``"word_drop"`` (probability of feeding the model's own output word instead of the real one).

    Attributes:
        joint_weights: ``"impact"`` (eq. 23's ``λ_j``) or ``"uniform"`` (all ``λ_j = 1``, the NL ablation).
        root_weight: weight of the squared error on the 6 standardised root channels, per frame.
        norm_weight: lambda of the quaternion-norm constraint (eq. 26).
        feature_weight, entropy_weight: weights of the layer-distance and cross-entropy parts of the
            classifier loss (eq. 24's beta_(c,l) are ``feature_weight`` over each layer's mean squared
            activation on the real clips, and ``entropy_weight`` for each attribute head).
        classifier_clips: clips of the batch the classifier loss sees (its first ``classifier_clips``).
        classifier_every: the classifier loss is computed every this many steps, with this factor on its
            weight (the same weight on average, at a fraction of the cost of a classifier pass over the
            whole batch on every step; chapter 04 prints the Motion Cell's training time over NC's when it
            trains both).
    """

    joint_weights: str = choice(JOINT_WEIGHTINGS, "impact")
    root_weight: float = real(1.0, minimum=0)
    norm_weight: float = real(0.1, minimum=0)
    feature_weight: float = real(1.0, minimum=0)
    entropy_weight: float = real(1.0, minimum=0)
    classifier_clips: int = integer(16, minimum=1)
    classifier_every: int = integer(2, minimum=1)


def joint_weights(kind: str, n_joints: int = 22) -> Tensor:
    """The non-root joints' weights ``λ_j`` ``(J - 1,)``, mean 1: ``"impact"`` (eq. 23) or
    ``"uniform"``."""
    check_choice(kind, "kind", "joint_weights", JOINT_WEIGHTINGS)
    if kind == "uniform":
        return torch.ones(n_joints - 1)
    weights = torch.as_tensor(joint_impact_weights()[1:], dtype=torch.float32)
    if weights.numel() != n_joints - 1:
        raise ValueError(
            f"joint_weights: the impact weights are for {weights.numel() + 1} joints, not {n_joints}"
        )
    return weights / weights.mean()


def rotation_loss(predicted: Tensor, target: Tensor, weights: Tensor) -> Tensor:
    """Eq. 22: mean over frames of ``sum_j λ_j d1(q_j, q^_j)`` for quaternions ``(..., J - 1, 4)``."""
    if predicted.shape != target.shape or predicted.shape[-2:] != (weights.numel(), 4):
        raise ValueError(
            f"rotation_loss: predicted {tuple(predicted.shape)} and target {tuple(target.shape)} must "
            f"both be (..., {weights.numel()}, 4)"
        )
    return (quat_geodesic(predicted, target) * weights).sum(-1).mean()


def root_loss(predicted: Tensor, target: Tensor) -> Tensor:
    """Mean over frames of the summed squared error of the standardised root channels ``(..., 6)``."""
    if predicted.shape != target.shape:
        raise ValueError(f"root_loss: shapes differ, {tuple(predicted.shape)} and {tuple(target.shape)}")
    return ((predicted - target) ** 2).sum(-1).mean()


def kl_loss(
    posterior_mu: Tensor, posterior_logvar: Tensor, prior_mu: Tensor, prior_logvar: Tensor, word_length: int
) -> Tensor:
    """KL(q || p) summed over latent dimensions, averaged over words, divided by the word length
    (nats/frame); the four Gaussians' parameters are ``(B, N, latent_dim)``."""
    check_scalar(word_length, "word_length", "kl_loss", kind=numbers.Integral, minimum=1)
    return gaussian_kl(posterior_mu, posterior_logvar, prior_mu, prior_logvar).sum(-1).mean() / word_length


def norm_loss(params: Tensor, head: OutputHead) -> Tensor:
    """Eq. 26: mean over frames of ``sum_k (|q_k| - 1)^2`` of raw quaternion outputs; 0 for other heads."""
    if head.kind != "quaternion":
        return params.new_zeros(())
    return quat_norm_penalty(params).sum(-1).mean()


def pose_loss(
    codec: PoseCodec, predicted: Tensor, target: Tensor, weights: Tensor, root_weight: float
) -> Tensor:
    """Eq. 22's rotation term plus ``root_weight`` times the root term, for pose vectors ``(..., 90)``."""
    predicted_q, predicted_root = codec.split(predicted)
    target_q, target_root = codec.split(target)
    return rotation_loss(predicted_q, target_q, weights) + root_weight * root_loss(
        predicted_root, target_root
    )


class ClassifierLoss(nn.Module):
    r"""Eq. 24 with a frozen classifier ``l`` (the benchmark's conv evaluator, with action and body heads):

    .. math:: \mathcal L_{CL} = \sum_{l} \lambda_l\, \lVert l(X) - l(\tilde X)\rVert^2
        + \beta_{ce} \big[\mathrm{CE}(\mathrm{action}(\tilde X), a)
        + \mathrm{CE}(\mathrm{body}(\tilde X), b)\big]

    for each ground-truth clip ``X`` and its reconstruction ``X~``, both as joint positions (ours: eq. 24
    applies the classifier to the joint-angle poses, and the paper has one classifier per attribute): the
    squared l2 distance of every intermediate layer's activations (mean over channels and frames, then over
    clips) and the cross-entropy of the attribute heads on the reconstruction against the clip's labels. The
    layer weights ``λ_l`` are fixed when the loss is built: one over the layer's mean squared activation
    on the real clips ``positions`` (so every layer counts alike, whatever its scale; :class:`LossConfig`
    scales the two parts by ``feature_weight`` and ``entropy_weight``).

    ``forward(reconstructed, real, action, body)`` takes joint positions ``(B, T, 22, 3)`` of the
    reconstructions (differentiable) and of the clips, with attributes ``(B,)``, and returns
    ``(layer_distance, cross_entropy)`` (``layer_distance`` already weighted by ``λ_l``).
    """

    def __init__(self, evaluator: Evaluator, positions: Tensor, chunk: int = 128) -> None:
        super().__init__()
        missing = {"action", "body"} - set(evaluator.classifier.heads)
        if missing:
            raise ValueError(f"ClassifierLoss: the evaluator has no {sorted(missing)} head(s)")
        self.evaluator = evaluator.eval().requires_grad_(False)
        squares: list[Tensor] | None = None
        with torch.no_grad():
            for begin in range(0, positions.shape[0], chunk):
                batch = self.activations(positions[begin : begin + chunk])
                parts = [(a.double() ** 2).mean(dim=tuple(range(1, a.dim()))).sum() for a in batch]
                squares = parts if squares is None else [s + p for s, p in zip(squares, parts)]
        n_clips = positions.shape[0]
        self.layer_weights = [float(1.0 / max(float(s) / n_clips, 1e-8)) for s in squares]

    def activations(self, positions: Tensor) -> list[Tensor]:
        """The classifier's intermediate activations for positions ``(B, T, 22, 3)``."""
        return self.evaluator.classifier.layer_activations(self.evaluator.inputs(positions))

    def forward(
        self, reconstructed: Tensor, real: Tensor, action: Tensor, body: Tensor
    ) -> tuple[Tensor, Tensor]:
        if (
            reconstructed.dim() != 4
            or reconstructed.shape != real.shape
            or reconstructed.shape[0] != action.shape[0]
            or action.shape != body.shape
        ):
            raise ValueError(
                f"ClassifierLoss: expected reconstructed and real (B, T, 22, 3) and attributes (B,), got "
                f"{tuple(reconstructed.shape)}, {tuple(real.shape)}, {tuple(action.shape)} and "
                f"{tuple(body.shape)}"
            )
        with torch.no_grad():
            targets = self.activations(real)
        outputs = self.activations(reconstructed)
        distance = reconstructed.new_zeros(())
        for weight, out, target in zip(self.layer_weights, outputs, targets):
            distance = distance + weight * ((out - target) ** 2).mean()
        heads = self.evaluator.classifier.heads
        entropy = F.cross_entropy(heads["action"](outputs[-1]), action) + F.cross_entropy(
            heads["body"](outputs[-1]), body
        )
        return distance, entropy


def motion_cell_loss(cfg: LossConfig, classifier: ClassifierLoss | None = None) -> LossFn:
    """The Motion Cell objective (eq. 14) for :func:`motionlab.train.train_or_load`.

    Reads the schedules ``beta``, ``classifier`` (lambda_CL; the classifier runs only while it is positive,
    and needs ``classifier``, a :class:`ClassifierLoss`) and ``word_drop`` from ``coeffs``. The classifier
    term is computed every ``cfg.classifier_every`` steps and weighted by that number (the same weight on
    average at a fraction of the cost; in between its terms are logged as 0).
    Returns the total and every term.
    """
    weights = joint_weights(cfg.joint_weights)

    def loss_fn(
        model: nn.Module, batch: WindowBatch, step: int, coeffs: dict[str, float]
    ) -> dict[str, Tensor]:
        out = model(batch.poses, batch.action, batch.body, word_drop=coeffs.get("word_drop", 0.0))
        codec = model.codec
        predicted_q, predicted_root = codec.split(out.poses)
        target_q, target_root = codec.split(batch.poses)
        rotation = rotation_loss(predicted_q, target_q, weights)
        root = root_loss(predicted_root, target_root)
        kl = kl_loss(
            out.posterior_mu, out.posterior_logvar, out.prior_mu, out.prior_logvar, model.cfg.word_length
        )
        norm = norm_loss(out.rotation_params, model.head)
        lambda_cl = coeffs.get("classifier", 0.0)
        matching = entropy = out.poses.new_zeros(())
        if lambda_cl > 0 and step % cfg.classifier_every == 0:
            if classifier is None:
                raise ValueError(
                    "motion_cell_loss: the 'classifier' schedule is positive but no ClassifierLoss was given"
                )
            k = min(cfg.classifier_clips, batch.poses.shape[0])
            action, body = batch.action[:k], batch.body[:k]
            with torch.no_grad():  # eq. 24: each clip against its reconstruction
                real = codec.positions(batch.poses[:k], body)
            matching, entropy = classifier(codec.positions(out.poses[:k], body), real, action, body)
        classifier_term = cfg.classifier_every * (
            cfg.feature_weight * matching + cfg.entropy_weight * entropy
        )
        total = (
            rotation
            + cfg.root_weight * root
            + coeffs.get("beta", 1.0) * kl
            + lambda_cl * classifier_term
            + cfg.norm_weight * norm
        )
        return {
            "loss": total,
            "rotation": rotation,
            "root": root,
            "kl": kl,
            "layer_distance": matching,
            "cross_entropy": entropy,
            "norm": norm,
        }

    return loss_fn
