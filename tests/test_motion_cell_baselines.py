"""ERD and the QuaterNet-style RNN: shapes, teacher forcing, determinism, randomness only in the initial
state."""

import pytest
import torch
from test_motion_cell_common import baseline, batch, perturb

from motionlab.models.motion_cell.baselines import BaselineConfig, baseline_loss
from motionlab.models.motion_cell.losses import LossConfig


@pytest.mark.parametrize("kind", ["erd", "quaternet"])
def test_shapes_and_unit_quaternions(kind):
    model = baseline(kind)
    b = batch()
    out = model(b.poses, b.action, b.body)
    assert out.poses.shape == b.poses.shape and out.rotation_params.shape == (12, 12, 21, 4)
    torch.testing.assert_close(model.codec.split(out.poses)[0].norm(dim=-1), torch.ones(12, 12, 21))
    poses = model.generate(b.action, b.body, 17, torch.Generator().manual_seed(0))
    assert poses.shape == (12, 17, 90)


@pytest.mark.parametrize("kind", ["erd", "quaternet"])
def test_prediction_of_frame_t_only_reads_frames_before_t(kind):
    model = baseline(kind)
    perturb(model.decoder[-1].weight, 0.1)
    b = batch()
    g = lambda: torch.Generator().manual_seed(1)  # noqa: E731
    a = model(b.poses, b.action, b.body, generator=g()).poses
    changed = b.poses.clone()
    changed[:, 6:] += 0.3
    c = model(changed, b.action, b.body, generator=g()).poses
    torch.testing.assert_close(a[:, :7], c[:, :7])
    assert not torch.allclose(a[:, 7:], c[:, 7:])


@pytest.mark.parametrize("kind", ["erd", "quaternet"])
def test_generation_is_random_only_through_the_initial_state(kind):
    model = baseline(kind)
    perturb(model.decoder[-1].weight, 0.1)
    action, body = torch.tensor([2, 2]), torch.tensor([1, 1])
    a = model.generate(action, body, 3, torch.Generator().manual_seed(4))
    b = model.generate(action, body, 3, torch.Generator().manual_seed(4))
    assert torch.equal(a, b)
    spread = (a[0] - a[1]).abs().max()
    assert spread > 0  # two initial states drawn
    with torch.no_grad():
        model.initial.logvar.fill_(-1e4)  # (almost) no spread: the samples of a setting (almost) coincide
    c = model.generate(action, body, 3, torch.Generator().manual_seed(5))
    assert (c[0] - c[1]).abs().max() < 0.2 * spread


def test_erd_input_noise_and_quaternet_sampling_change_the_inputs_only_when_asked():
    b = batch()
    erd = baseline("erd")
    perturb(erd.decoder[-1].weight, 0.1)
    g = lambda: torch.Generator().manual_seed(3)  # noqa: E731
    clean = erd(b.poses, b.action, b.body, generator=g()).poses
    noisy = erd(b.poses, b.action, b.body, input_noise=0.1, generator=g()).poses
    assert torch.equal(clean, erd(b.poses, b.action, b.body, generator=g()).poses)
    assert not torch.allclose(clean[:, 1:], noisy[:, 1:])
    with pytest.raises(ValueError, match="sampling"):
        erd(b.poses, b.action, b.body, sampling=2.0)


def test_baseline_losses_have_their_terms_and_backpropagate():
    b = batch()
    for kind, coeffs in (("erd", {"input_noise": 0.05}), ("quaternet", {"sampling": 0.5})):
        model = baseline(kind)
        terms = baseline_loss(LossConfig())(model, b, 0, coeffs)
        assert set(terms) == {"loss", "pose", "root", "norm"}
        terms["loss"].backward()
        assert all(torch.isfinite(p.grad).all() for p in model.parameters() if p.grad is not None)


def test_quaternet_pose_term_is_the_joint_distance_in_metres_on_every_second_frame():
    b = batch()
    model = baseline("quaternet")
    terms = baseline_loss(LossConfig())(model, b, 0, {})
    out = model(b.poses, b.action, b.body)
    local = model.codec.local_positions
    expected = (local(out.poses[:, ::2], b.body) - local(b.poses[:, ::2], b.body)).norm(dim=-1).sum(-1).mean()
    assert float(terms["pose"].detach()) == pytest.approx(float(expected.detach()), rel=1e-5)


def test_baseline_config_validation():
    with pytest.raises(ValueError, match="kind"):
        BaselineConfig(kind="lstm")
