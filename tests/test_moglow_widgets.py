"""The steering widget's callbacks and the control test (tiny models, quick profile)."""

import matplotlib

matplotlib.use("Agg")

import math

import matplotlib.pyplot as plt
import pytest
import torch

from motionlab.data.synthetic import generate
from motionlab.models.moglow import (
    MoGlow,
    MoGlowConfig,
    MoGlowFeatures,
    clip_features,
    evaluate,
    experiment,
    fit_scalers,
    select_actions,
    splice_controls,
)
from motionlab.widgets.moglow import STAND_SPEED, Character, show_steering, steer, steering_control


@pytest.fixture(scope="module")
def library():
    clips = generate(seed=5, n_per_mode=1, seconds=2.0, split="test")
    return clips, clip_features(clips, experiment.ExperimentConfig().data, augment=False)


@pytest.fixture(scope="module")
def model(library):
    torch.manual_seed(0)
    features = library[1]
    model = MoGlow(MoGlowConfig(steps=1, hidden=4, cond_features=4, dropout=0.5)).eval()
    scalers = fit_scalers(features)
    return model, scalers


def test_splice_controls_crossfades():
    a, b = torch.zeros(40, 3), torch.ones(30, 3)
    out = splice_controls([a, b], blend=10)
    assert out.shape == (60, 3)
    assert float(out[:30].abs().max()) == 0.0 and float((out[40:] - 1).abs().max()) == 0.0
    fade = out[30:40, 0]
    assert torch.all(fade[1:] > fade[:-1]) and 0 < float(fade[0]) < float(fade[-1]) < 1
    with pytest.raises(ValueError):
        splice_controls([torch.zeros(10, 3)], blend=10)


def test_steering_control_retargets_a_recorded_clip(library):
    _, features = library
    control, index = steering_control(features, speed=1.8, turn=30.0, frames=150)
    assert control.shape == (150, 3)
    assert math.isclose(float(control[:, 0].mean()) * 30, 1.8, rel_tol=0.05)
    recorded_turn = float(features.control[index, 1:, 2].mean())
    assert math.isclose(float(control[:, 2].mean()), recorded_turn + math.radians(30) / 30, abs_tol=2e-3)
    standing, stand_index = steering_control(features, speed=0.0, turn=0.0, frames=60)
    assert abs(float(standing[:, 0].mean()) * 30) < STAND_SPEED
    assert stand_index != index
    with pytest.raises(ValueError):
        steering_control(features, speed=-1.0, turn=0.0, frames=10)


def test_steering_control_reads_speeds_and_turns_at_the_data_frame_rate(library):
    _, features = library
    at_30, index = steering_control(features, speed=1.8, turn=30.0, frames=150)
    at_12, index_12 = steering_control(features, speed=1.8, turn=30.0, frames=150, fps=12.0)
    # the same recorded clips read at 12 fps move 12/30 as fast: another clip matches 1.8 m/s
    assert math.isclose(float(at_12[:, 0].mean()) * 12, 1.8, rel_tol=0.05)
    recorded_turn = float(features.control[index_12, 1:, 2].mean())
    assert math.isclose(float(at_12[:, 2].mean()), recorded_turn + math.radians(30) / 12, abs_tol=2e-3)
    with pytest.raises(ValueError, match="fps"):
        steering_control(features, speed=1.0, turn=0.0, frames=10, fps=0.0)


def test_steer_is_seeded_and_follows_the_speed(library, model):
    _, features = library
    net, scalers = model
    a = steer(net, scalers, features, speed=1.5, turn=0.0, temperature=0.5, seconds=2.0, sample_seed=3)
    b = steer(net, scalers, features, speed=1.5, turn=0.0, temperature=0.5, seconds=2.0, sample_seed=3)
    assert torch.equal(a.positions, b.positions)
    assert a.positions.shape == (1, net.cfg.history + 60, 22, 3)
    root = a.positions[0, net.cfg.history :, 0, :2]
    travelled = float((root[1:] - root[:-1]).norm(dim=-1).sum())
    assert math.isclose(travelled / (59 / 30), 1.5, rel_tol=0.1)


def test_show_steering_draws(library, model):
    _, features = library
    net, scalers = model
    figure = show_steering(net, scalers, features, speed=1.0, turn=-20.0, temperature=0.3)
    assert len(figure.axes) == 6
    plt.close("all")


def test_show_steering_draws_another_character(library, model):
    _, features = library
    net, scalers = model
    other = Character(fps=12.0, toes=(4, 8), feet=(3, 4, 7, 8))  # another frame rate, toes and feet
    figure = show_steering(net, scalers, features, speed=1.0, turn=10.0, temperature=0.3, character=other)
    assert len(figure.axes) == 6
    path = plt.figure(1).axes[0]  # the path from above: pelvis and the two toes' trails
    assert [line.get_label() for line in path.lines][-2:] == ["left toe", "right toe"]
    plt.close("all")


def test_control_test_pieces(library):
    clips, features = library
    chosen = select_actions(clips, experiment.ExperimentConfig().data.actions)
    test = evaluate.control_test(features, chosen.action, chosen.action_names, 2, history=3, blend=3, fps=10)
    assert test.control.shape == (2, 4 * 30 - 3 * 3, 3)
    assert test.seed.pose.shape == (2, 3, 64)
    walk_speed = float(test.control[:, :20, 0].mean()) * 30
    stand_speed = float(test.control[:, 40:50, 0].abs().mean()) * 30
    assert walk_speed > 0.5 and stand_speed < 0.1
    with pytest.raises(ValueError):
        evaluate.control_test(
            MoGlowFeatures(features.pose[:, :5], features.control[:, :5]),
            chosen.action,
            chosen.action_names,
            1,
            history=3,
        )
