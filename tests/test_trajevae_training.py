"""TrajeVAE's data pipeline, training through the cache, the widget callback and the speed benchmark's
pieces."""

import dataclasses
import math

import numpy as np
import pytest
import torch

from motionlab.data.synthetic import generate
from motionlab.models.trajevae.baselines import GRUCompletion
from motionlab.models.trajevae.data import (
    CompletionBatches,
    CompletionData,
    completion_task,
    completion_windows,
    decimate,
)
from motionlab.models.trajevae.evaluate import (
    FIGURE6_KS,
    PAPER_KS,
    multimodal_futures,
    sweep_given_joints,
)
from motionlab.models.trajevae.experiment import (
    CACHE_NAMES,
    RUNGS,
    SCHEDULE_CHECK_KS,
    START_ORDER,
    ExperimentConfig,
    completion_run,
    runs,
    schedule_check,
    train_all,
    validation_batches,
)
from motionlab.models.trajevae.masks import first_joints
from motionlab.models.trajevae.model import TrajeVAE
from motionlab.skeleton import JOINT
from motionlab.train import TrainConfig
from motionlab.widgets.trajevae import bend_trajectory, complete_window, left_direction


@pytest.fixture(scope="module")
def clips():
    data = generate(seed=5, n_per_mode=1)
    return decimate(data.positions[:6]), decimate(data.rotations[:6])


@pytest.fixture(autouse=True)
def build(monkeypatch, tmp_path):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))


def test_windows_start_above_the_origin(clips):
    positions, _ = clips
    windows = completion_windows(positions)
    assert windows.shape == (6, 60, 66)
    torch.testing.assert_close(windows[:, 0, :2], torch.zeros(6, 2))
    torch.testing.assert_close(windows[..., 2::3], positions[..., 2])  # heights unchanged
    with pytest.raises(ValueError, match="NaN"):
        completion_windows(torch.full((1, 4, 22, 3), float("nan")))


def test_batches_are_seeded_and_yaw_augmentation_keeps_shape(clips):
    positions, rotations = clips
    batches = CompletionBatches(positions, rotations, augment=True)
    first = list(batches(0, torch.Generator().manual_seed(3), 4))
    again = list(batches(0, torch.Generator().manual_seed(3), 4))
    assert len(first) == 1 and first[0][0].shape == (4, 60, 66) and first[0][1].shape == (4, 22)
    assert torch.equal(first[0][0], again[0][0]) and torch.equal(first[0][1], again[0][1])
    plain = list(
        CompletionBatches(positions, rotations, augment=False)(0, torch.Generator().manual_seed(3), 4)
    )
    turned, straight = first[0][0].unflatten(-1, (-1, 3)), plain[0][0].unflatten(-1, (-1, 3))
    # the same clips (same order), turned about the first pelvis: heights and distances to it are kept
    torch.testing.assert_close(turned[..., 2], straight[..., 2])
    torch.testing.assert_close(
        turned[..., :2].norm(dim=-1), straight[..., :2].norm(dim=-1), atol=1e-5, rtol=1e-5
    )
    assert not torch.allclose(turned, straight)
    with pytest.raises(ValueError, match="batch_size"):
        next(batches(0, torch.Generator(), 7))


def test_training_is_cached_and_reproducible(clips):
    positions, rotations = clips
    cfg = ExperimentConfig.quick().trajevae
    train_cfg = TrainConfig(steps=3, batch_size=3, lr=1e-3, checkpoint_every=None)
    run = completion_run("trajevae_test", cfg, train_cfg, positions, rotations)
    assert not run.is_cached()
    model, result = run.train(progress=False)
    assert not result.loaded_from_cache and set(result.history.terms) >= {"recon", "kl"}
    assert run.is_cached()
    again, cached = run.train(progress=False)
    assert cached.loaded_from_cache
    for a, b in zip(model.state_dict().values(), again.state_dict().values()):
        assert torch.equal(a, b)
    start, trajectories = completion_task(completion_windows(positions[:2]), first_joints(2))
    g = torch.Generator
    assert torch.equal(
        model.sample(start, trajectories, 3, generator=g().manual_seed(1)),
        again.sample(start, trajectories, 3, generator=g().manual_seed(1)),
    )
    with pytest.raises(TypeError, match="completion_run: model must be"):
        completion_run("trajevae_test", {"width": 3}, train_cfg, positions, rotations)


def _tiny_experiment(clips):
    positions, rotations = clips
    cfg = dataclasses.replace(
        ExperimentConfig.quick(),
        train=TrainConfig(steps=2, batch_size=3, lr=1e-3, checkpoint_every=None),
        n_eval_windows=3,
    )
    windows = completion_windows(positions[:3])
    data = CompletionData(
        positions,
        rotations,
        windows,
        np.zeros(3, dtype=int),
        multimodal_futures(windows),
        positions[3:],
        rotations[3:],
    )
    return cfg, data


def test_runs_are_the_ladder_and_the_baselines_longest_first(clips):
    cfg, data = _tiny_experiment(clips)
    chapter_runs = runs(cfg, data)
    assert tuple(chapter_runs) == START_ORDER and set(START_ORDER) == set(RUNGS) | {"GRU", "CVAE-RNN"}
    assert {name: run.name for name, run in chapter_runs.items()} == CACHE_NAMES
    assert chapter_runs["+ masked future poses"].model == cfg.trajevae
    assert chapter_runs["GRU"].model == cfg.gru and chapter_runs["CVAE-RNN"].model == cfg.cvae_rnn
    assert not chapter_runs["Base"].model.learnable_prior and not chapter_runs["Base"].model.use_dct


def test_runs_validate_on_the_val_clips_without_changing_the_weights(clips, check_validation_leaves_weights):
    """Every run validates on all of the data's validation clips, in order, unturned even when the run
    augments, with masks as in training that every pass draws alike; the trained weights are those of the same
    run without validation, bit for bit (the yaw, the masks and the latent noise draw from the random state a
    validation pass must leave alone)."""
    cfg, data = _tiny_experiment(clips)
    cfg = dataclasses.replace(cfg, train=dataclasses.replace(cfg.train, steps=6, batch_size=2, val_every=4))
    run = runs(cfg, data)["+ masked future poses"]
    assert run.model.augment and run.train_config.val_every == 4 and run.val_batches is not None
    source = run.val_batches(None)
    batches = list(source(0, torch.Generator().manual_seed(1), 2))  # 3 clips: a batch of 2, then of 1
    assert [windows.shape[0] for windows, _ in batches] == [2, 1]
    assert torch.equal(torch.cat([windows for windows, _ in batches]), completion_windows(data.val_positions))
    again = list(source(0, torch.Generator().manual_seed(1), 2))
    assert all(torch.equal(mask, same) for (_, mask), (_, same) in zip(batches, again))
    assert batches[0][1].shape == (2, 22) and batches[1][1].shape == (1, 22)
    assert validation_batches(cfg.gru, data.val_positions, data.val_rotations).keep_probability == (
        cfg.gru.keep_probability
    )

    validated, result = run.train(progress=False)
    assert result.history.val_step == [4, 6] and len(result.history.val_terms["loss"]) == 2
    assert set(result.history.val_terms) == set(result.history.terms)
    check_validation_leaves_weights(run, validated)
    assert ExperimentConfig.quick().train.val_every == 4 and ExperimentConfig.full().train.val_every == 7


def test_train_all_trains_each_run_once_and_sweeps_it_as_in_process(clips):
    cfg, data = _tiny_experiment(clips)
    trained = train_all(cfg, data)
    assert tuple(trained) == START_ORDER and all(run.is_cached() for run in runs(cfg, data).values())
    for name, item in trained.items():
        assert item.result.loaded_from_cache and item.seconds is not None and item.seconds > 0
        ks = FIGURE6_KS if name in ("+ masked future poses", "GRU") else PAPER_KS
        assert set(item.measured) == set(ks)
    for name in ("+ masked future poses", "Base"):  # the sweep in a worker equals the sweep here
        item = trained[name]
        in_process = sweep_given_joints(
            item.model, data.test_windows, sorted(item.measured), cfg.n_samples, 0
        )
        assert item.measured == in_process


def test_schedule_check_trains_longer_and_measures_both_gaps(clips):
    cfg, data = _tiny_experiment(clips)
    measured = schedule_check(cfg, data, 16, reconstruction="mean")
    assert set(measured) == {"follow", "follow_ci95", "train_seconds", "apd_k0", "apd_k0_ci95"} | {
        "apd_k4",
        "apd_k4_ci95",
    } | {
        f"{name}_k{k}"
        for k in SCHEDULE_CHECK_KS
        for name in ("decode_prior", "decode_posterior", "sigma_p", "sigma_q")
    }
    assert all(math.isfinite(v) and v >= 0 for v in measured.values())
    assert schedule_check(cfg, data, 16, reconstruction="mean") == measured  # loaded from the cache
    with pytest.raises(ValueError, match="steps"):
        schedule_check(cfg, data, 2)


def test_experiment_config_profiles_and_model_dispatch(monkeypatch):
    quick = ExperimentConfig.quick()
    clips = torch.zeros(1, 60, 22, 3), torch.zeros(1, 60, 22, 4)
    run = {
        kind: completion_run(f"trajevae_{kind}", getattr(quick, kind), quick.train, *clips, clips)
        for kind in ("trajevae", "gru", "cvae_rnn")
    }
    assert isinstance(run["trajevae"].build(0), TrajeVAE)
    assert isinstance(run["gru"].build(0), GRUCompletion)
    assert type(run["cvae_rnn"].build(0)).__name__ == "CVAERNN"
    assert run["gru"].loss().__name__ == "gru_loss"
    assert run["cvae_rnn"].loss().__name__ == "cvae_rnn_loss"
    full = ExperimentConfig.full()
    assert full.trajevae.n_frames == 60 and full.train.steps == 300 and quick.train.steps == 10
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    assert ExperimentConfig.current() == quick
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    assert ExperimentConfig.current() == full
    with pytest.raises(TypeError, match="ExperimentConfig: gru must be a RecurrentConfig"):
        dataclasses.replace(quick, gru=quick.trajevae)
    with pytest.raises(ValueError, match="ExperimentConfig: n_eval_windows must be at least 2"):
        dataclasses.replace(quick, n_eval_windows=1)
    with pytest.raises(ValueError, match="same windows"):
        dataclasses.replace(quick, gru=dataclasses.replace(quick.gru, n_frames=30))


def test_bend_trajectory_moves_one_joint_to_the_left():
    trajectories = torch.zeros(10, 66)
    left = torch.tensor([0.0, 1.0, 0.0])
    bent = bend_trajectory(trajectories, "left_wrist", 0.5, left)
    index = 3 * JOINT["left_wrist"]
    assert bent[-1, index + 1].item() == pytest.approx(0.5)
    assert bent[4, index + 1].item() == pytest.approx(0.5 * 0.25)
    assert torch.count_nonzero(bent) == 10  # only the y channel of that joint
    with pytest.raises(ValueError, match="unknown joint"):
        bend_trajectory(trajectories, "tail", 0.5, left)


def test_left_direction_of_a_character_facing_x_is_y(clips):
    pose = torch.zeros(66)
    pose[3 * JOINT["left_hip"] + 1] = 0.1
    pose[3 * JOINT["right_hip"] + 1] = -0.1
    torch.testing.assert_close(left_direction(pose), torch.tensor([0.0, 1.0, 0.0]))
    with pytest.raises(ValueError, match="hips coincide"):
        left_direction(torch.zeros(66))


def test_complete_window_callback(clips):
    positions, _ = clips
    window = completion_windows(positions)[0]
    model = TrajeVAE(ExperimentConfig.quick().trajevae).eval()
    result = complete_window(
        model,
        window,
        ["right_foot", "pelvis"],
        n_samples=3,
        temperature=0.5,
        bend_joint="right_foot",
        bend=0.4,
        seed=2,
    )
    assert result.samples.shape == (3, 60, 22, 3)
    assert result.mask.sum() == 2 and result.mask[JOINT["right_foot"]] and result.mask[0]
    torch.testing.assert_close(result.samples[:, 0], window[0].reshape(22, 3).expand(3, -1, -1))
    # the requested right foot was bent: 0.4 m sideways at the end, relative to the true one
    shift = result.trajectories[-1, JOINT["right_foot"]] - window[-1].reshape(22, 3)[JOINT["right_foot"]]
    assert shift.norm().item() == pytest.approx(0.4, rel=1e-4) and abs(shift[2].item()) < 1e-6
    assert torch.count_nonzero(result.trajectories[:, JOINT["left_foot"]]) == 0
    same = complete_window(model, window, ["right_foot", "pelvis"], 3, 0.5, "right_foot", 0.4, seed=2)
    assert torch.equal(result.samples, same.samples)
    with pytest.raises(ValueError, match="can only bend a given joint"):
        complete_window(model, window, ["pelvis"], 2, 1.0, "right_foot", 0.3)
    assert math.isfinite(float(result.samples.abs().max())) and np.isfinite(result.samples.numpy()).all()
