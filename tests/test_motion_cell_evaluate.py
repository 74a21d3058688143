"""The evaluation protocol: sample sets, distances to the mean pose, collapse ratios, Table 2 rows."""

import numpy as np
import pytest
import torch
from test_motion_cell_common import clips, motion_cell, perturb

from motionlab.data.datasets import Standardizer
from motionlab.evaluation import EVAL_FEATURES, Evaluator, body_frame_features
from motionlab.evaluation.classifiers import ClassifierConfig, MotionClassifier
from motionlab.models.motion_cell import evaluate as E
from motionlab.models.motion_cell.experiment import table_row
from motionlab.skeleton import average_skeleton


def test_attribute_grid_covers_every_combination_equally():
    action, body = E.attribute_grid(3, n_actions=6, n_bodies=2)
    assert action.shape == body.shape == (36,)
    pairs = torch.stack([action, body], dim=1)
    unique, counts = torch.unique(pairs, dim=0, return_counts=True)
    assert unique.shape == (12, 2) and torch.all(counts == 3)
    with pytest.raises(ValueError, match="n_per_combination"):
        E.attribute_grid(0)


def test_protocol_samples_have_140_frames_and_discard_20():
    samples = E.protocol_samples(motion_cell(), 1, torch.Generator().manual_seed(0))
    assert samples.positions.shape == (12, 140, 22, 3)
    assert samples.evaluated.shape == (12, 120, 22, 3)
    torch.testing.assert_close(samples.evaluated, samples.positions[:, 20:])


def test_distance_to_pose_by_hand():
    positions = torch.as_tensor(clips().positions[:2, :5])
    poses = E.body_frame_poses(positions)
    pose = poses.flatten(0, 1).mean(0)
    by_hand = np.linalg.norm(poses.numpy() - pose.numpy(), axis=-1).mean(-1)
    np.testing.assert_allclose(E.distance_to_pose(positions, pose).numpy(), by_hand, rtol=1e-5)
    assert E.mean_pose(positions).shape == (22, 3)
    with pytest.raises(ValueError, match="pose"):
        E.distance_to_pose(positions, pose[:21])


def test_collapse_ratio_and_action_mask():
    curve = torch.cat([torch.full((60,), 5.0), torch.full((80,), 2.0)])
    assert E.collapse_ratio(curve, real_level=4.0) == pytest.approx(0.5)
    with pytest.raises(ValueError, match="frames"):
        E.collapse_ratio(curve[:100], 4.0)
    with pytest.raises(ValueError, match="real_level"):
        E.collapse_ratio(curve, 0.0)
    names = ["walk", "jog", "jump", "lift", "wave", "kick"]
    mask = E.action_mask(torch.tensor([0, 2, 3, 4, 5, 1]), names)
    assert mask.tolist() == [False, True, True, False, True, False]
    with pytest.raises(ValueError, match="unknown actions"):
        E.action_mask(torch.tensor([0]), names, ("swim",))


def test_collapse_curve_averages_the_non_periodic_samples():
    samples = E.protocol_samples(motion_cell(), 1, torch.Generator().manual_seed(0))
    names = list(clips().action_names)
    pose = E.mean_pose(clips().positions)
    curve = E.collapse_curve(samples, pose, names)
    mask = E.action_mask(samples.action, names)
    torch.testing.assert_close(curve, E.distance_to_pose(samples.positions[mask], pose).mean(0))
    level = E.real_collapse_level(clips().positions, clips().action, pose, names)
    real_mask = E.action_mask(torch.as_tensor(clips().action), names)
    assert level == pytest.approx(
        float(E.distance_to_pose(clips().positions[real_mask.numpy()], pose).mean()), rel=1e-6
    )


def _untrained_evaluator() -> Evaluator:
    torch.manual_seed(0)
    data = clips()
    standardizer = Standardizer(EVAL_FEATURES).fit(body_frame_features(torch.as_tensor(data.positions)))
    classifier = MotionClassifier(
        ClassifierConfig("gru", EVAL_FEATURES, {"action": 6, "mode": 12, "body": 2}, hidden=8)
    )
    return Evaluator(classifier, standardizer).eval()


def test_evaluate_model_gives_a_reproducible_table_row():
    evaluator = _untrained_evaluator()
    reference = evaluator.features(clips().positions)
    model = motion_cell()
    perturb(model.word_decoder.net[-1].weight, 0.05)
    first = E.evaluate_model(model, evaluator, reference, n_per_combination=1, n_repeats=2, seed=3)
    second = E.evaluate_model(model, evaluator, reference, n_per_combination=1, n_repeats=2, seed=3)
    assert set(first.row) == {"accuracy", "fid", "diversity", "multimodality", "is", "is_action"}
    assert first.row == second.row
    assert set(first.values) == set(first.row) and all(len(v) == 2 for v in first.values.values())
    assert first.row["fid"][0] == pytest.approx(np.mean(first.values["fid"]))
    assert torch.equal(first.samples.positions, second.samples.positions)
    assert all(np.isfinite(mean) and half >= 0 for mean, half in first.row.values())
    with pytest.raises(ValueError, match="n_repeats"):
        E.evaluate_model(model, evaluator, reference, 1, 1)
    row = table_row("mcell", model, evaluator, reference, n_per_combination=1, n_repeats=2)
    assert row.row == E.evaluate_model(model, evaluator, reference, 1, 2, seed=0).row
    assert table_row("output_matrix", model, evaluator, reference, 1, 2) is None


def test_tsne_embedding_shape_and_seed():
    x = np.random.default_rng(0).normal(size=(30, 5))
    a = E.tsne_embedding(x, seed=0)
    assert a.shape == (30, 2)
    np.testing.assert_allclose(a, E.tsne_embedding(x, seed=0))
    with pytest.raises(ValueError, match="features"):
        E.tsne_embedding(x[:3])


def test_speed_curve_averages_the_non_periodic_samples_and_real_level_matches():
    data = clips()
    names = list(data.action_names)
    samples = E.SampleSet(
        torch.as_tensor(data.positions), torch.as_tensor(data.action), torch.as_tensor(data.body)
    )
    mask = E.action_mask(samples.action, names)
    expected = E.joint_speed(samples.positions[mask]).mean(0)
    torch.testing.assert_close(E.speed_curve(samples, names), expected)
    assert E.real_speed_level(data.positions, data.action, names) == pytest.approx(
        float(expected.mean()), rel=1e-5
    )
    walks = samples.action == names.index("walk")
    with pytest.raises(ValueError, match="non-periodic"):
        E.speed_curve(
            E.SampleSet(samples.positions[walks], samples.action[walks], samples.body[walks]), names
        )


def test_joint_attribute_probs_is_the_product_of_the_two_classifiers():
    action = torch.tensor([[0.5, 0.5, 0.0], [0.0, 0.0, 1.0]], dtype=torch.float64)
    body = torch.tensor([[0.25, 0.75], [1.0, 0.0]], dtype=torch.float64)
    joint = E.joint_attribute_probs(action, body)
    expected = torch.tensor(
        [[0.125, 0.375, 0.125, 0.375, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 1.0, 0.0]], dtype=torch.float64
    )
    torch.testing.assert_close(joint, expected)  # index action * 2 + body
    with pytest.raises(ValueError, match="joint_attribute_probs"):
        E.joint_attribute_probs(action, body[:1])


def test_attribute_is_of_confident_clips_reaches_the_number_of_combinations():
    """The paper's IS over attributes: confident, balanced over all 6 x 2 combinations -> 12; the action-only
    IS of the same clips is 6."""
    from motionlab.metrics import inception_score

    combination = torch.arange(12)
    action = torch.nn.functional.one_hot(combination // 2, 6).double()
    body = torch.nn.functional.one_hot(combination % 2, 2).double()
    assert inception_score(E.joint_attribute_probs(action, body)) == pytest.approx(12.0)
    assert inception_score(action) == pytest.approx(6.0)


def test_attribute_metrics_one_pass_matches_the_evaluator():
    evaluator = _untrained_evaluator()
    data = clips()
    reference = evaluator.features(data.positions)
    row = E.attribute_metrics(evaluator, data.positions, data.action, reference, np.random.default_rng(0))
    from motionlab.metrics import inception_score

    joint = E.joint_attribute_probs(
        evaluator.probs(data.positions, "action"), evaluator.probs(data.positions, "body")
    )
    assert row["is"] == pytest.approx(inception_score(joint), rel=1e-9)
    assert row["is_action"] == pytest.approx(
        inception_score(evaluator.probs(data.positions, "action")), rel=1e-9
    )


def test_difference_interval_is_welchs():
    from scipy import stats

    a, b = [1.0, 1.2, 0.9, 1.1, 1.05], [1.5, 1.7, 1.4, 1.9]
    diff, lower, upper = E.difference_interval(a, b)
    assert diff == pytest.approx(np.mean(a) - np.mean(b))
    result = stats.ttest_ind(a, b, equal_var=False)
    ci = result.confidence_interval(0.95)
    assert (lower, upper) == (pytest.approx(ci.low), pytest.approx(ci.high))
    assert upper < 0
    assert E.difference_interval([1.0, 1.0], [1.0, 1.0]) == (0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="difference_interval"):
        E.difference_interval([1.0], [1.0, 2.0])


def _standing(n_clips: int, n_frames: int) -> torch.Tensor:
    """Clips ``(n_clips, n_frames, 22, 3)`` of the average skeleton standing still."""
    rest = torch.tensor(average_skeleton().rest_positions(), dtype=torch.float32) + torch.tensor([0, 0, 0.9])
    return rest.expand(n_clips, n_frames, 22, 3).clone()


def test_speed_by_phase_splits_boundary_steps_from_steps_inside_words():
    stairs = _standing(2, 40)
    stairs[..., 1:, 2] += (torch.arange(40) // 3).float()[None, :, None] * 0.03  # all but the root step up
    phases = E.speed_by_phase(stairs, 3, first=20)
    assert phases[1] == phases[2] == 0  # inside a word: still
    assert phases[0] > 0.5  # across a boundary: 3 cm in 1/30 s for 21 of the 22 joints
    assert phases[0].item() == pytest.approx(0.03 * 30 * 21 / 22, rel=1e-4)


def test_event_strength_finds_the_busiest_half_second_wherever_it_is():
    names = ["walk", "jump", "lift", "kick"]
    still = _standing(3, 60)
    early, late = still.clone(), still.clone()
    bump = 0.2 * torch.sin(torch.linspace(0, torch.pi, 15))[:, None]
    early[:, 5:20, 1:, 2] += bump  # the same movement, at two times
    late[:, 40:55, 1:, 2] += bump
    jumps = torch.ones(3, dtype=torch.long)
    a, b = E.event_strength(early, jumps, names), E.event_strength(late, jumps, names)
    assert a == pytest.approx(b, rel=1e-5) and a > 0.1
    assert E.event_strength(still, jumps, names) == 0.0
    with pytest.raises(ValueError, match="non-periodic"):
        E.event_strength(early, torch.zeros(3, dtype=torch.long), names)
    with pytest.raises(ValueError, match="shorter than the window"):
        E.event_strength(early[:, :10], jumps, names)
