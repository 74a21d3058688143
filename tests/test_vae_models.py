"""MLP and recurrent VAEs: shapes, the ELBO terms against hand computations, determinism, bad input."""

from __future__ import annotations

import math

import pytest
import torch
from torch.distributions import Normal, kl_divergence

from motionlab.models.vae.evaluate import encode_all
from motionlab.models.vae.losses import elbo_loss, elbo_terms, negative_elbo
from motionlab.models.vae.model import MLPVAE, RecurrentVAE, RecurrentVAEConfig, VAEConfig
from motionlab.models.vae.sampling import interpolate_codes
from motionlab.train import Constant, TensorBatches, TrainConfig, train


def _pose_cvae(**kw) -> MLPVAE:
    torch.manual_seed(0)
    return MLPVAE(VAEConfig((6,), latent_dim=3, hidden=8, n_classes=2, **kw))


def _clip_vae(**kw) -> RecurrentVAE:
    torch.manual_seed(0)
    return RecurrentVAE(RecurrentVAEConfig(4, length=5, latent_dim=3, hidden=8, n_classes=2, **kw))


def test_mlp_shapes_conditional_and_clip():
    model = _pose_cvae()
    x, label = torch.randn(7, 6), torch.tensor([0, 1, 0, 1, 1, 0, 0])
    out = model(x, label)
    assert out.mean.shape == (7, 6) and out.mu.shape == out.logvar.shape == out.z.shape == (7, 3)
    clip_model = MLPVAE(VAEConfig((5, 4), latent_dim=2, hidden=8))
    assert clip_model(torch.randn(3, 5, 4)).mean.shape == (3, 5, 4)
    assert clip_model.sample(4, torch.Generator().manual_seed(0)).shape == (4, 5, 4)
    assert model.sample(torch.tensor([1, 0]), torch.Generator().manual_seed(0)).shape == (2, 6)


def test_elbo_terms_match_hand_computation():
    model = _pose_cvae(obs_logvar=math.log(2.0), prior_logvar=math.log(0.05))
    x, label = torch.randn(5, 6, dtype=torch.float32), torch.tensor([0, 1, 1, 0, 1])
    terms = elbo_terms(model, x, label, torch.Generator().manual_seed(3))
    out = model(x, label, torch.Generator().manual_seed(3))  # the same draw of z
    recon = (-Normal(out.mean, math.sqrt(2.0)).log_prob(x)).sum(1).mean()
    kl = (
        kl_divergence(Normal(out.mu, torch.exp(0.5 * out.logvar)), Normal(0.0, math.sqrt(0.05))).sum(1).mean()
    )
    assert terms["recon"].item() == pytest.approx(recon.item(), rel=1e-5)
    assert terms["kl"].item() == pytest.approx(kl.item(), rel=1e-5)
    assert terms["kl_per_dim"].shape == (3,)
    loss = elbo_loss(model, (x, label), 0, {"beta": 0.25})
    assert set(loss) == {"loss", "recon", "kl", "objective"}
    assert loss["loss"].item() == pytest.approx(loss["recon"].item() + 0.25 * loss["kl"].item(), rel=1e-6)
    assert loss["objective"].item() == pytest.approx(loss["recon"].item() + loss["kl"].item(), rel=1e-6)


def test_negative_elbo_is_the_model_free_elbo_terms_up_to_the_constant():
    model = _pose_cvae(obs_logvar=math.log(2.0))
    x, label = torch.randn(5, 6, dtype=torch.float32), torch.tensor([0, 1, 1, 0, 1])
    terms = elbo_terms(model, x, label, torch.Generator().manual_seed(3))
    mu, logvar = model.encode(x, label)
    eps = torch.randn(mu.shape, generator=torch.Generator().manual_seed(3))  # the draw elbo_terms made
    recon, kl = negative_elbo(x, mu, logvar, eps, lambda z: model.decode(z, label), 2.0)
    constant = 0.5 * math.log(2 * math.pi * 2.0) * 6
    assert recon.shape == kl.shape == (5,)
    assert recon.mean().item() + constant == pytest.approx(terms["recon"].item(), rel=1e-5)
    assert kl.mean().item() == pytest.approx(terms["kl"].item(), rel=1e-5)
    with pytest.raises(ValueError, match="eps"):
        negative_elbo(x, mu, logvar, eps[:, :2], lambda z: model.decode(z, label), 2.0)
    with pytest.raises(ValueError, match="obs_var"):
        negative_elbo(x, mu, logvar, eps, lambda z: model.decode(z, label), 0.0)


def test_autoencoder_has_no_noise_and_no_kl():
    model = _pose_cvae(variational=False)
    x, label = torch.randn(4, 6), torch.tensor([0, 1, 0, 1])
    a, b = model(x, label), model(x, label)
    assert a.logvar is None and torch.equal(a.z, a.mu) and torch.equal(a.mean, b.mean)
    loss = elbo_loss(model, (x, label), 0, {"beta": 1.0})
    assert set(loss) == {"loss", "recon"}
    expected = 0.5 * (math.log(2 * math.pi) + (x - a.mean) ** 2).sum(1).mean()
    assert loss["loss"].item() == pytest.approx(expected.item(), rel=1e-6)


def test_recurrent_teacher_forcing_is_causal():
    model = _clip_vae()
    x, label = torch.randn(2, 5, 4), torch.tensor([0, 1])
    z = torch.randn(2, 3)
    base = model.reconstruct(x, z, label)
    changed = x.clone()
    changed[:, 2] += 1.0  # frame 2 may only influence predictions of frames 3 and 4
    after = model.reconstruct(changed, z, label)
    assert torch.equal(base[:, :3], after[:, :3])
    assert not torch.allclose(base[:, 3:], after[:, 3:])


def test_recurrent_free_running_decode_and_non_autoregressive():
    model = _clip_vae()
    z, label = torch.randn(3, 3), torch.tensor([1, 0, 1])
    assert model.decode(z, label).shape == (3, 5, 4)
    assert model.decode(z, label, length=8).shape == (3, 8, 4)
    # the free-running first frame equals the teacher-forced one (both read a zero "previous frame")
    x = torch.randn(3, 5, 4)
    assert torch.allclose(model.decode(z, label)[:, 0], model.reconstruct(x, z, label)[:, 0], atol=1e-6)
    plain = _clip_vae(autoregressive=False)
    assert torch.allclose(plain.decode(z, label), plain.reconstruct(x, z, label), atol=1e-6)


def test_sampling_and_training_are_deterministic_by_seed():
    label = torch.tensor([0, 1, 1])
    for model in (_pose_cvae(prior_logvar=math.log(0.05)), _clip_vae()):
        a = model.sample(label, torch.Generator().manual_seed(7))
        b = model.sample(label, torch.Generator().manual_seed(7))
        assert torch.equal(a, b)
    data = TensorBatches(
        (torch.randn(32, 6, generator=torch.Generator().manual_seed(1)), torch.arange(32) % 2)
    )
    cfg = TrainConfig(steps=5, batch_size=8, checkpoint_every=None, schedules={"beta": Constant(1.0)})
    weights = []
    for _ in range(2):
        model = _pose_cvae()
        train(model, elbo_loss, data, cfg, progress=False)
        weights.append(torch.cat([p.detach().flatten() for p in model.parameters()]))
    assert torch.equal(weights[0], weights[1])


def test_prior_sample_scale():
    model = _pose_cvae(prior_logvar=math.log(0.05))
    z = model.prior_sample(20_000, torch.Generator().manual_seed(0))
    assert z.std().item() == pytest.approx(math.sqrt(0.05), rel=0.02)


def test_encode_all_and_interpolation():
    model = _pose_cvae()
    x, label = torch.randn(10, 6), torch.arange(10) % 2
    mu, logvar = encode_all(model, x, label, chunk=3)
    ref_mu, ref_logvar = model.encode(x, label)
    assert torch.allclose(mu, ref_mu, atol=1e-6) and torch.allclose(logvar, ref_logvar, atol=1e-6)
    z0, z1 = torch.zeros(3), torch.tensor([1.0, 2.0, 3.0])
    path = interpolate_codes(z0, z1, torch.tensor([0.0, 0.5, 1.0]))
    assert torch.equal(path[0], z0) and torch.equal(path[2], z1) and torch.allclose(path[1], z1 / 2)


def test_bad_inputs_raise():
    model = _pose_cvae()
    with pytest.raises(ValueError, match="conditional on 2 classes; pass label"):
        model(torch.randn(2, 6))
    with pytest.raises(ValueError, match=r"label values must lie in \[0, 2\)"):
        model(torch.randn(2, 6), torch.tensor([0, 2]))
    with pytest.raises(ValueError, match=r"MLPVAE.encode: x must have shape \(\.\.\., 6\)"):
        model(torch.randn(2, 5), torch.tensor([0, 1]))
    with pytest.raises(ValueError, match="x contains NaN"):
        model(torch.full((2, 6), float("nan")), torch.tensor([0, 1]))
    with pytest.raises(ValueError, match="unconditional"):
        MLPVAE(VAEConfig((3,), latent_dim=2, hidden=4))(torch.randn(2, 3), torch.tensor([0, 1]))
    with pytest.raises(ValueError, match="this model is conditional"):
        model.sample(3)
    with pytest.raises(ValueError, match=r"x must have shape \(\.\.\., \*, 4\)"):
        _clip_vae()(torch.randn(2, 5, 3), torch.tensor([0, 1]))
    with pytest.raises(TypeError, match="label must have an integer dtype"):
        model(torch.randn(2, 6), torch.tensor([0.0, 1.0]))
    with pytest.raises(ValueError, match=r"label must have shape \(2,\)"):
        model(torch.randn(2, 6), torch.tensor([0, 1, 1]))
    with pytest.raises(ValueError, match="VAEConfig: latent_dim must be at least 1"):
        VAEConfig((3,), latent_dim=0)
    with pytest.raises(TypeError, match="VAEConfig: hidden must be an integer"):
        VAEConfig((3,), hidden=2.5)
    with pytest.raises(ValueError, match="RecurrentVAEConfig: prior_logvar must be a finite number"):
        RecurrentVAEConfig(4, prior_logvar=float("inf"))
    with pytest.raises(ValueError, match=r"frame_dropout must be in \[0, 1\)"):
        RecurrentVAEConfig(4, frame_dropout=1.0)
    with pytest.raises(ValueError, match="input_shape must be a non-empty tuple"):
        VAEConfig(())
    with pytest.raises(TypeError, match="prior_sample: n must be an integer"):
        model.prior_sample(2.0)
