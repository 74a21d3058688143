"""MDM's denoiser and losses: shapes, the config's defaults and checks, the null condition, the loss terms by
hand and the total of the objective."""

import dataclasses

import pytest
import torch

from motionlab.geometry import quat_normalize
from motionlab.models.diffusion.data import n_features, to_mdm
from motionlab.models.diffusion.losses import (
    diffusion_objective,
    foot_contact_error,
    foot_contact_mask,
    frame_error,
    velocity_error,
)
from motionlab.models.diffusion.model import FOOT_JOINTS, MDM, MDMConfig

TINY = {"latent_dim": 16, "ff_size": 32, "layers": 1, "heads": 2, "dropout": 0.0, "diffusion_steps": 50}


def tiny(**overrides) -> MDM:
    torch.manual_seed(0)
    cfg = MDMConfig(n_frames=12, n_actions=3, **(TINY | overrides))
    return MDM(cfg).fit_standardizer(random_clips(6, cfg.n_frames))


def random_clips(n: int, frames: int) -> torch.Tensor:
    """Features ``(n, frames, 135)`` of random poses and root paths."""
    generator = torch.Generator().manual_seed(n)
    rotations = quat_normalize(torch.randn(n, frames, 22, 4, generator=generator))
    root = torch.cumsum(0.02 * torch.randn(n, frames, 3, generator=generator), dim=1)
    return to_mdm(rotations, root).float()


def test_defaults_are_the_repositorys_and_course_is_smaller():
    cfg = MDMConfig()
    assert (cfg.latent_dim, cfg.ff_size, cfg.layers, cfg.heads) == (512, 1024, 8, 4)
    assert (cfg.diffusion_steps, cfg.cond_mask_prob, cfg.dropout) == (1000, 0.1, 0.1)
    assert (cfg.lambda_pos, cfg.lambda_vel, cfg.lambda_foot, cfg.contact_threshold) == (1.0, 1.0, 1.0, 0.01)
    assert cfg.n_features == n_features(22) == 135
    course = MDMConfig.course(n_actions=4)
    assert course.latent_dim < cfg.latent_dim and course.layers < cfg.layers and course.n_actions == 4
    assert course.diffusion_steps == 1000
    assert FOOT_JOINTS == (7, 10, 8, 11)


def test_forward_shapes_and_shorter_clips():
    model = tiny().eval()
    x = torch.randn(5, 12, 135)
    out = model(x, torch.randint(0, 50, (5,)), torch.tensor([0, 1, 2, 0, 1]))
    assert out.shape == (5, 12, 135)
    assert model(x[:, :7], torch.zeros(5, dtype=torch.int64), None).shape == (5, 7, 135)


def test_the_null_condition():
    model = tiny().eval()
    x, t = torch.randn(4, 12, 135), torch.tensor([3, 10, 20, 49])
    action = torch.tensor([0, 1, 2, 1])
    unconditioned = model(x, t, None)
    assert torch.equal(model(x, t, action, torch.ones(4, dtype=torch.bool)), unconditioned)
    conditioned = model(x, t, action)
    assert not torch.allclose(conditioned, unconditioned)
    mixed = model(x, t, action, torch.tensor([True, False, True, False]))
    assert torch.allclose(mixed[[0, 2]], unconditioned[[0, 2]]) and torch.allclose(
        mixed[[1, 3]], conditioned[[1, 3]]
    )
    # training mode drops the condition with probability cond_mask_prob (no dropout in this model)
    always = tiny(cond_mask_prob=1.0).train()
    assert torch.allclose(always(x, t, action), always.eval()(x, t, None))
    never = tiny(cond_mask_prob=0.0).train()
    assert torch.allclose(never(x, t, action), never.eval()(x, t, action))
    sometimes = tiny(cond_mask_prob=0.5).train()
    torch.manual_seed(1)
    drawn = sometimes(x.repeat(100, 1, 1), t.repeat(100), action.repeat(100))
    null = sometimes.eval()(x.repeat(100, 1, 1), t.repeat(100), None)
    dropped = torch.isclose(drawn, null).flatten(1).all(dim=1).float().mean()
    assert 0.4 < dropped < 0.6


def test_loss_terms_by_hand():
    prediction, target = torch.tensor([[[1.0, 2.0], [3.0, 5.0]]]), torch.tensor([[[0.0, 2.0], [2.0, 4.0]]])
    assert frame_error(prediction, target).tolist() == [0.75]
    # a constant offset has no velocity error; the differences are compared frame to frame
    assert velocity_error(target + 3.0, target).tolist() == [0.0]
    assert velocity_error(prediction, target).tolist() == [0.5]
    positions = torch.zeros(1, 3, 22, 3)
    positions[0, 1, 7, 0] = 0.005  # the left ankle moves 5 mm, then 5 cm
    positions[0, 2, 7, 0] = 0.055
    contact = foot_contact_mask(positions, 0.01)
    assert (
        contact.shape == (1, 2, 4) and contact[0, :, 0].tolist() == [True, False] and contact[0, :, 1:].all()
    )
    predicted = torch.zeros(1, 3, 22, 3)
    predicted[0, 1, 10, 1] = 0.2  # the left foot slides 20 cm while in contact, then back
    assert foot_contact_error(predicted, contact).item() == pytest.approx(2 * 0.2**2 / (2 * 4 * 3))
    assert foot_contact_error(predicted, torch.zeros_like(contact)).item() == 0.0


def test_objective_adds_its_terms_and_reaches_every_parameter():
    model = tiny().train()
    batch = (random_clips(4, 12), torch.tensor([0, 1, 2, 0]))
    torch.manual_seed(3)
    terms = diffusion_objective(model, batch, 0, {})
    assert set(terms) == {"loss", "simple", "position", "velocity", "foot_contact"}
    assert all(value.dim() == 0 and torch.isfinite(value) for value in terms.values())
    total = terms["simple"] + terms["position"] + terms["velocity"] + terms["foot_contact"]
    assert torch.allclose(terms["loss"], total)
    terms["loss"].backward()
    assert all(p.grad is not None and p.grad.abs().sum() > 0 for p in model.parameters())
    simple_only = tiny(lambda_pos=0.0, lambda_vel=0.0, lambda_foot=0.0)
    torch.manual_seed(3)
    terms = diffusion_objective(simple_only, batch, 0, {})
    assert set(terms) == {"loss", "simple"} and torch.equal(terms["loss"], terms["simple"])


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"heads": 3}, "divisible"),
        ({"latent_dim": 0}, "latent_dim"),
        ({"cond_mask_prob": 1.5}, "cond_mask_prob"),
        ({"lambda_foot": -1.0}, "lambda_foot"),
        ({"contact_threshold": 0.0}, "contact_threshold"),
        ({"diffusion_steps": 1}, "diffusion_steps"),
        ({"dropout": 1.0}, "dropout"),
    ],
)
def test_config_rejects_bad_values(change, match):
    with pytest.raises(ValueError, match=match):
        dataclasses.replace(MDMConfig(), **change)


def test_config_rejects_bad_types():
    with pytest.raises(TypeError, match="layers"):
        MDMConfig(layers=True)
    with pytest.raises(TypeError, match="cfg"):
        MDM({"layers": 1})


@pytest.mark.parametrize(
    ("args", "error", "match"),
    [
        ((torch.randn(2, 12, 134), torch.tensor([0, 1]), None), ValueError, "x_t"),
        ((torch.randn(2, 13, 135), torch.tensor([0, 1]), None), ValueError, "frames"),
        ((torch.randn(2, 12, 135), torch.tensor([0.0, 1.0]), None), TypeError, "t must"),
        ((torch.randn(2, 12, 135), torch.tensor([0, 50]), None), ValueError, "steps"),
        ((torch.randn(2, 12, 135), torch.tensor([0, 1]), torch.tensor([0.0, 1.0])), TypeError, "action"),
        ((torch.randn(2, 12, 135), torch.tensor([0, 1]), torch.tensor([0, 3])), ValueError, "actions"),
        ((torch.randn(2, 12, 135), torch.tensor([0, 1]), torch.tensor([0])), ValueError, "action"),
        (
            (torch.randn(2, 12, 135), torch.tensor([0, 1]), torch.tensor([0, 1]), torch.tensor([0, 1])),
            TypeError,
            "null",
        ),
        (
            (
                torch.randn(2, 12, 135),
                torch.tensor([0, 1]),
                torch.tensor([0, 1]),
                torch.ones(3, dtype=torch.bool),
            ),
            ValueError,
            "null",
        ),
    ],
)
def test_forward_rejects_bad_inputs(args, error, match):
    with pytest.raises(error, match=match):
        tiny()(*args)


def test_state_dict_round_trip_restores_weights_and_statistics():
    model = tiny().eval()
    restored = MDM(model.cfg).eval()
    restored.load_state_dict(model.state_dict())
    x, t = torch.randn(2, 12, 135), torch.tensor([1, 30])
    assert torch.equal(restored(x, t, torch.tensor([2, 0])), model(x, t, torch.tensor([2, 0])))
    assert torch.equal(restored.standardizer.std, model.standardizer.std)
