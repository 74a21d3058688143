"""Sampling from MDM: classifier-free guidance, inpainting that returns the given part exactly, the fast
variant, reproducibility and bad inputs."""

import pytest
import torch

from motionlab.models.diffusion.data import known_mask
from motionlab.models.diffusion.model import MDM, MDMConfig
from motionlab.models.diffusion.sampling import Edit, guided_prediction, sample


def tiny(**overrides) -> MDM:
    torch.manual_seed(0)
    sizes = {"latent_dim": 16, "ff_size": 32, "layers": 1, "heads": 2, "dropout": 0.0, "diffusion_steps": 40}
    cfg = MDMConfig(n_frames=10, n_actions=3, **(sizes | overrides))
    return MDM(cfg).fit_standardizer(torch.randn(8, cfg.n_frames, cfg.n_features))


def test_guidance_extrapolates_from_the_null_prediction():
    model = tiny().eval()
    x, t, action = torch.randn(3, 10, 135), torch.tensor([5, 20, 39]), torch.tensor([0, 2, 1])
    conditional, unconditional = model(x, t, action), model(x, t, None)
    assert torch.allclose(guided_prediction(model, x, t, action, 1.0), conditional, atol=1e-5)
    assert torch.allclose(guided_prediction(model, x, t, action, 0.0), unconditional, atol=1e-5)
    expected = unconditional + 2.5 * (conditional - unconditional)
    assert torch.allclose(guided_prediction(model, x, t, action, 2.5), expected, atol=1e-5)
    assert torch.equal(guided_prediction(model, x, t, action, None), conditional)
    assert torch.equal(guided_prediction(model, x, t, None, 2.5), unconditional)


@pytest.mark.parametrize("inpaint", ["prediction", "noised"])
@pytest.mark.parametrize(("method", "steps"), [("ancestral", None), ("ancestral", 7), ("ddim", 7)])
def test_inpainting_returns_the_given_part_exactly(inpaint, method, steps):
    model = tiny()
    given = torch.randn(2, 10, 135)
    known = known_mask(10, 22, frames=[0, 1, 8, 9], joints=[4], root_position=True)
    out = sample(
        model,
        torch.tensor([0, 2]),
        steps=steps,
        method=method,
        guidance=2.5,
        edit=Edit(given, known),
        inpaint=inpaint,
        generator=torch.Generator().manual_seed(0),
    )
    mask = known.expand_as(given)
    assert torch.allclose(out[mask], given[mask], atol=1e-5)
    assert (out[~mask] - given[~mask]).abs().mean() > 0.1  # the rest is generated, not copied


def test_samples_have_the_shape_and_are_reproducible():
    model = tiny()
    first = sample(model, None, n_samples=3, steps=5, generator=torch.Generator().manual_seed(4))
    again = sample(model, None, n_samples=3, steps=5, generator=torch.Generator().manual_seed(4))
    assert first.shape == (3, 10, 135) and torch.equal(first, again)
    other = sample(model, None, n_samples=3, steps=5, generator=torch.Generator().manual_seed(5))
    assert not torch.allclose(first, other)
    ddim = sample(
        model, torch.tensor([1]), method="ddim", steps=4, generator=torch.Generator().manual_seed(4)
    )
    assert ddim.shape == (1, 10, 135) and torch.isfinite(ddim).all()


def test_ddim_without_noise_is_fixed_by_its_start():
    model = tiny()
    start = torch.randn(2, 10, 135, generator=torch.Generator().manual_seed(1))
    runs = [
        sample(
            model,
            torch.tensor([0, 1]),
            steps=5,
            method="ddim",
            guidance=2.5,
            initial_noise=start,
            generator=torch.Generator().manual_seed(seed),
        )
        for seed in (0, 1)
    ]
    assert torch.equal(runs[0], runs[1])  # eta 0: the generator's later draws are unused
    drawn = sample(
        model,
        torch.tensor([0, 1]),
        steps=5,
        method="ddim",
        guidance=2.5,
        generator=torch.Generator().manual_seed(1),
    )
    assert torch.equal(drawn, runs[0])  # the start is the generator's first draw otherwise
    ancestral = sample(
        model, torch.tensor([0, 1]), steps=5, initial_noise=start, generator=torch.Generator().manual_seed(0)
    )
    assert not torch.allclose(ancestral, runs[0])


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"action": None}, TypeError, "n_samples"),
        ({"action": torch.tensor([0.0])}, TypeError, "action"),
        ({"action": torch.tensor([0]), "n_samples": 2}, ValueError, "n_samples"),
        ({"action": torch.tensor([0]), "method": "euler"}, ValueError, "method"),
        ({"action": torch.tensor([0]), "inpaint": "copy"}, ValueError, "inpaint"),
        ({"action": torch.tensor([0]), "steps": 0}, ValueError, "steps"),
        ({"action": torch.tensor([0]), "eta": -1.0}, ValueError, "eta"),
        ({"action": torch.tensor([0]), "edit": (torch.zeros(1, 10, 135), None)}, TypeError, "Edit"),
        (
            {
                "action": torch.tensor([0]),
                "edit": Edit(torch.zeros(1, 9, 135), torch.ones(9, 135, dtype=torch.bool)),
            },
            ValueError,
            "edit.motion",
        ),
        (
            {"action": torch.tensor([0]), "edit": Edit(torch.zeros(1, 10, 135), torch.ones(10, 135))},
            TypeError,
            "known",
        ),
        (
            {"action": torch.tensor([0]), "initial_noise": torch.zeros(2, 10, 135)},
            ValueError,
            "initial_noise",
        ),
        (
            {"action": torch.tensor([0]), "initial_noise": torch.zeros(1, 10, 135).long()},
            TypeError,
            "initial_noise",
        ),
    ],
)
def test_sample_rejects_bad_inputs(kwargs, error, match):
    with pytest.raises(error, match=match):
        sample(tiny(), **kwargs)
    with pytest.raises(TypeError, match="model"):
        sample(torch.nn.Linear(2, 2), torch.tensor([0]))
