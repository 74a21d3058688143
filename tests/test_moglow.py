"""MoGlow and its Gaussian baseline: conditioning, likelihoods, frame-by-frame sampling, determinism,
errors."""

import math

import numpy as np
import pytest
import torch

from motionlab.models.flows import logdet_error, perturb_parameters_, roundtrip_error
from motionlab.models.moglow import (
    GaussianAR,
    GaussianARConfig,
    LSTMAffineCoupling,
    MoGlow,
    MoGlowConfig,
    MoGlowFeatures,
    autoregressive_conditioning,
    autoregressive_sample,
    dropout_objective_nll,
    frame_conditioning,
    held_out_nll,
    held_out_nll_per_clip,
    held_out_nll_per_window,
    history_keep_mask,
    nll_per_frame_loss,
    sample_loop,
    sample_plain,
)
from motionlab.models.moglow.sampling import sample_frames

SMALL = dict(pose_dim=6, control_dim=2, history=3)


def _moglow(dropout=0.0, dtype=torch.float64, spread=0.1):
    torch.manual_seed(0)
    model = MoGlow(MoGlowConfig(**SMALL, steps=3, hidden=8, cond_features=5, dropout=dropout)).to(dtype)
    return perturb_parameters_(model, spread, torch.Generator().manual_seed(1)).eval()


def _data(batch=2, frames=12, dtype=torch.float64, seed=0):
    generator = torch.Generator().manual_seed(seed)
    return (
        torch.randn(batch, frames, 6, generator=generator, dtype=dtype),
        torch.randn(batch, frames, 2, generator=generator, dtype=dtype),
    )


def test_conditioning_layout_by_hand():
    pose = torch.arange(2 * 5 * 2, dtype=torch.float32).reshape(2, 5, 2)
    control = 100 + torch.arange(2 * 5 * 1, dtype=torch.float32).reshape(2, 5, 1)
    cond = autoregressive_conditioning(pose, control, history=2)
    assert cond.shape == (2, 3, 2 * 2 + 3 * 1)
    # frame t = 2 of clip 1: poses 0, 1 (oldest first), controls 0, 1, 2
    expected = torch.cat([pose[1, 0], pose[1, 1], control[1, 0], control[1, 1], control[1, 2]])
    assert torch.equal(cond[1, 0], expected)
    assert torch.equal(cond[1, 0], frame_conditioning(pose[1:2, 0:2], control[1:2, 0:3])[0])
    keep = torch.tensor([[[0.0, 1.0]] * 3] * 2)
    dropped = autoregressive_conditioning(pose, control, history=2, keep=keep)
    assert torch.equal(dropped[..., :2], torch.zeros_like(dropped[..., :2]))
    assert torch.equal(dropped[..., 2:], cond[..., 2:])


def test_history_keep_mask_rate_and_seed():
    a = history_keep_mask(200, 50, 5, 0.7, torch.Generator().manual_seed(0))
    b = history_keep_mask(200, 50, 5, 0.7, torch.Generator().manual_seed(0))
    assert torch.equal(a, b)
    assert abs(float(a.mean()) - 0.3) < 0.01
    assert set(a.unique().tolist()) <= {0.0, 1.0}
    # inverted dropout: the kept poses scaled by 1 / (1 - p), the same flags, mean weight 1
    scaled = history_keep_mask(200, 50, 5, 0.7, torch.Generator().manual_seed(0), rescale=True)
    assert torch.allclose(scaled, a / 0.3)
    assert abs(float(scaled.mean()) - 1.0) < 0.03


def test_rescaled_dropout_keeps_the_linear_fit_on_the_full_history_scale():
    # an AR(1) sequence: with zeroed (unscaled) history at p = 0.9 the least-squares fit sees each lag alone
    # and sums them on the full history; the rescaled fit's prediction stays on the data's scale
    generator = torch.Generator().manual_seed(0)
    pose = torch.zeros(256, 30, 6, dtype=torch.float64)
    for t in range(1, 30):
        pose[:, t] = 0.95 * pose[:, t - 1] + 0.3 * torch.randn(
            256, 6, generator=generator, dtype=torch.float64
        )
    control = torch.zeros(256, 30, 2, dtype=torch.float64)
    gains = {}
    for rescale in (False, True):
        cfg = MoGlowConfig(**SMALL, steps=1, hidden=4, cond_features=3, dropout=0.9, dropout_rescale=rescale)
        model = MoGlow(cfg).double()
        model.initialize(pose, control)
        past = model.linear.weight[:, : 3 * 6].reshape(6, 3, 6)  # (out, lag, in)
        gains[rescale] = float(past.sum(dim=1).diagonal().mean())  # x_t per unit of a constant history
    assert gains[False] > 1.5 and 0.2 < gains[True] < 1.0


def test_lstm_coupling_logdet_roundtrip_and_frame_weights():
    torch.manual_seed(0)
    layer = perturb_parameters_(
        LSTMAffineCoupling(6, cond_channels=3, hidden=8).double(), 0.3, torch.Generator().manual_seed(0)
    ).eval()
    generator = torch.Generator().manual_seed(1)
    x = torch.randn(2, 6, 5, dtype=torch.float64, generator=generator)
    cond = torch.randn(2, 3, 5, dtype=torch.float64, generator=generator)
    assert logdet_error(layer, x, cond) < 1e-10
    assert roundtrip_error(layer, x, cond) < 1e-12
    y, _ = layer(x, cond)
    layer.out.bias.data[3:] += 0.4  # a non-zero raw-scale bias checks that the offset is folded correctly
    y, _ = layer(x, cond)
    # the split weights, used as the generator uses them, invert the layer frame by frame
    w = layer.frame_weights()
    h = c = torch.zeros(2, 8, dtype=torch.float64)
    rebuilt = []
    for t in range(5):
        y_a, y_b, cond_t = y[:, :3, t], y[:, 3:, t], cond[:, :, t]
        h, c = torch.lstm_cell(
            y_a, (h, c), w.lstm_input_a, w.lstm_hidden, cond_t @ w.lstm_input_cond.T, w.lstm_bias
        )
        shift, raw_scale = (
            h @ w.out_hidden + y_a @ w.out_input_a + cond_t @ w.out_input_cond + w.out_bias
        ).chunk(2, 1)
        rebuilt.append(torch.cat([y_a, y_b / torch.sigmoid(raw_scale) - shift], dim=1))
    assert torch.allclose(torch.stack(rebuilt, dim=2), x, atol=1e-12)


def test_moglow_causality():
    model = _moglow()
    pose, control = _data()
    changed_pose, changed_control = pose.clone(), control.clone()
    changed_pose[:, 9:] += 1.0
    changed_control[:, 9:] += 1.0
    z, _ = model.latents(pose, control)
    z_changed, _ = model.latents(changed_pose, changed_control)
    # frames 3..8 (latents 0..5) depend only on the past and the present control
    assert torch.equal(z[:, :6], z_changed[:, :6])
    assert not torch.allclose(z[:, 6:], z_changed[:, 6:])


@pytest.mark.parametrize("pose_dim", [6, 7])  # 7: the coupling halves differ in size
def test_sampling_inverts_the_training_pass_exactly(pose_dim):
    torch.manual_seed(0)
    cfg = MoGlowConfig(
        pose_dim=pose_dim, control_dim=2, history=3, steps=3, hidden=8, cond_features=5, dropout=0.5
    )
    model = perturb_parameters_(MoGlow(cfg).double(), 0.1, torch.Generator().manual_seed(1)).eval()
    generator = torch.Generator().manual_seed(0)
    seed_pose = torch.randn(2, 3, pose_dim, generator=generator, dtype=torch.float64)
    control = torch.randn(2, 3 + 7, 2, generator=generator, dtype=torch.float64)
    sample = model.sample(control, seed_pose, temperature=1.0, generator=torch.Generator().manual_seed(4))
    assert sample.shape == (2, 7, pose_dim)
    # replay the generator: it draws the latents only (no history dropout when generating)
    latents = torch.randn(2, 7, pose_dim, generator=torch.Generator().manual_seed(4), dtype=torch.float64)
    for generated in (
        sample,
        sample_frames(model.generation_plan(), control, seed_pose, None, latents, scripted=False),
        sample_plain(model, control, seed_pose, temperature=1.0, generator=torch.Generator().manual_seed(4)),
    ):
        full = torch.cat([seed_pose, generated], dim=1)
        cond = autoregressive_conditioning(full, control, 3)  # the full history
        u, _ = model.linear(generated.transpose(1, 2), cond.transpose(1, 2))
        z, _ = model.flow(u, model.cond_encoder(cond).transpose(1, 2))
        assert torch.allclose(z.transpose(1, 2), latents, atol=1e-9)


def test_sampling_is_deterministic_by_seed():
    model = _moglow(dropout=0.3, dtype=torch.float32)
    seed_pose, control = _data(frames=3, dtype=torch.float32)[0], _data(frames=10, dtype=torch.float32)[1]
    a = model.sample(control, seed_pose, 0.8, torch.Generator().manual_seed(0))
    b = model.sample(control, seed_pose, 0.8, torch.Generator().manual_seed(0))
    c = model.sample(control, seed_pose, 0.8, torch.Generator().manual_seed(1))
    assert torch.equal(a, b) and not torch.equal(a, c)


def test_scripted_generation_loop_matches_plain_python_and_reports_divergence():
    model = _moglow(dropout=0.5, dtype=torch.float32)
    seed_pose = _data(frames=3, dtype=torch.float32)[0]
    control = _data(frames=3 + 9, seed=1, dtype=torch.float32)[1]
    keep = history_keep_mask(2, 9, 3, 0.5, torch.Generator().manual_seed(0))
    noise = torch.randn(2, 9, 6, generator=torch.Generator().manual_seed(1))
    plan = model.generation_plan()
    scripted = sample_frames(plan, control, seed_pose, keep, noise)
    plain = sample_frames(plan, control, seed_pose, keep, noise, scripted=False)
    assert torch.allclose(scripted, plain, atol=1e-5)
    assert not torch.equal(
        scripted, sample_frames(plan, control, seed_pose, None, noise)
    )  # the flags are used
    with pytest.raises(ValueError, match=r"shapes disagree: control \(2, 12, 2\)"):
        sample_frames(plan, control, seed_pose, keep, noise[:, :8])
    with pytest.raises(ValueError, match=r"plan's H \* P = 18"):
        sample_frames(plan, control, seed_pose[:, :, :5], keep, noise[:, :, :5])
    with pytest.raises(TypeError, match="share one dtype"):
        sample_frames(plan, control.double(), seed_pose.double(), keep, noise.double())

    def plan_tensors(p):
        return list(p[:-1]) + [t for step in p.steps for t in (*step.coupling, *step[1:])]

    before = [t.clone() for t in plan_tensors(plan)]
    with torch.no_grad():
        for parameter in model.parameters():
            parameter.add_(0.1)
    assert all(
        torch.equal(a, b) for a, b in zip(plan_tensors(plan), before)
    )  # a plan is a snapshot of the weights
    with torch.no_grad():
        model.linear.weight[:, :6] = (
            1e20  # the last pose amplified without bound: overflows within a few frames
        )
    with pytest.raises(
        ValueError, match="MoGlow.sample: generation diverged: non-finite poses from generated frame"
    ):
        model.sample(control, seed_pose, 1.0, torch.Generator().manual_seed(0))


@pytest.mark.parametrize("dropout", [0.0, 0.5])
def test_plain_generation_loop_gives_the_fused_loops_frames(dropout):
    model = _moglow(dropout=dropout, dtype=torch.float32)
    seed_pose = _data(frames=3, dtype=torch.float32)[0]
    control = _data(frames=3 + 20, seed=1, dtype=torch.float32)[1]
    for temperature in (0.0, 0.8):
        fused = model.sample(control, seed_pose, temperature, torch.Generator().manual_seed(7))
        plain = sample_plain(model, control, seed_pose, temperature, torch.Generator().manual_seed(7))
        assert plain.shape == fused.shape == (2, 20, 6)
        torch.testing.assert_close(plain, fused, rtol=1e-5, atol=1e-5)
    with pytest.raises(ValueError, match="sample_plain: temperature"):
        sample_plain(model, control, seed_pose, -1.0)


def test_likelihood_sums_frame_terms_and_loss_is_per_frame():
    model = _moglow()
    pose, control = _data()
    z, logdet = model.latents(pose, control)
    normal = torch.distributions.Normal(torch.zeros(()), torch.ones(())).log_prob(z).sum(dim=(1, 2))
    log_p = model(pose, control)
    assert torch.allclose(log_p, normal + logdet)
    out = nll_per_frame_loss(model, (pose, control), 0, {})
    expected = float(-log_p.detach().sum() / (2 * 9))
    assert math.isclose(float(out["loss"].detach()), expected, rel_tol=1e-9)
    assert held_out_nll(model, MoGlowFeatures(pose, control)) == pytest.approx(expected)


@pytest.mark.parametrize("family", ["moglow", "gaussian"])
def test_history_dropout_is_applied_in_training_only(family):
    # the paper's Fig. 3: "dropout is only applied at training time". The same weights with p = 0.5 and
    # with p = 0 are the same model in eval mode (likelihood and generation); in training mode p = 0.5
    # zeroes previous poses, so its log-likelihood differs (a draw over masks, the training objective).
    pose, control = _data()
    torch.manual_seed(0)
    if family == "moglow":
        configs = [
            MoGlowConfig(**SMALL, steps=2, hidden=8, cond_features=5, dropout=rate) for rate in (0.5, 0.0)
        ]
        models = {cfg.dropout: MoGlow(cfg).double() for cfg in configs}
    else:
        configs = [GaussianARConfig(**SMALL, hidden=8, dropout=rate) for rate in (0.5, 0.0)]
        models = {cfg.dropout: GaussianAR(cfg).double() for cfg in configs}
    models[0.5].initialize(pose, control)
    perturb_parameters_(models[0.5], 0.1, torch.Generator().manual_seed(1))
    for name, buffer in models[0.5].named_buffers():
        if name.endswith("initialized"):
            buffer.fill_(True)  # as after training: a training-mode pass must not re-initialise ActNorm
    models[0.0].load_state_dict(models[0.5].state_dict())  # the same weights
    for model in models.values():
        model.eval()
    dropping, clean = models[0.5], models[0.0]
    assert torch.equal(dropping(pose, control), clean(pose, control))
    seed_pose, more_control = pose[:, :3], _data(frames=9, seed=3)[1]
    for temperature in (0.0, 1.0):
        a = dropping.sample(more_control, seed_pose, temperature, torch.Generator().manual_seed(5))
        b = clean.sample(more_control, seed_pose, temperature, torch.Generator().manual_seed(5))
        assert torch.equal(a, b)
    expected = -float(clean(pose, control).detach().sum()) / (2 * 9)
    dropping.train()
    # held_out_nll measures the model's likelihood (eval mode) and restores the training mode
    assert held_out_nll(dropping, MoGlowFeatures(pose, control)) == pytest.approx(expected)
    assert dropping.training
    drawn = dropping(pose, control, torch.Generator().manual_seed(0))
    assert not torch.allclose(drawn, clean(pose, control))
    # the training objective averages over masks: equal to the likelihood only without dropout
    windows = MoGlowFeatures(pose, control)
    assert dropout_objective_nll(clean, windows) == pytest.approx(held_out_nll(clean, windows))
    assert dropout_objective_nll(dropping, windows) != pytest.approx(held_out_nll(dropping, windows))
    per_window = held_out_nll_per_window(dropping, windows)
    assert per_window.shape == (2,) and float(per_window.mean()) == pytest.approx(expected)


def _baseline_mean_and_std(model, pose, control):
    cond = autoregressive_conditioning(pose, control, 3)
    hidden, _ = model.lstm(cond)
    correction, raw = model.out(hidden).chunk(2, dim=-1)
    scale = model.linear.log_scale.exp()
    return model.linear.mean(cond) + scale * correction, scale * raw.exp()


def test_gaussian_baseline_against_torch_distributions_and_temperature_zero():
    torch.manual_seed(0)
    model = GaussianAR(GaussianARConfig(**SMALL, hidden=8)).double().eval()
    pose, control = _data(batch=16)
    model.initialize(pose, control)
    perturb_parameters_(model, 0.2, torch.Generator().manual_seed(0))
    mean, std = _baseline_mean_and_std(model, pose, control)
    expected = torch.distributions.Normal(mean, std).log_prob(pose[:, 3:]).sum(dim=(1, 2))
    assert torch.allclose(model(pose, control), expected)
    seed_pose, more_control = pose[:, :3], _data(batch=16, frames=8, seed=2)[1]
    zero_latent_path = model.sample(more_control, seed_pose, temperature=0.0)
    # at temperature 0 each frame is the predicted mean given the frames generated before it
    full = torch.cat([seed_pose, zero_latent_path], dim=1)
    assert torch.allclose(zero_latent_path, _baseline_mean_and_std(model, full, more_control)[0], atol=1e-12)


def test_linear_predictor_recovers_a_linear_system_and_is_a_flow_layer():
    generator = torch.Generator().manual_seed(0)
    control = torch.randn(64, 12, 2, generator=generator, dtype=torch.float64)
    weight = torch.randn(6, 3 * 6 + 4 * 2, generator=generator, dtype=torch.float64) * 0.2
    pose = torch.zeros(64, 12, 6, dtype=torch.float64)
    pose[:, :3] = torch.randn(64, 3, 6, generator=generator, dtype=torch.float64)
    for t in range(3, 12):  # x_t = W c_t + 0.5 + tiny noise
        cond = frame_conditioning(pose[:, t - 3 : t], control[:, t - 3 : t + 1])
        pose[:, t] = (
            cond @ weight.T + 0.5 + 1e-3 * torch.randn(64, 6, generator=generator, dtype=torch.float64)
        )
    model = MoGlow(MoGlowConfig(**SMALL, steps=1, hidden=4, cond_features=3, dropout=0.0)).double()
    assert model.linear.fit_rms is None
    rms = model.initialize(pose, control)
    assert rms < 2e-3 and model.linear.fit_rms == rms
    assert "fit_rms" not in str(list(model.state_dict()))
    fitted = {key: value.clone() for key, value in model.linear.state_dict().items()}
    assert model.initialize(pose, control, solve=False) == pytest.approx(
        rms, rel=1e-9
    )  # measured, not refitted
    assert all(torch.equal(value, fitted[key]) for key, value in model.linear.state_dict().items())
    assert torch.allclose(model.linear.weight, weight, atol=0.02)
    assert torch.allclose(model.linear.bias, torch.full((6,), 0.5, dtype=torch.float64), atol=0.02)
    layer = model.linear.eval()
    x = torch.randn(2, 6, 4, dtype=torch.float64, generator=generator)
    cond = torch.randn(2, layer.cond_dim, 4, dtype=torch.float64, generator=generator)
    assert logdet_error(layer, x, cond) < 1e-9
    assert roundtrip_error(layer, x, cond) < 1e-12


def test_autoregressive_loop_feeds_back_its_output():
    def step(t, cond, state):  # next pose = last pose of the history + the current control
        return cond[:, 2:4] + cond[:, -2:], state

    seed_pose = torch.zeros(1, 2, 2)
    control = torch.ones(1, 2 + 3, 2)
    out = autoregressive_sample(step, control, seed_pose)
    assert torch.equal(out[0], torch.tensor([[1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]))

    def exploding(t, cond, state):
        return cond[:, 2:4] * 1e30 + 1.0, state

    with pytest.raises(ValueError, match="diverged: non-finite poses from generated frame 2"):
        autoregressive_sample(exploding, control, seed_pose)


def test_sample_loop_scales_the_noise_and_carries_the_state():
    def invert_frame(z, cond, state):  # next pose = last pose + current control + latent; counts its calls
        calls = 0 if state is None else state
        return cond[:, 2:4] + cond[:, -2:] + z, calls + 1

    seed_pose, control = torch.zeros(1, 2, 2), torch.ones(1, 2 + 3, 2)
    noise = torch.ones(1, 3, 2)
    out = sample_loop(invert_frame, control, seed_pose, noise, temperature=0.5)
    assert torch.equal(out[0], torch.tensor([[1.5, 1.5], [3.0, 3.0], [4.5, 4.5]]))
    assert torch.equal(
        sample_loop(invert_frame, control, seed_pose, noise, 0.0)[0, -1], torch.tensor([3.0, 3.0])
    )
    with pytest.raises(ValueError):
        sample_loop(invert_frame, control, seed_pose, noise[0], 0.5)


def test_held_out_nll_per_clip_averages_each_clips_windows():
    model = _moglow()
    pose, control = _data(batch=6, frames=8)
    windows = MoGlowFeatures(pose, control)
    per_window = held_out_nll_per_window(model, windows)
    per_clip = held_out_nll_per_clip(model, windows, n_clips=3)  # windows 0, 3 are clip 0; 1, 4 clip 1; ...
    assert torch.allclose(per_clip, (per_window[:3] + per_window[3:]) / 2)
    with pytest.raises(ValueError):
        held_out_nll_per_clip(model, windows, n_clips=4)


def test_bad_inputs_raise():
    model = _moglow(dtype=torch.float32)
    pose, control = _data(dtype=torch.float32)
    with pytest.raises(ValueError, match="same frames"):
        model(pose, control[:, :-1])
    with pytest.raises(ValueError, match="NaN"):
        model(pose.masked_fill(torch.rand(pose.shape) > 0.5, float("nan")), control)
    with pytest.raises(ValueError, match=r"MoGlow: pose must have shape \(\.\.\., 6\)"):
        model(pose[..., :5], control)
    with pytest.raises(ValueError, match="at least 3 frames"):
        model.sample(control, pose[:, :2])
    with pytest.raises(ValueError, match="H=3"):
        model.sample(control, pose[:, :4])
    with pytest.raises(ValueError, match="temperature"):
        model.sample(control, pose[:, :3], temperature=-0.1)
    with pytest.raises(ValueError, match="dropout"):
        MoGlowConfig(dropout=1.0)
    with pytest.raises(ValueError, match="GaussianARConfig: hidden must be at least 1, got 0"):
        GaussianARConfig(hidden=0)
    np.testing.assert_equal(MoGlowConfig().cond_dim, 5 * 64 + 6 * 3)


def test_error_policy_type_for_types_value_for_values():
    model = _moglow(dtype=torch.float32)
    pose, control = _data(dtype=torch.float32)
    with pytest.raises(TypeError, match="MoGlowConfig: steps must be an integer, got 2.0"):
        MoGlowConfig(steps=2.0)
    with pytest.raises(TypeError, match="MoGlowConfig: dropout must be a real number"):
        MoGlowConfig(dropout="0.5")
    with pytest.raises(
        ValueError, match=r"MoGlowConfig: pose_dim \(a coupling splits it\) must be at least 2"
    ):
        MoGlowConfig(pose_dim=1)
    with pytest.raises(TypeError, match="MoGlow: pose must have a floating-point dtype, got torch.int64"):
        model(pose.long(), control)
    with pytest.raises(TypeError, match="MoGlow: control must be a torch.Tensor"):
        model(pose, control.numpy())
    with pytest.raises(ValueError, match="MoGlow: pose must be 3-dimensional"):
        model(pose[0], control)
    with pytest.raises(ValueError, match="history_keep_mask: dropout must be in"):
        history_keep_mask(2, 3, 4, 1.5)
    with pytest.raises(TypeError, match="LSTMAffineCoupling: channels must be an integer"):
        LSTMAffineCoupling(6.0, cond_channels=3, hidden=8)
