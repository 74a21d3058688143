"""Chapter 11's widgets: the seeded sampler, slerp of the start noise, the inpainting editor, their figures,
and the widgets driven headless through their controls (a tiny untrained MDM on a few synthetic clips)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import ipywidgets as widgets  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import torch  # noqa: E402

from motionlab.data.synthetic import generate  # noqa: E402
from motionlab.models.diffusion.data import prepare  # noqa: E402
from motionlab.models.diffusion.model import MDM, MDMConfig  # noqa: E402
from motionlab.skeleton import JOINT  # noqa: E402
from motionlab.widgets import controls as controls_module  # noqa: E402
from motionlab.widgets import diffusion as dw  # noqa: E402

NAMES = ["walk", "jog", "jump", "lift", "wave", "kick"]
FRAMES = 15  # 1 s of the synthetic clips at 15 fps


@pytest.fixture(scope="module")
def data():
    return prepare(generate(0, 1, seconds=1.0))  # 12 clips, one per style mode, 15 frames each


@pytest.fixture(scope="module")
def model(data):
    torch.manual_seed(0)
    cfg = MDMConfig(
        n_frames=FRAMES, latent_dim=16, ff_size=32, layers=1, heads=2, dropout=0.0, diffusion_steps=40
    )
    return MDM(cfg).fit_standardizer(data.features)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _image(box: widgets.VBox) -> bytes:
    """The PNG the widget's output shows (it shows exactly one)."""
    output = box.children[-1]
    assert isinstance(output, widgets.Output) and len(output.outputs) == 1
    return output.outputs[0]["data"]["image/png"]


def _controls(box: widgets.VBox) -> dict[str, widgets.Widget]:
    return {c.description: c for row in box.children[:-1] for c in row.children}


def test_step_choices_stop_at_the_model_diffusion_steps(model):
    assert dw.step_choices(model) == [10, 25]
    short = MDM(MDMConfig(n_frames=FRAMES, latent_dim=16, ff_size=32, layers=1, heads=2, diffusion_steps=5))
    assert dw.step_choices(short) == [5]


def test_a_seed_fixes_the_clip_and_is_the_start_noise(model):
    clip = dw.sample_motion(model, 1, 3, 10, 2.5)
    assert clip.shape == (FRAMES, model.cfg.n_features)
    assert torch.equal(clip, dw.sample_motion(model, 1, 3, 10, 2.5))
    started = dw.sample_motion(model, 1, 0, 10, 2.5, initial_noise=dw.start_noise(model, 3))
    assert torch.equal(clip, started)  # DDIM with eta 0: the start is the only randomness
    assert not torch.allclose(clip, dw.sample_motion(model, 1, 4, 10, 2.5))
    assert not torch.allclose(clip, dw.sample_motion(model, 2, 3, 10, 2.5))  # the action counts
    assert not torch.allclose(clip, dw.sample_motion(model, 1, 3, 25, 2.5))  # and the step count


def test_slerp_runs_on_the_great_circle():
    gen = torch.Generator().manual_seed(0)
    a, b = torch.randn(60, 135, generator=gen), torch.randn(60, 135, generator=gen)
    assert torch.equal(dw.slerp(a, b, 0.0), a) and torch.allclose(dw.slerp(a, b, 1.0), b, atol=1e-6)
    norm = float(a.norm())
    same_norm = b * norm / b.norm()
    for weight in (0.25, 0.5, 0.9):
        assert float(dw.slerp(a, same_norm, weight).norm()) == pytest.approx(norm, rel=1e-5)
    # two draws are nearly orthogonal: halfway along the straight line the norm drops by about sqrt(2)
    assert float(((a + b) / 2).norm()) / norm == pytest.approx(2**-0.5, abs=0.03)
    assert float(dw.slerp(a, b, 0.5).norm()) / norm == pytest.approx(1.0, abs=0.03)
    # equal angles for equal steps of the weight
    quarter = dw.slerp(a, same_norm, 0.25)
    cosine = torch.nn.functional.cosine_similarity
    first, second = (
        cosine(a.flatten(), quarter.flatten(), 0),
        cosine(quarter.flatten(), dw.slerp(a, same_norm, 0.5).flatten(), 0),
    )
    assert float(first) == pytest.approx(float(second), abs=1e-5)
    assert torch.allclose(dw.slerp(a, a, 0.3), a, atol=1e-6)  # no angle: no NaN


@pytest.mark.parametrize(
    ("args", "error", "match"),
    [
        ((np.zeros(3), torch.ones(3), 0.5), TypeError, "a must be a torch.Tensor"),
        ((torch.ones(3), torch.ones(4), 0.5), ValueError, "one shape"),
        ((torch.ones(3), torch.ones(3), 1.5), ValueError, "weight"),
        ((torch.zeros(3), torch.ones(3), 0.5), ValueError, "non-zero"),
        ((torch.ones(3), -torch.ones(3), 0.5), ValueError, "opposite"),
    ],
)
def test_slerp_rejects_bad_arguments(args, error, match):
    with pytest.raises(error, match=match):
        dw.slerp(*args)


def test_interpolation_goes_from_one_seed_clip_to_the_other_smoothly(model):
    ends = [dw.sample_motion(model, 0, seed, 10, 2.5) for seed in (0, 1)]
    path = [dw.interpolated_motion(model, 0, 0, 1, weight, 10, 2.5) for weight in (0.0, 0.45, 0.5, 1.0)]
    assert torch.equal(path[0], ends[0]) and torch.allclose(path[3], ends[1], atol=1e-5)
    assert torch.equal(path[2], dw.interpolated_motion(model, 0, 0, 1, 0.5, 10, 2.5))
    step = float((path[2] - path[1]).abs().mean())
    assert 0 < step < 0.25 * float((ends[1] - ends[0]).abs().mean())


def test_editor_keyframes_show_the_seams():
    assert dw.editor_keyframes(60, "ends", 5).tolist() == [0, 4, 21, 38, 55, 59]
    assert dw.editor_keyframes(60, "ends", 1).tolist() == [0, 20, 39, 59]
    assert dw.editor_keyframes(60, "ends", 30).tolist() == [0, 29, 30, 59]
    assert dw.editor_keyframes(60, "legs", 5).tolist() == [0, 12, 24, 35, 47, 59]


def test_editing_masks_and_the_joints_they_fix():
    ends = dw.editing_mask(FRAMES, 22, "ends", 3)
    assert ends.shape == (FRAMES, 135)
    given_frames = ends.all(dim=1)
    assert given_frames.tolist() == [True] * 3 + [False] * (FRAMES - 6) + [True] * 3
    assert not ends[3:-3].any()
    assert torch.equal(dw.fixed_joints(ends), given_frames[:, None].expand(FRAMES, 22))
    legs = dw.editing_mask(FRAMES, 22, "legs", 3)
    fixed = dw.fixed_joints(legs)
    assert torch.equal(fixed, fixed[:1].expand_as(fixed))  # the same joints in every frame
    names = {"pelvis", "left_hip", "right_hip", "spine1"} | {
        f"{side}_{part}" for side in ("left", "right") for part in ("knee", "ankle", "foot")
    }
    assert {name for name, j in JOINT.items() if fixed[0, j]} == names  # spine1 hangs off the pelvis only
    with pytest.raises(ValueError, match="keep"):
        dw.editing_mask(FRAMES, 22, "arms", 3)
    with pytest.raises(ValueError, match="kept"):
        dw.editing_mask(FRAMES, 22, "ends", FRAMES // 2 + 1)
    with pytest.raises(TypeError, match="known"):
        dw.fixed_joints(ends.float())


@pytest.mark.parametrize("keep", ["ends", "legs"])
def test_the_completion_keeps_the_given_part(model, data, keep):
    reference, known, completion = dw.complete_clip(model, data, 4, keep, 3, 2, 0, 10, 2.5)
    assert torch.equal(reference, data.features[4])
    assert torch.allclose(completion[known], reference[known], atol=1e-4)
    assert float((completion[~known] - reference[~known]).abs().max()) > 0.1  # the rest is sampled
    # what the figure draws: the joints the given channels fix stand where the reference's do
    fixed = dw.fixed_joints(known).numpy()
    positions, expected = dw.clip_positions(completion), dw.clip_positions(reference)
    np.testing.assert_allclose(positions[fixed], expected[fixed], atol=1e-4)
    assert np.abs(positions[~fixed] - expected[~fixed]).max() > 0.01
    again = dw.complete_clip(model, data, 4, keep, 3, 2, 0, 10, 2.5)
    assert torch.equal(again.completion, completion)


def test_figures_draw_keyframes_and_say_what_they_show(model, data):
    strip = dw.sample_figure(model, 1, 2, 10, action_names=NAMES)
    assert (
        len(strip.axes) == 6
        and "jog, seed 2: 10 DDIM steps, guidance 2.5, sampled in" in strip._suptitle.get_text()
    )
    morph = dw.interpolation_figure(model, 1, 2, 3, 0.5, 10)
    assert len(morph.axes) == 6 and "weight = 0.50" in morph._suptitle.get_text()
    editor = dw.inbetween_figure(model, data, 0, "ends", 2, 0, 0, 10, action_names=NAMES)
    assert len(editor.axes) == 12
    assert [ax.get_title().split(",")[0] for ax in editor.axes] == ["reference"] * 6 + ["completion"] * 6
    green = [ax for ax in editor.axes if any(line.get_color() == dw.GIVEN_COLOR for line in ax.lines)]
    titles = [ax.get_title().split(", ")[1] for ax in editor.axes[:6]]
    assert titles == [f"t = {t / 15:.2f} s" for t in (0, 1, 5, 9, 13, 14)]  # the ends, the seams, the gap
    given = ["t = 0.00 s", "t = 0.07 s", "t = 0.87 s", "t = 0.93 s"]
    assert [ax.get_title().split(", ")[1] for ax in green] == given * 2


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda m, d: dw.sample_motion("mdm", 0, 0, 10, 2.5), TypeError, "model must be an MDM"),
        (lambda m, d: dw.sample_motion(m, 6, 0, 10, 2.5), ValueError, "action"),
        (lambda m, d: dw.sample_motion(m, 0, -1, 10, 2.5), ValueError, "seed"),
        (lambda m, d: dw.sample_motion(m, 0, 0, 50, 2.5), ValueError, "steps"),
        (lambda m, d: dw.sample_motion(m, 0, 0, 10, -1.0), ValueError, "guidance"),
        (lambda m, d: dw.interpolated_motion(m, 0, 0, 1.5, 0.5, 10, 2.5), TypeError, "seed_b"),
        (lambda m, d: dw.complete_clip(m, d.features, 0, "ends", 2, 0, 0, 10, 2.5), TypeError, "MDMData"),
        (lambda m, d: dw.complete_clip(m, d, 12, "ends", 2, 0, 0, 10, 2.5), ValueError, "clip"),
        (lambda m, d: dw.sample_figure(m, 0, 0, 10, fps=0.0), ValueError, "fps"),
        (
            lambda m, d: dw.inbetween_widget(m, prepare(generate(0, 1, seconds=2.0)), NAMES),
            ValueError,
            "frames",
        ),
    ],
)
def test_bad_arguments_are_named(model, data, call, error, match):
    with pytest.raises(error, match=match):
        call(model, data)


def test_sample_widget_redraws_on_every_control(model):
    box = dw.sample_widget(model, NAMES)
    controls = _controls(box)
    assert list(controls) == ["action", "seed", "DDIM steps", "guidance"]
    assert list(controls["DDIM steps"].options) == [10, 25]
    shown = [_image(box)]
    for name, value in (("seed", 5), ("action", 3), ("DDIM steps", 25), ("guidance", 1.0)):
        controls[name].value = value
        shown.append(_image(box))
    assert len(set(shown)) == len(shown)


def test_interpolation_widget_morphs_and_comes_back(model):
    box = dw.interpolation_widget(model, NAMES)
    controls = _controls(box)
    assert list(controls) == ["action", "seed A", "seed B", "weight", "DDIM steps"]
    start = _image(box)
    controls["weight"].value = 0.5
    middle = _image(box)
    controls["weight"].value = 0.0
    assert middle != start and _image(box) == start  # deterministic: the same weight draws the same figure
    controls["seed A"].value = 4
    assert _image(box) != start


def test_inbetween_widget_follows_the_clip_and_redraws_once(model, data, monkeypatch):
    box = dw.inbetween_widget(model, data, NAMES)
    controls = _controls(box)
    assert list(controls) == ["clip", "keep", "kept", "action", "seed", "DDIM steps"]
    assert controls["action"].value == int(data.action[0])
    first = _image(box)
    controls["kept"].value = 2
    assert _image(box) != first
    draws = []
    real = controls_module.show_figure
    monkeypatch.setattr(
        controls_module, "show_figure", lambda output, fig: draws.append(fig) or real(output, fig)
    )
    other = next(i for i in range(len(data)) if int(data.action[i]) != int(data.action[0]))
    controls["clip"].value = other
    assert controls["action"].value == int(data.action[other]) and len(draws) == 1
    controls["keep"].value = "legs"
    assert len(draws) == 2
