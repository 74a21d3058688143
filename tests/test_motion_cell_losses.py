"""Motion Cell loss terms against hand computations, scipy and torch.distributions."""

import numpy as np
import pytest
import torch
import torch.nn.functional as F
from scipy.spatial.transform import Rotation

from motionlab.evaluation import EVAL_FEATURES, body_frame_features
from motionlab.models.motion_cell.heads import OutputHead
from motionlab.models.motion_cell.losses import (
    ClassifierLoss,
    LossConfig,
    joint_weights,
    kl_loss,
    motion_cell_loss,
    norm_loss,
    root_loss,
    rotation_loss,
)
from motionlab.skeleton import joint_impact_weights


def _random_quats(n: int, seed: int) -> torch.Tensor:
    xyzw = Rotation.random(n, random_state=seed).as_quat()
    return torch.tensor(np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1), dtype=torch.float64)


def test_joint_weights_are_the_impact_weights_of_the_non_root_joints_with_mean_one():
    weights = joint_weights("impact")
    expected = joint_impact_weights()[1:]
    np.testing.assert_allclose(weights.numpy(), expected / expected.mean(), rtol=1e-6)
    assert weights.shape == (21,) and abs(float(weights.mean()) - 1) < 1e-6
    hips, wrists = (
        weights[0],
        weights[19],
    )  # joint 1 (left hip) reaches the foot; joint 20 (left wrist) is a leaf
    assert hips > wrists
    assert torch.equal(joint_weights("uniform"), torch.ones(21))
    with pytest.raises(ValueError, match="kind"):
        joint_weights("learned")


def test_rotation_loss_is_the_weighted_sum_of_angles_from_scipy():
    q1 = _random_quats(5 * 21, 0).reshape(5, 21, 4)
    q2 = _random_quats(5 * 21, 1).reshape(5, 21, 4)
    weights = torch.rand(21, dtype=torch.float64)
    r1 = Rotation.from_quat(q1.reshape(-1, 4)[:, [1, 2, 3, 0]].numpy())
    r2 = Rotation.from_quat(q2.reshape(-1, 4)[:, [1, 2, 3, 0]].numpy())
    angles = (r1.inv() * r2).magnitude().reshape(5, 21)
    expected = (angles * weights.numpy()).sum(-1).mean()
    assert float(rotation_loss(q1, q2, weights)) == pytest.approx(expected, rel=1e-9)
    # sign-invariant: -q is the same rotation
    assert float(rotation_loss(q1, -q1, weights)) == pytest.approx(0.0, abs=1e-6)


def test_rotation_loss_rejects_mismatched_shapes():
    q = _random_quats(21, 0)
    with pytest.raises(ValueError, match="rotation_loss"):
        rotation_loss(q[None], q[None, :20], torch.ones(21))


def test_root_loss_by_hand():
    a = torch.tensor([[1.0, 2, 3, 4, 5, 6], [0, 0, 0, 0, 0, 0]])
    b = torch.zeros(2, 6)
    assert float(root_loss(a, b)) == pytest.approx((1 + 4 + 9 + 16 + 25 + 36) / 2)
    with pytest.raises(ValueError, match="root_loss"):
        root_loss(a, b[:, :5])


def test_kl_loss_matches_torch_distributions():
    gen = torch.Generator().manual_seed(0)
    mu_q, lv_q, mu_p, lv_p = (torch.randn(4, 7, 5, generator=gen, dtype=torch.float64) for _ in range(4))
    q = torch.distributions.Normal(mu_q, (0.5 * lv_q).exp())
    p = torch.distributions.Normal(mu_p, (0.5 * lv_p).exp())
    expected = torch.distributions.kl_divergence(q, p).sum(-1).mean() / 3
    assert float(kl_loss(mu_q, lv_q, mu_p, lv_p, word_length=3)) == pytest.approx(float(expected), rel=1e-10)


def test_norm_loss_by_hand_and_zero_for_other_heads():
    params = torch.tensor([[[2.0, 0, 0, 0], [0, 0.5, 0, 0]]])  # norms 2 and 0.5
    assert float(norm_loss(params, OutputHead("quaternion"))) == pytest.approx(1.0 + 0.25)
    assert float(norm_loss(torch.ones(1, 2, 9), OutputHead("matrix"))) == 0.0


class _TinyEvaluator(torch.nn.Module):
    """A stand-in for Evaluator: no standardisation, an untrained conv classifier."""

    def __init__(self):
        super().__init__()
        from motionlab.evaluation.classifiers import ClassifierConfig, MotionClassifier

        torch.manual_seed(0)
        heads = {"action": 6, "mode": 12, "body": 2}
        self.classifier = MotionClassifier(ClassifierConfig("conv", EVAL_FEATURES, heads, hidden=8))

    def inputs(self, positions):
        return body_frame_features(positions)


def _clip_positions(seed: int, n: int = 2, frames: int = 12) -> torch.Tensor:
    from motionlab.geometry import axis_angle_to_quat
    from motionlab.skeleton import PARENTS, average_skeleton, forward_kinematics

    gen = torch.Generator().manual_seed(seed)
    rotations = axis_angle_to_quat(0.3 * torch.randn(n, frames, 22, 3, generator=gen))
    root = torch.tensor([0.0, 0.0, 0.9]).expand(n, frames, 3)
    return forward_kinematics(
        rotations, root, torch.tensor(average_skeleton().offsets, dtype=torch.float32), PARENTS
    )[0]


def _real_set():
    """24 clips: two of every (action, body) combination."""
    action = torch.arange(6).repeat_interleave(4)
    body = torch.tensor([0, 1]).repeat(12)
    return _clip_positions(5, n=24), action, body


def test_classifier_loss_is_eq24_layer_distances_plus_cross_entropy_by_hand():
    positions, action, body = _real_set()
    evaluator = _TinyEvaluator()
    loss = ClassifierLoss(evaluator, positions, chunk=7)
    # beta_l: one over each layer's mean squared activation on the real clips
    acts = loss.activations(positions)
    assert len(loss.layer_weights) == len(acts)
    for weight, a in zip(loss.layer_weights, acts):
        assert weight == pytest.approx(1.0 / float((a.double() ** 2).mean()), rel=1e-5)
    real, recon = positions[:6], _clip_positions(3, n=6)
    distance, entropy = loss(recon, real, action[:6], body[:6])
    by_hand = sum(
        w * float(((r - t) ** 2).mean())
        for w, r, t in zip(loss.layer_weights, loss.activations(recon), loss.activations(real))
    )
    assert float(distance) == pytest.approx(by_hand, rel=1e-5)
    features = evaluator.classifier.features(evaluator.inputs(recon))
    heads = evaluator.classifier.heads
    expected = F.cross_entropy(heads["action"](features), action[:6]) + F.cross_entropy(
        heads["body"](features), body[:6]
    )
    assert float(entropy) == pytest.approx(float(expected), rel=1e-6)
    # pairs, not statistics: a perfect reconstruction costs nothing, a shuffled one does
    assert float(loss(real, real, action[:6], body[:6])[0]) == pytest.approx(0.0, abs=1e-10)
    assert float(loss(real[torch.tensor([1, 0, 2, 3, 4, 5])], real, action[:6], body[:6])[0]) > 0
    with pytest.raises(ValueError, match="expected reconstructed and real"):
        loss(recon[:5], real, action[:6], body[:6])


def test_classifier_loss_gradient_reaches_the_reconstruction_but_not_the_classifier():
    positions, _, _ = _real_set()
    evaluator = _TinyEvaluator()
    loss = ClassifierLoss(evaluator, positions)
    recon = _clip_positions(1).requires_grad_(True)
    distance, entropy = loss(recon, _clip_positions(2), torch.tensor([1, 4]), torch.tensor([0, 1]))
    (distance + entropy).backward()
    assert recon.grad is not None and torch.isfinite(recon.grad).all() and recon.grad.abs().sum() > 0
    assert all(p.grad is None for p in evaluator.parameters())


def test_motion_cell_loss_needs_a_classifier_when_its_weight_is_positive(tiny_model, tiny_batch):
    loss_fn = motion_cell_loss(LossConfig())
    terms = loss_fn(tiny_model, tiny_batch, 0, {"beta": 0.5, "word_drop": 0.2})
    assert set(terms) == {"loss", "rotation", "root", "kl", "layer_distance", "cross_entropy", "norm"}
    expected = terms["rotation"] + terms["root"] + 0.5 * terms["kl"] + 0.1 * terms["norm"]
    assert float(terms["loss"].detach()) == pytest.approx(float(expected.detach()), rel=1e-6)
    with pytest.raises(ValueError, match="ClassifierLoss"):
        loss_fn(tiny_model, tiny_batch, 0, {"classifier": 1.0})


def test_motion_cell_loss_with_the_classifier_adds_its_terms_every_second_step(tiny_model, tiny_batch):
    positions, action, body = _real_set()
    loss_fn = motion_cell_loss(
        LossConfig(classifier_clips=2, classifier_every=2),
        ClassifierLoss(_TinyEvaluator(), positions),
    )
    skipped = loss_fn(tiny_model, tiny_batch, 1, {"beta": 1.0, "classifier": 0.5})
    assert float(skipped["cross_entropy"].detach()) == 0 and float(skipped["layer_distance"].detach()) == 0
    terms = loss_fn(tiny_model, tiny_batch, 2, {"beta": 1.0, "classifier": 0.5})
    assert float(terms["cross_entropy"].detach()) > 0 and float(terms["layer_distance"].detach()) > 0
    expected = (
        terms["rotation"]
        + terms["root"]
        + terms["kl"]
        + 2 * 0.5 * (terms["layer_distance"] + terms["cross_entropy"])
        + 0.1 * terms["norm"]
    )
    assert float(terms["loss"].detach()) == pytest.approx(float(expected.detach()), rel=1e-6)
    terms["loss"].backward()
    assert all(torch.isfinite(p.grad).all() for p in tiny_model.parameters() if p.grad is not None)
