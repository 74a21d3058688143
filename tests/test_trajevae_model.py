"""TrajeVAE, its ablation switches and the recurrent baselines: shapes, semantics, losses, determinism,
errors."""

import dataclasses

import pytest
import torch

from motionlab.models.trajevae.baselines import CVAERNN, GRUCompletion, RecurrentConfig
from motionlab.models.trajevae.experiment import RUNGS, SWITCHES, ladder
from motionlab.models.trajevae.losses import (
    cvae_rnn_loss,
    gru_loss,
    latent_kl,
    squared_error_terms,
    trajevae_loss,
)
from motionlab.models.trajevae.masks import given_trajectories
from motionlab.models.trajevae.model import TrajeVAE, TrajeVAEConfig

TINY = TrajeVAEConfig(n_frames=9, width=8, latent_dim=3, dct_components=4, heads=2)
TINY_RNN = RecurrentConfig(n_frames=9, hidden=8)


def _batch(n=3, frames=9, seed=0):
    g = torch.Generator().manual_seed(seed)
    windows = torch.randn(n, frames, 66, generator=g)
    mask = torch.rand(n, 22, generator=g) < 0.3
    return windows, mask


def _randomise(model):
    """Non-zero weights everywhere (the offset heads start at zero on purpose)."""
    with torch.no_grad():
        for p in model.parameters():
            p.add_(0.1 * torch.randn_like(p))
    return model.eval()


def test_forward_shapes_and_loss_terms():
    model = TrajeVAE(TINY)
    windows, mask = _batch()
    out = model(windows, mask)
    assert out.poses.shape == (3, 8, 66)
    assert out.prior.mu.shape == out.posterior.mu.shape == (3, 4, 3)
    terms = trajevae_loss(model, (windows, mask), 0, {})
    assert set(terms) == {"loss", "recon", "recon_given", "recon_hidden", "recon_sum", "kl"}
    torch.testing.assert_close(terms["recon"], terms["recon_given"] + terms["recon_hidden"])


def test_fresh_decoder_holds_the_initial_pose():
    model = TrajeVAE(TINY)
    windows, mask = _batch()
    poses = model(windows, mask).poses
    torch.testing.assert_close(poses, windows[:, :1].expand(-1, 8, -1))


def test_squared_error_terms_by_hand():
    predicted = torch.zeros(2, 1, 66)
    target = torch.ones(2, 1, 66)
    target[1] *= 2.0
    mask = torch.zeros(2, 22, dtype=torch.bool)
    mask[:, 0] = True
    terms = squared_error_terms(predicted, target, mask)
    # sequence 0: 66 errors of 1; sequence 1: 66 errors of 4; mean over all 132 elements
    assert terms["recon"].item() == pytest.approx((66 + 264) / 132)
    assert terms["recon_given"].item() == pytest.approx((3 + 12) / 132)
    # eq. 2: summed over frames and coordinates, averaged over the 2 sequences
    assert terms["recon_sum"].item() == pytest.approx((66 + 264) / 2)


def test_trajevae_loss_sums_the_squared_errors_as_eq_2():
    """The paper's reconstruction term is the sum over frames and coordinates; "mean" is the variant that
    divides it by F * 3J, which is the paper's objective with beta multiplied by F * 3J."""
    model = _randomise(TrajeVAE(TINY)).train()
    windows, mask = _batch()
    torch.manual_seed(0)
    terms = trajevae_loss(model, (windows, mask), 0, {})
    torch.manual_seed(0)  # the same posterior sample
    poses = model(windows, mask).poses
    by_hand = ((poses - windows[:, 1:]) ** 2).sum(dim=(1, 2)).mean()  # 8 frames x 66 coordinates
    assert terms["recon_sum"].item() == pytest.approx(by_hand.item(), rel=1e-5)
    assert terms["recon_sum"].item() == pytest.approx(terms["recon"].item() * 8 * 66, rel=1e-5)
    assert terms["loss"].item() == pytest.approx(
        terms["recon_sum"].item() + TINY.beta * terms["kl"].item(), rel=1e-5
    )
    mean_model = _randomise(TrajeVAE(dataclasses.replace(TINY, reconstruction="mean"))).train()
    mean_terms = trajevae_loss(mean_model, (windows, mask), 0, {})
    assert mean_terms["loss"].item() == pytest.approx(
        mean_terms["recon"].item() + TINY.beta * mean_terms["kl"].item(), rel=1e-5
    )
    with pytest.raises(ValueError, match="reconstruction"):
        TrajeVAEConfig(reconstruction="median")
    with pytest.raises(ValueError, match="reconstruction"):
        RecurrentConfig(reconstruction="max")


def test_kl_matches_torch_distributions():
    model = _randomise(TrajeVAE(TINY)).train()
    out = model(*_batch(), generator=torch.Generator().manual_seed(0))
    q = torch.distributions.Normal(out.posterior.mu, torch.exp(0.5 * out.posterior.logvar))
    p = torch.distributions.Normal(out.prior.mu, torch.exp(0.5 * out.prior.logvar))
    expected = torch.distributions.kl_divergence(q, p).sum() / 3
    torch.testing.assert_close(latent_kl(out), expected)
    base = _randomise(TrajeVAE(ladder(TINY)["Base"]))
    out = base(*_batch())
    assert out.posterior is None
    q = torch.distributions.Normal(out.prior.mu, torch.exp(0.5 * out.prior.logvar))
    expected = torch.distributions.kl_divergence(q, torch.distributions.Normal(0.0, 1.0)).sum() / 3
    torch.testing.assert_close(latent_kl(out), expected)


def test_posterior_sees_only_the_hidden_joints():
    model = _randomise(TrajeVAE(TINY))
    windows, mask = _batch()
    changed = windows.clone()
    given_channels = mask.repeat_interleave(3, dim=-1)[:, None, :].expand(-1, 9, -1).clone()
    given_channels[:, 0] = False  # the initial pose is seen by both
    changed[given_channels] += 1.0
    g = torch.Generator
    # the reconstruction decodes a posterior sample: identical noise, identical output
    a = model(windows, mask, generator=g().manual_seed(0)).poses
    b = model(changed, mask, generator=g().manual_seed(0)).poses
    torch.testing.assert_close(a, b)
    unmasked = _randomise(TrajeVAE(dataclasses.replace(TINY, mask_future_poses=False)))
    a = unmasked(windows, mask, generator=g().manual_seed(0)).poses
    b = unmasked(changed, mask, generator=g().manual_seed(0)).poses
    assert not torch.allclose(a, b)


def test_sampling_shapes_means_and_seed():
    model = _randomise(TrajeVAE(TINY))
    windows, mask = _batch()
    start, trajectories = windows[:, 0], given_trajectories(windows[:, 1:], mask)
    samples = model.sample(start, trajectories, 5, generator=torch.Generator().manual_seed(3))
    assert samples.shape == (3, 5, 8, 66)
    again = model.sample(start, trajectories, 5, generator=torch.Generator().manual_seed(3))
    assert torch.equal(samples, again)
    assert not torch.equal(samples[:, 0], samples[:, 1])
    single = model.sample(start, trajectories, 1)
    cold = model.sample(start, trajectories, 5, temperature=0.0)
    torch.testing.assert_close(cold, single.expand(-1, 5, -1, -1))
    # the means decoded by hand
    embed = model.initial_pose_encoder(start)
    prior = model.prior(trajectories, embed)
    torch.testing.assert_close(single[:, 0], model.decoder(prior.mu, start, embed))


def test_same_seed_same_weights():
    a, b = TrajeVAE(TINY), TrajeVAE(TINY)
    for (name, p), q in zip(a.state_dict().items(), b.state_dict().values()):
        assert torch.equal(p, q), name
    c = TrajeVAE(dataclasses.replace(TINY, seed=TINY.seed + 1))  # TINY's seed is the base seed
    assert not torch.equal(a.frame_encoder[0].weight, c.frame_encoder[0].weight)


def test_bad_inputs_raise_clear_errors():
    model = TrajeVAE(TINY)
    windows, mask = _batch()
    with pytest.raises(ValueError, match="windows must have shape"):
        model(windows[:, :5], mask)
    bad = windows.clone()
    bad[0, 2, 5] = float("nan")
    with pytest.raises(ValueError, match="NaN"):
        model(bad, mask)
    with pytest.raises(TypeError, match="TrajeVAE.forward: mask must be a bool"):
        model(windows, mask.float())
    with pytest.raises(ValueError, match="TrajeVAE.forward: mask must have shape"):
        model(windows, mask[:2])
    with pytest.raises(TypeError, match="windows must have a floating-point dtype"):
        model(windows.long(), mask)
    with pytest.raises(ValueError, match="n_samples"):
        model.sample(windows[:, 0], windows[:, 1:], 0)
    with pytest.raises(ValueError, match="temperature"):
        model.sample(windows[:, 0], windows[:, 1:], 2, temperature=-1.0)
    with pytest.raises(ValueError, match="trajectories must have shape"):
        model.sample(windows[:, 0], windows[:2, 1:], 2)


def test_config_validation():
    with pytest.raises(ValueError, match="dct_components"):
        TrajeVAEConfig(n_frames=9, dct_components=9)
    with pytest.raises(ValueError, match="needs learnable_prior"):
        TrajeVAEConfig(learnable_prior=False, mask_future_poses=True)
    with pytest.raises(ValueError, match="divisible"):
        TrajeVAEConfig(width=5, heads=4)
    with pytest.raises(ValueError, match="probability"):
        TrajeVAEConfig(keep_probability=2.0)
    with pytest.raises(TypeError, match="TrajeVAEConfig"):
        TrajeVAE(TINY_RNN)
    with pytest.raises(TypeError, match="TrajeVAEConfig: width must be an integer"):
        TrajeVAEConfig(width=8.0)
    with pytest.raises(TypeError, match="TrajeVAEConfig: use_dct must be a bool"):
        TrajeVAEConfig(use_dct=1)
    with pytest.raises(ValueError, match="RecurrentConfig: latent_dim must be at least 0"):
        RecurrentConfig(latent_dim=-1)


def test_ablation_ladder_turns_switches_on_one_by_one():
    rungs = ladder(TINY)
    assert tuple(rungs) == RUNGS
    for index, cfg in enumerate(rungs.values()):
        assert [getattr(cfg, s) for s in SWITCHES] == [i < index for i in range(len(SWITCHES))]
        assert cfg.width == TINY.width and cfg.beta == TINY.beta
    assert rungs["+ masked future poses"] == TINY
    assert TrajeVAE(rungs["Base"]).posterior_branch is None
    frames = TrajeVAE(rungs["Base"])(*_batch())
    assert frames.prior.mu.shape == (3, 8, 3)  # one latent per frame without the DCT


def test_gru_baseline_is_deterministic():
    model = _randomise(GRUCompletion(TINY_RNN))
    windows, mask = _batch()
    start, trajectories = windows[:, 0], given_trajectories(windows[:, 1:], mask)
    samples = model.sample(start, trajectories, 4, generator=torch.Generator().manual_seed(0))
    assert samples.shape == (3, 4, 8, 66)
    assert torch.equal(samples[:, 0], samples[:, 3])
    torch.testing.assert_close(samples[:, 0], model(windows, mask))
    terms = gru_loss(model, (windows, mask), 0, {})
    assert set(terms) == {"loss", "recon", "recon_given", "recon_hidden", "recon_sum"}
    assert terms["loss"].item() == pytest.approx(terms["recon_sum"].item())
    with pytest.raises(ValueError, match="latent_dim"):
        GRUCompletion(dataclasses.replace(TINY_RNN, latent_dim=2))


def test_cvae_rnn_one_latent_per_sequence():
    cfg = dataclasses.replace(TINY_RNN, latent_dim=3)
    model = _randomise(CVAERNN(cfg))
    windows, mask = _batch()
    poses, posterior = model(windows, mask)
    assert poses.shape == (3, 8, 66) and posterior.mu.shape == (3, 3)
    start, trajectories = windows[:, 0], given_trajectories(windows[:, 1:], mask)
    samples = model.sample(start, trajectories, 4, generator=torch.Generator().manual_seed(0))
    assert samples.shape == (3, 4, 8, 66) and not torch.equal(samples[:, 0], samples[:, 1])
    assert torch.equal(
        samples, model.sample(start, trajectories, 4, generator=torch.Generator().manual_seed(0))
    )
    terms = cvae_rnn_loss(model.train(), (windows, mask), 0, {})
    assert terms["loss"].item() == pytest.approx(
        terms["recon_sum"].item() + cfg.beta * terms["kl"].item(), rel=1e-5
    )
    with pytest.raises(ValueError, match="latent_dim"):
        CVAERNN(TINY_RNN)
