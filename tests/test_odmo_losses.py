"""ODMO's embedding loss: eq. 1 against hand computations, the prior term against torch.distributions, pairs,
batches."""

import math

import pytest
import torch
from torch.distributions import Normal, kl_divergence

from motionlab.models.odmo.data import BalancedBatches
from motionlab.models.odmo.losses import balanced_pairs, contrastive_loss, prior_term


def test_contrastive_loss_matches_hand_computation():
    mu_a = torch.tensor([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0], [0.0, 0.0]])
    mu_b = torch.tensor([[3.0, 4.0], [3.0, 4.0], [1.0, 1.0], [6.0, 8.0]])
    same = torch.tensor([True, False, False, False])
    loss = contrastive_loss(mu_a, mu_b, same, margin=5.0)
    # same class at distance 5: 0.5 * 25; different at 5: at the margin, 0; identical codes of
    # different classes: 0.5 * 5**2; different at 10: beyond the margin, 0
    assert torch.allclose(loss, torch.tensor([12.5, 0.0, 12.5, 0.0]))
    short = contrastive_loss(torch.zeros(1, 2), torch.tensor([[1.0, 0.0]]), torch.tensor([False]), margin=5.0)
    assert torch.allclose(short, torch.tensor([0.5 * 16.0]))


def test_contrastive_slack_frees_close_same_class_codes():
    a, b = torch.zeros(2, 3), torch.tensor([[0.3, 0.0, 0.0], [0.0, 2.0, 0.0]])
    loss = contrastive_loss(a, b, torch.tensor([True, True]), margin=5.0, slack=0.5)
    assert torch.allclose(loss, torch.tensor([0.0, 0.5 * (4.0 - 0.25)]))


def test_contrastive_gradient_is_finite_for_identical_codes():
    mu = torch.zeros(1, 4, requires_grad=True)
    contrastive_loss(mu, torch.zeros(1, 4), torch.tensor([False]), margin=5.0).sum().backward()
    assert torch.isfinite(mu.grad).all()


@pytest.mark.parametrize("kind", ["covariance", "covariance_and_mean", "standard"])
def test_prior_term_matches_torch_distributions(kind):
    gen = torch.Generator().manual_seed(0)
    mu, logvar = torch.randn(5, 3, generator=gen), torch.randn(5, 3, generator=gen)
    variance = 0.05
    scale = torch.exp(0.5 * logvar)
    prior = Normal(0.0, math.sqrt(variance))  # sigma^2 is a variance: the Normal's scale is its root
    if kind == "covariance":
        expected = 2 * kl_divergence(Normal(torch.zeros_like(mu), scale), prior)
    elif kind == "covariance_and_mean":
        expected = 2 * kl_divergence(Normal(mu, scale), prior)
    else:
        expected = kl_divergence(Normal(mu, scale), Normal(0.0, 1.0))
    assert torch.allclose(prior_term(mu, logvar, variance, kind), expected.sum(-1), atol=1e-5)


def test_covariance_prior_is_eq_1_up_to_a_constant():
    # eq. 1: -ln det Sigma + Tr(Sigma) / sigma^2, per clip; ours subtracts its minimum D (1 - ln sigma^2)
    gen = torch.Generator().manual_seed(1)
    mu, logvar = torch.randn(4, 3, generator=gen) * 5, torch.randn(4, 3, generator=gen)
    variance = 0.05
    eq1 = -logvar.sum(-1) + logvar.exp().sum(-1) / variance
    expected = eq1 - 3 * (1 - math.log(variance))
    assert torch.allclose(prior_term(mu, logvar, variance, "covariance"), expected, atol=1e-4)
    # the extension adds |mu|^2 / sigma^2: a spring of stiffness 2 / sigma^2 on every code mean
    assert torch.allclose(
        prior_term(mu, logvar, variance, "covariance_and_mean"),
        expected + mu.pow(2).sum(-1) / variance,
        rtol=1e-5,
    )


def test_covariance_prior_ignores_the_mean_and_is_zero_at_the_prior_variance():
    logvar = torch.full((2, 4), math.log(0.05))
    assert torch.allclose(
        prior_term(torch.randn(2, 4) * 10, logvar, 0.05, "covariance"), torch.zeros(2), atol=1e-6
    )


def test_prior_term_rejects_bad_arguments():
    with pytest.raises(ValueError, match="kind"):
        prior_term(torch.zeros(1, 2), torch.zeros(1, 2), 0.05, "other")
    with pytest.raises(ValueError, match="prior_variance"):
        prior_term(torch.zeros(1, 2), torch.zeros(1, 2), 0.0, "covariance")


def test_balanced_pairs_give_one_partner_of_each_kind():
    labels = torch.tensor([0, 0, 1, 1, 1, 2, 2])
    first, second, same = balanced_pairs(labels, torch.Generator().manual_seed(1))
    n = len(labels)
    assert first.tolist() == list(range(n)) * 2
    assert same.tolist() == [True] * n + [False] * n
    assert torch.equal(labels[first[:n]], labels[second[:n]])
    assert (first[:n] != second[:n]).all()
    assert (labels[first[n:]] != labels[second[n:]]).all()


def test_balanced_pairs_reject_unpairable_batches():
    with pytest.raises(ValueError, match="single clip"):
        balanced_pairs(torch.tensor([0, 0, 1]))
    with pytest.raises(ValueError, match="2 classes"):
        balanced_pairs(torch.tensor([0, 0]))


def test_balanced_batches_hold_every_class_equally_and_reuse_no_clip():
    labels = torch.tensor([0] * 5 + [1] * 4 + [2] * 6)
    features = torch.arange(15.0)[:, None, None]
    batches = list(BalancedBatches(features, labels, 3)(0, torch.Generator().manual_seed(0), 6))
    assert len(batches) == 2
    seen = torch.cat([x.flatten() for x, _ in batches])
    assert len(set(seen.tolist())) == 12
    for x, y in batches:
        assert torch.bincount(y, minlength=3).tolist() == [2, 2, 2]
        assert torch.equal(labels[x.flatten().long()], y)
    again = list(BalancedBatches(features, labels, 3)(0, torch.Generator().manual_seed(0), 6))
    assert all(torch.equal(a[0], b[0]) for a, b in zip(batches, again))


def test_balanced_batches_for_validation_deal_every_clip_in_order():
    """``shuffle=False, drop_last=False`` (validation): each class's clips in their stored order, a last
    smaller balanced batch when at least 2 clips of the smallest class remain, the same batches whatever the
    generator."""
    labels = torch.tensor([0, 1] * 5 + [1])  # 5 clips of class 0, 6 of class 1
    features = torch.arange(11.0)[:, None, None]
    source = BalancedBatches(features, labels, 2, shuffle=False, drop_last=False)
    batches = list(source(0, torch.Generator().manual_seed(0), 6))
    assert [x.flatten().tolist() for x, _ in batches] == [[0, 2, 4, 1, 3, 5], [6, 8, 7, 9]]
    assert [y.tolist() for _, y in batches] == [[0, 0, 0, 1, 1, 1], [0, 0, 1, 1]]
    again = list(source(3, torch.Generator().manual_seed(1), 6))
    assert all(torch.equal(a[0], b[0]) for a, b in zip(batches, again))
    assert len(list(source(0, torch.Generator(), 4))) == 2  # 2 per class: the last clip of class 0 is alone
    assert len(list(BalancedBatches(features, labels, 2, shuffle=False)(0, torch.Generator(), 6))) == 1
    with pytest.raises(TypeError, match="BalancedBatches: drop_last must be a bool"):
        BalancedBatches(features, labels, 2, drop_last=0)


def test_balanced_batches_reject_bad_sizes():
    source = BalancedBatches(torch.zeros(8, 1, 1), torch.tensor([0, 1] * 4), 2)
    with pytest.raises(ValueError, match="multiple"):
        next(source(0, torch.Generator(), 5))
    with pytest.raises(ValueError, match="at least 2 clips"):
        BalancedBatches(torch.zeros(3, 1, 1), torch.tensor([0, 0, 1]), 2)
