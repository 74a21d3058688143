import math

import numpy as np
import pytest
import torch

from motionlab.data.representations import rotate_xy
from motionlab.data.synthetic import generate
from motionlab.evaluation import (
    EVAL_FEATURES,
    body_frame_features,
    body_frame_poses,
    hip_heading,
    joint_speed,
)
from motionlab.evaluation.benchmark import Benchmark, labels_of, real_reference, sample_metrics
from motionlab.evaluation.classifiers import ClassifierConfig, MotionClassifier
from motionlab.evaluation.evaluator import EvaluatorConfig, evaluator_run, load_evaluator
from motionlab.metrics import mean_ci
from motionlab.skeleton import average_skeleton


@pytest.fixture(scope="module")
def clips():
    return generate(seed=3, n_per_mode=4)


@pytest.fixture(autouse=True)
def build(monkeypatch, tmp_path):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))


def _turn(positions: torch.Tensor, angle: float, shift=(0.0, 0.0)) -> torch.Tensor:
    xy = rotate_xy(positions[..., :2], torch.tensor(angle)) + torch.tensor(shift)
    return torch.cat([xy, positions[..., 2:]], dim=-1)


def test_hip_heading_of_a_character_facing_x_is_zero(clips):
    pos = torch.as_tensor(clips.positions[:1, :1])
    yaw = hip_heading(pos)
    turned = hip_heading(_turn(pos, 0.7))
    assert torch.allclose(
        torch.remainder(turned - yaw - 0.7 + math.pi, 2 * math.pi) - math.pi, torch.zeros(1), atol=1e-5
    )


def test_features_ignore_where_and_which_way_the_clip_happens(clips):
    pos = torch.as_tensor(clips.positions[:3])
    feats = body_frame_features(pos)
    assert feats.shape == (3, clips.n_frames, EVAL_FEATURES)
    moved = body_frame_features(_turn(pos, 2.0, shift=(5.0, -3.0)))
    assert torch.allclose(feats, moved, atol=1e-4)


def test_features_reject_bad_input():
    with pytest.raises(ValueError, match="positions"):
        body_frame_features(torch.zeros(2, 10, 21, 3))
    bad = torch.zeros(1, 2, 22, 3)
    bad[..., 1, 1] = 0.1
    bad[0, 0, 5, 0] = float("nan")
    with pytest.raises(
        ValueError, match=r"body_frame_features: positions contains NaN .* \(first at index \(0, 0, 5, 0\)\)"
    ):
        body_frame_features(bad)
    with pytest.raises(TypeError, match="body_frame_features: positions must have a floating-point dtype"):
        body_frame_features(torch.zeros(1, 2, 22, 3, dtype=torch.long))


def test_body_frame_poses_of_a_rest_pose_are_the_rest_positions():
    rest = torch.tensor(average_skeleton().rest_positions(), dtype=torch.float32)
    placed = rest + torch.tensor([2.0, -1.0, 0.9])  # somewhere on the floor, facing +x
    poses = body_frame_poses(placed.expand(1, 3, 22, 3))
    torch.testing.assert_close(poses[0, 0], rest + torch.tensor([0.0, 0.0, 0.9]), atol=1e-5, rtol=0)


def test_joint_speed_ignores_travel_and_turning_and_matches_a_hand_computation(clips):
    rest = torch.tensor(average_skeleton().rest_positions(), dtype=torch.float32) + torch.tensor(
        [0.0, 0.0, 0.9]
    )
    gliding = rest + torch.linspace(0, 3, 10)[:, None, None] * torch.tensor(
        [1.0, 0.0, 0.0]
    )  # a frozen pose sliding along x
    turning = torch.stack([_turn(rest, angle) for angle in torch.linspace(0, 1.5, 10).tolist()])
    for frozen in (gliding, turning):
        torch.testing.assert_close(joint_speed(frozen[None]), torch.zeros(1, 10), atol=1e-4, rtol=0)
    positions = torch.as_tensor(clips.positions[:2, :6])
    poses = body_frame_poses(positions).numpy()
    by_hand = np.linalg.norm(np.diff(poses, axis=1), axis=-1).mean(-1) * 15.0
    speed = joint_speed(positions.numpy(), fps=15.0).numpy()  # NumPy in, torch out
    np.testing.assert_allclose(speed[:, 1:], by_hand, rtol=1e-5)
    np.testing.assert_allclose(speed[:, 0], speed[:, 1])
    with pytest.raises(ValueError, match="2 frames"):
        joint_speed(positions[:, :1])
    with pytest.raises(ValueError, match="fps"):
        joint_speed(positions, fps=0.0)


@pytest.mark.parametrize("kind", ["conv", "gru"])
def test_classifier_shapes_and_deterministic_features(kind):
    torch.manual_seed(0)
    model = MotionClassifier(
        ClassifierConfig(kind, 7, {"action": 3, "body": 2}, hidden=16, feature_dim=5)
    ).eval()
    x = torch.randn(4, 9, 7)
    logits = model(x)
    assert logits["action"].shape == (4, 3) and logits["body"].shape == (4, 2)
    assert torch.equal(model.features(x), model.features(x))
    assert model.features(x).shape == (4, model.feature_dim)
    acts = model.layer_activations(x)
    assert len(acts) == (4 if kind == "conv" else 2)
    with pytest.raises(
        ValueError, match=r"MotionClassifier: x must have shape \(\.\.\., 7\), got \(4, 9, 6\)"
    ):
        model(torch.randn(4, 9, 6))
    with pytest.raises(ValueError, match="MotionClassifier: x must be 3-dimensional"):
        model(torch.randn(9, 7))
    with pytest.raises(ValueError, match="MotionClassifier: x must hold at least one frame"):
        model(torch.randn(4, 0, 7))


def test_classifier_config_is_validated():
    with pytest.raises(ValueError, match="kind"):
        ClassifierConfig("rnn", 3, {"a": 2})
    with pytest.raises(ValueError, match=r"ClassifierConfig: classes\['a'\] must be at least 2, got 1"):
        ClassifierConfig("gru", 3, {"a": 1})
    with pytest.raises(ValueError, match="ClassifierConfig: classes needs at least one head"):
        ClassifierConfig("gru", 3, {})
    with pytest.raises(TypeError, match="ClassifierConfig: hidden must be an integer"):
        ClassifierConfig("gru", 3, {"a": 2}, hidden=16.0)


def test_evaluator_learns_actions_and_is_cached(clips):
    cfg = EvaluatorConfig(kind="conv", steps=60, batch_size=24, hidden=32)
    evaluator, result = load_evaluator(clips.positions, labels_of(clips), cfg, progress=False)
    assert not result.loaded_from_cache
    held_out = generate(seed=4, n_per_mode=2, split="test")
    assert evaluator.accuracy(held_out.positions, held_out.action) >= 0.8
    again, cached = load_evaluator(clips.positions, labels_of(clips), cfg, progress=False)
    assert cached.loaded_from_cache
    assert torch.equal(again.features(held_out.positions), evaluator.features(held_out.positions))
    probs = evaluator.probs(held_out.positions)
    assert torch.allclose(probs.sum(-1), torch.ones(len(probs), dtype=probs.dtype))
    row = sample_metrics(
        evaluator,
        held_out.positions,
        held_out.action,
        evaluator.features(clips.positions),
        np.random.default_rng(0),
    )
    assert set(row) == {"accuracy", "fid", "diversity", "multimodality", "is"}
    assert all(np.isfinite(v) for v in row.values())
    real = real_reference(evaluator, Benchmark(clips, held_out, held_out), n_repeats=3, seed=5)
    by_hand = [
        sample_metrics(
            evaluator,
            held_out.positions,
            held_out.action,
            evaluator.features(clips.positions),
            np.random.default_rng([5, r]),
        )
        for r in range(3)
    ]
    assert real == {key: mean_ci([row[key] for row in by_hand]) for key in row}
    with pytest.raises(KeyError, match="heads"):
        evaluator.logits(held_out.positions, "style")
    # one pass for both: bitwise the same numbers as the two separate calls, with more clips than one chunk
    many = np.concatenate([held_out.positions] * 30)
    for head in ("action", "body"):
        features, head_probs = evaluator.features_and_probs(many, head)
        assert torch.equal(features, evaluator.features(many)) and torch.equal(
            head_probs, evaluator.probs(many, head)
        )
    with pytest.raises(KeyError, match="heads"):
        evaluator.features_and_probs(held_out.positions, "style")


def test_evaluator_validates_on_held_out_clips_without_changing_the_weights(clips):
    """Given held-out clips, the run validates every ``val_every`` steps on random windows of every clip
    once, in order, standardised by the training clips' statistics, the same windows in every pass; the
    trained weights are those of the run without validation, bit for bit."""
    cfg = EvaluatorConfig(kind="gru", steps=6, batch_size=8, hidden=8, feature_dim=4)
    val = generate(seed=4, n_per_mode=1, split="val")  # 12 clips: batches of 8 and 4
    run = evaluator_run(
        clips.positions, labels_of(clips), cfg, val_positions=val.positions, val_labels=labels_of(val)
    )
    assert run.train_config.val_every == 4  # 6 steps: at step 4 and the end
    validated, result = load_evaluator(
        clips.positions,
        labels_of(clips),
        cfg,
        progress=False,
        val_positions=val.positions,
        val_labels=labels_of(val),
    )
    assert result.history.val_step == [4, 6]
    assert set(result.history.val_terms) == {"loss", "ce_action", "ce_mode", "ce_body"}

    def windows():
        return list(run.val_batches(validated)(0, torch.Generator().manual_seed(1), cfg.batch_size))

    first, again = windows(), windows()
    assert [len(labels["action"]) for _, labels in first] == [8, 4]
    for (window, labels), (same_window, same_labels) in zip(first, again):
        assert torch.equal(window, same_window) and labels.keys() == same_labels.keys()
    for head, value in labels_of(val).items():
        assert torch.equal(torch.cat([labels[head] for _, labels in first]), torch.as_tensor(value))
    inputs, window = validated.inputs(val.positions[:1])[0], first[0][0][0]  # clip 0 and its window
    assert any(torch.equal(inputs[s : s + len(window)], window) for s in range(len(inputs) - len(window) + 1))

    plain, plain_result = load_evaluator(clips.positions, labels_of(clips), cfg, progress=False)
    assert plain_result.history.val_step == [] and not plain_result.loaded_from_cache
    for key, value in validated.state_dict().items():
        assert torch.equal(value, plain.state_dict()[key]), key

    with pytest.raises(ValueError, match="give both val_positions and val_labels"):
        evaluator_run(clips.positions, labels_of(clips), cfg, val_positions=val.positions)
    with pytest.raises(ValueError, match=r"val_labels has heads \['action'\]"):
        evaluator_run(
            clips.positions,
            labels_of(clips),
            cfg,
            val_positions=val.positions,
            val_labels={"action": val.action},
        )
    with pytest.raises(ValueError, match=r"val_labels\['action'\] must lie in \[0, 6\)"):
        evaluator_run(
            clips.positions,
            {"action": clips.action},
            cfg,
            val_positions=val.positions,
            val_labels={"action": val.action + 6},
        )


def test_evaluator_rejects_mismatched_labels(clips):
    with pytest.raises(ValueError, match="labels"):
        load_evaluator(
            clips.positions, {"action": clips.action[:-1]}, EvaluatorConfig(steps=1), progress=False
        )
    with pytest.raises(ValueError, match="unknown label heads"):
        load_evaluator(clips.positions, {"style": clips.action}, EvaluatorConfig(steps=1), progress=False)
