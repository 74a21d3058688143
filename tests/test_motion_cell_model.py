"""The Motion Cell model: shapes, unit quaternions, determinism by seed, generation of any length, bad
input."""

import math

import pytest
import torch
from test_motion_cell_common import batch, motion_cell, perturb

from motionlab.models.motion_cell.model import InitialState, MotionCellConfig, bounded_logvar
from motionlab.models.motion_cell.smoothing import smooth_word_boundaries


def _quaternion_norms(model, poses):
    return model.codec.split(poses)[0].norm(dim=-1)


def test_forward_shapes_and_unit_quaternions(tiny_model, tiny_batch):
    out = tiny_model(tiny_batch.poses, tiny_batch.action, tiny_batch.body, word_drop=0.3)
    n, t = tiny_batch.poses.shape[:2]
    assert out.poses.shape == (n, t, 90)
    assert out.rotation_params.shape == (n, t, 21, 4)
    for tensor in (out.posterior_mu, out.posterior_logvar, out.prior_mu, out.prior_logvar):
        assert tensor.shape == (n, t // 3, 4)
    torch.testing.assert_close(_quaternion_norms(tiny_model, out.poses), torch.ones(n, t, 21))


def test_untrained_decoder_starts_at_the_rest_pose(tiny_model, tiny_batch):
    out = tiny_model(tiny_batch.poses, tiny_batch.action, tiny_batch.body)
    quaternions, root = tiny_model.codec.split(out.poses)
    torch.testing.assert_close(quaternions, torch.tensor([1.0, 0, 0, 0]).expand_as(quaternions))
    assert torch.all(root == 0)


def test_the_posterior_sees_the_words_and_the_prior_does_not(tiny_model, tiny_batch):
    g = lambda: torch.Generator().manual_seed(3)  # noqa: E731
    a = tiny_model(tiny_batch.poses, tiny_batch.action, tiny_batch.body, generator=g())
    changed = tiny_batch.poses.clone()
    changed[:, 3:] += 0.5  # change every word from the second on
    b = tiny_model(changed, tiny_batch.action, tiny_batch.body, generator=g())
    torch.testing.assert_close(a.posterior_mu[:, 0], b.posterior_mu[:, 0])  # word 1 unchanged
    assert not torch.allclose(a.posterior_mu[:, 1], b.posterior_mu[:, 1])
    torch.testing.assert_close(a.prior_mu[:, :2], b.prior_mu[:, :2])  # p(z_t | h_{t-1}) reads words < t only
    assert not torch.allclose(a.prior_mu[:, 2], b.prior_mu[:, 2])


def test_dropped_words_are_replaced_by_the_models_own_output(tiny_model, tiny_batch):
    """Scheduled sampling (§4.2): with word_drop = 1 the transition reads f_w(f_enc^w(w~_t)), the word the
    cell decodes from its posterior latent, never the data; the posterior still reads the data."""
    from motionlab.models.gaussian import reparameterize

    model, (poses, action, body) = tiny_model, tiny_batch
    torch.nn.init.normal_(model.word_decoder.net[-1].weight, std=0.1)  # own output != rest pose
    out = model(poses, action, body, word_drop=1.0, generator=torch.Generator().manual_seed(5))
    g = torch.Generator().manual_seed(5)
    cell = model.cell
    with torch.no_grad():
        n_words = poses.shape[1] // 3
        torch.rand(poses.shape[0], n_words, 1, generator=g)  # the drop mask
        control = cell.control(action, body)
        pre = cell.posterior_input(model.encode_words(poses), control[:, None].expand(-1, n_words, -1))
        layers = cell.initial_state(action, body, g)
        states = []
        for t in range(n_words):
            state = torch.cat(layers, dim=-1)  # both GRU states
            states.append(state)
            mu, logvar = cell.posterior(pre[:, t], state)
            features = cell.latent_feature(reparameterize(mu, logvar, g))
            own, _ = model.decode_words(cell.decode(features, state, control)[:, None])
            layers = cell.transition(layers, model.encode_words(own)[:, 0], features, control)
        prior_mu, _ = cell.prior(torch.stack(states, dim=1), control[:, None].expand(-1, n_words, -1))
    torch.testing.assert_close(out.prior_mu, prior_mu)


def test_prior_posterior_and_decoder_read_both_gru_states(tiny_model):
    cell = tiny_model.cell
    h = cell.cfg.hidden_dim
    assert cell.prior_net[0].in_features == 2 * h + cell.cfg.control_dim
    assert cell.posterior_state.in_features == 2 * h
    assert cell.decoder_net[0].in_features == cell.cfg.feature_dim + 2 * h + cell.cfg.control_dim
    control = cell.control(torch.tensor([0]), torch.tensor([1]))
    lower, upper = torch.zeros(1, h), torch.zeros(1, h)
    a = cell.prior(cell.state((lower, upper)), control)[0]
    b = cell.prior(cell.state((lower + 1.0, upper)), control)[0]
    assert not torch.allclose(a, b)  # the lower GRU's state reaches the prior


def test_forward_is_deterministic_given_the_generator(tiny_model, tiny_batch):
    runs = [
        tiny_model(
            tiny_batch.poses,
            tiny_batch.action,
            tiny_batch.body,
            word_drop=0.5,
            generator=torch.Generator().manual_seed(11),
        )
        for _ in range(2)
    ]
    for x, y in zip(*runs):
        assert torch.equal(x, y)


@pytest.mark.parametrize("n_frames", [1, 7, 12, 100])
def test_generate_any_length_with_unit_quaternions(tiny_model, n_frames):
    action, body = torch.tensor([0, 5, 2]), torch.tensor([1, 0, 1])
    poses = tiny_model.generate(action, body, n_frames, torch.Generator().manual_seed(0))
    assert poses.shape == (3, n_frames, 90)
    torch.testing.assert_close(_quaternion_norms(tiny_model, poses), torch.ones(3, n_frames, 21))


def test_generation_with_the_same_seed_is_bitwise_identical_and_other_seeds_differ():
    model = motion_cell()
    perturb(model.word_decoder.net[-1].weight, 0.1)  # a decoder that moves
    action, body = torch.tensor([0, 3]), torch.tensor([0, 1])
    a = model.generate(action, body, 30, torch.Generator().manual_seed(7))
    b = model.generate(action, body, 30, torch.Generator().manual_seed(7))
    c = model.generate(action, body, 30, torch.Generator().manual_seed(8))
    assert torch.equal(a, b)
    assert not torch.equal(a, c)


def test_a_longer_generation_starts_with_the_shorter_one():
    model = motion_cell()
    perturb(model.word_decoder.net[-1].weight, 0.1)
    action, body = torch.tensor([1]), torch.tensor([0])
    short = model.generate(action, body, 9, torch.Generator().manual_seed(2), smooth=False)
    long = model.generate(action, body, 60, torch.Generator().manual_seed(2), smooth=False)
    torch.testing.assert_close(long[:, :9], short)


def test_generate_smooths_the_decoded_words_by_default():
    model = motion_cell()
    perturb(model.word_decoder.net[-1].weight, 0.1)
    action, body = torch.tensor([1, 4]), torch.tensor([0, 1])
    decoded = model.generate(action, body, 30, torch.Generator().manual_seed(2), smooth=False)
    generated = model.generate(action, body, 30, torch.Generator().manual_seed(2))
    assert torch.equal(generated, smooth_word_boundaries(decoded, model.cfg.word_length))
    assert not torch.equal(generated, decoded)


@pytest.mark.parametrize("output,params", [("quaternion", 4), ("matrix", 9), ("axis_angle", 3)])
def test_every_output_head_gives_unit_quaternions(output, params, tiny_batch):
    model = motion_cell(output=output)
    perturb(model.word_decoder.net[-1].weight, 0.3)
    out = model(tiny_batch.poses, tiny_batch.action, tiny_batch.body)
    assert out.rotation_params.shape[-1] == params
    torch.testing.assert_close(_quaternion_norms(model, out.poses), torch.ones(out.poses.shape[:2] + (21,)))


def test_sl_ablation_runs_the_recurrence_once_per_frame_without_word_layers():
    model = motion_cell(word_length=1, word_layers=False)
    assert isinstance(model.word_encoder, torch.nn.Identity) and isinstance(
        model.word_decoder, torch.nn.Identity
    )
    assert model.cell.word_feature[0].in_features == 90 and model.cell.decoder_net[-1].out_features == 90
    b = batch(frames=10)
    out = model(b.poses, b.action, b.body, word_drop=0.5)
    assert out.posterior_mu.shape[:2] == (12, 10)
    torch.testing.assert_close(_quaternion_norms(model, out.poses), torch.ones(12, 10, 21))
    assert model.generate(b.action, b.body, 7).shape == (12, 7, 90)


def test_bad_input_raises_clear_errors(tiny_model, tiny_batch):
    poses, action, body = tiny_batch
    with pytest.raises(ValueError, match="whole number of words"):
        tiny_model(poses[:, :10], action, body)
    with pytest.raises(ValueError, match=r"\(\.\.\., 90\)"):
        tiny_model(poses[..., :89], action, body)
    bad = poses.clone()
    bad[0, 0, 0] = math.nan
    with pytest.raises(ValueError, match="NaN"):
        tiny_model(bad, action, body)
    with pytest.raises(ValueError, match="word_drop"):
        tiny_model(poses, action, body, word_drop=1.5)
    with pytest.raises(ValueError, match="action values"):
        tiny_model(poses, action + 6, body)
    with pytest.raises(TypeError, match="action must hold integer class indices"):
        tiny_model(poses, action.float(), body)
    with pytest.raises(ValueError, match="n_frames"):
        tiny_model.generate(action, body, 0)
    with pytest.raises(ValueError, match="action and body"):
        tiny_model.generate(action, body[:3], 6)


def test_config_validation():
    with pytest.raises(ValueError, match="output"):
        MotionCellConfig(output="euler")
    with pytest.raises(ValueError, match="word_length"):
        MotionCellConfig(word_length=0)
    with pytest.raises(TypeError, match="MotionCellConfig: hidden_dim must be an integer"):
        MotionCellConfig(hidden_dim=16.0)
    with pytest.raises(TypeError, match="MotionCellConfig: n_joints"):
        MotionCellConfig(n_joints=True)


def test_initial_state_is_a_learned_gaussian_per_attribute_combination():
    initial = InitialState(n_actions=3, n_bodies=2, size=4)
    with torch.no_grad():
        initial.mean[1 * 2 + 1] = 5.0  # action 1, body 1
        initial.logvar.fill_(math.log(0.25))  # sigma = 0.5
    n = 4000
    states = initial(
        torch.tensor([1, 0]).repeat_interleave(n),
        torch.tensor([1, 1]).repeat_interleave(n),
        torch.Generator().manual_seed(0),
    )
    for part, mean in ((states[:n], 5.0), (states[n:], 0.0)):
        torch.testing.assert_close(part.mean(0), torch.full((4,), mean), atol=0.05, rtol=0)
        torch.testing.assert_close(part.std(0), torch.full((4,), 0.5), atol=0.03, rtol=0)


def test_bounded_logvar_is_the_identity_near_zero_and_bounded():
    x = torch.tensor([-1e6, -0.01, 0.0, 0.01, 1e6])
    y = bounded_logvar(x)
    assert y[0] >= -8.0 and y[-1] <= 8.0
    assert -8.0 < float(bounded_logvar(torch.tensor(-20.0))) < -7.5
    torch.testing.assert_close(y[1:4], x[1:4], atol=1e-6, rtol=1e-4)
