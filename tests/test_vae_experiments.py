"""Chapter 03's measurements (latent summaries, pose plausibility), the KL schedule, the experiment config and
its runs."""

from __future__ import annotations

import math
import pickle
from dataclasses import replace

import numpy as np
import pytest
import torch

from motionlab.data.datasets import motion_windows
from motionlab.data.representations import representation
from motionlab.data.synthetic import generate
from motionlab.evaluation.benchmark import load_benchmark
from motionlab.models.vae.data import pose_features
from motionlab.models.vae.evaluate import latent_summary, plausibility
from motionlab.models.vae.experiment import ExperimentConfig, runs
from motionlab.models.vae.losses import kl_weight
from motionlab.train.run import Run


def test_latent_summary_measures_activity_in_prior_units():
    g = torch.Generator().manual_seed(0)
    mu = torch.randn(500, 3, generator=g) * torch.tensor([1.0, 0.05, 0.0])
    logvar = torch.full((500, 3), math.log(0.2))
    unit = latent_summary(mu, logvar)
    assert unit.active == 1  # variances 1, 0.0025, 0 against the 0.01 threshold
    assert torch.allclose(unit.posterior_var, torch.full((3,), 0.2))
    assert torch.allclose(unit.mu_std, mu.std(0))
    expected_kl = 0.5 * (-math.log(0.2) + 0.2 + (mu**2).mean(0) - 1)
    assert torch.allclose(unit.kl_per_dim, expected_kl, atol=1e-5)
    # the same codes measured against a prior of variance 0.05: activity divides by 0.05
    small = latent_summary(mu, logvar, prior_logvar=math.log(0.05))
    assert torch.allclose(small.activity, unit.activity / 0.05, rtol=1e-5)
    assert small.active == 2


def test_plausibility_is_zero_for_real_poses_and_grows_with_stretching():
    clips = generate(0, 1, seconds=1.0)
    poses = torch.as_tensor(clips.positions[:, 0])  # (12, 22, 3), both body types
    assert plausibility(poses, clips.offsets, clips.parents) < 1e-5
    stretched = poses * 1.1
    bones = np.linalg.norm(clips.offsets[clips.body], axis=-1)[:, 1:]  # (12, 21) each clip's own bones
    assert plausibility(stretched, clips.offsets, clips.parents) == pytest.approx(
        0.1 * bones.mean(), rel=0.05
    )
    with pytest.raises(ValueError, match="poses \\(N, 22, 3\\)"):
        plausibility(poses[0], clips.offsets, clips.parents)


def test_kl_weight_and_configs():
    ramp = kl_weight(600, anneal=True)
    assert ramp(0) == 0.0 and ramp(150) == pytest.approx(0.5) and ramp(300) == 1.0 and ramp(599) == 1.0
    assert kl_weight(600, anneal=False)(0) == 1.0
    with pytest.raises(ValueError, match="kl_weight: steps must be at least 1"):
        kl_weight(0, anneal=True)
    cfg = ExperimentConfig.current()
    cvae = cfg.clip_model(n_actions=6, prior_var=0.05)
    assert cvae.input_shape == (cfg.clip_length, 67) and cvae.n_classes == 6
    assert math.exp(cvae.obs_logvar) == pytest.approx(33.5)
    assert math.exp(cvae.prior_logvar) == pytest.approx(0.05)
    assert cfg.pose_model(variational=False).variational is False


def test_experiment_config_profiles_and_checks():
    quick, full = ExperimentConfig.quick(), ExperimentConfig.full()
    assert quick.pose_steps < full.pose_steps and quick.clip_hidden < full.clip_hidden
    assert ExperimentConfig.current() in (quick, full)
    with pytest.raises(ValueError, match="ExperimentConfig: clip_steps must be at least 1"):
        ExperimentConfig(clip_steps=0)
    with pytest.raises(TypeError, match="ExperimentConfig: pose_every must be an integer"):
        ExperimentConfig(pose_every=2.5)
    with pytest.raises(ValueError, match="ExperimentConfig: lr must be greater than 0"):
        ExperimentConfig(lr=0.0)


def test_runs_are_named_picklable_and_keep_their_cache_names():
    cfg = ExperimentConfig.quick()
    named = runs(cfg, n_actions=6)
    assert list(named) == ["cvae", "cvae_no_anneal", "pose_ae", "pose_vae", "pose_vae_small_prior"]
    assert {name: run.name for name, run in named.items()} == {
        "cvae": "vae03_cvae",
        "cvae_no_anneal": "vae03_cvae_no_anneal",
        "pose_ae": "vae03_pose_ae",
        "pose_vae": "vae03_pose_vae",
        "pose_vae_small_prior": "vae03_pose_vae_small_prior",
    }
    assert all(isinstance(run, Run) for run in named.values())
    copied = pickle.loads(pickle.dumps(named))
    assert {name: (run.name, run.model, run.train_config, run.data) for name, run in copied.items()} == {
        name: (run.name, run.model, run.train_config, run.data) for name, run in named.items()
    }
    assert named["cvae"].model == named["cvae_no_anneal"].model
    assert named["cvae"].train_config.schedules["beta"](0) == 0.0
    assert named["cvae_no_anneal"].train_config.schedules["beta"](0) == 1.0
    assert named["pose_ae"].model.variational is False
    assert math.exp(named["pose_vae_small_prior"].model.prior_logvar) == pytest.approx(cfg.small_prior_var)


def test_a_run_trains_into_the_cache_and_loads_the_same_weights(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    cfg = ExperimentConfig(pose_every=20, pose_hidden=8, pose_steps=3, clip_hidden=8, clip_steps=3)
    run = runs(cfg, n_actions=6)["cvae"]
    assert not run.is_cached()
    model, result = run.train(progress=False)
    assert run.is_cached() and not result.loaded_from_cache and result.metrics["steps"] == 3
    again, cached = run.train(progress=False)
    assert cached.loaded_from_cache
    for (key, value), (other, loaded) in zip(model.state_dict().items(), again.state_dict().items()):
        assert key == other and torch.equal(value, loaded)
    x, label = cfg.clips.training_inputs()
    assert x.shape[1:] == (cfg.clip_length, 67) and label.shape == x.shape[:1]


@pytest.mark.parametrize("name", ["pose_vae", "cvae"])
def test_runs_validate_on_the_val_split_without_changing_the_weights(name, tmp_path, monkeypatch):
    """A run validates on the benchmark's val split, prepared like its training data (the training data's
    statistics), every ``val_every`` steps; its weights are those of the same run without validation, bit for
    bit (the latent draws come from the random state a validation pass must leave alone)."""
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    cfg = ExperimentConfig(pose_every=20, pose_hidden=8, pose_steps=6, clip_hidden=8, clip_steps=6)
    run = runs(cfg, n_actions=6)[name]
    assert run.train_config.val_every == 4 and run.val_batches is not None  # 6 steps: at step 4 and the end
    data = cfg.clips if name == "cvae" else cfg.poses
    x, label = data.validation_inputs()
    val = load_benchmark().val
    if name == "cvae":
        standardizer = data.load().codec.standardizer
        expected = motion_windows(val, representation("moglow"), cfg.clip_length, cfg.clip_stride)
        assert torch.allclose(x, standardizer.transform(expected.features))
        assert torch.equal(label, expected.action)
    else:
        expected = pose_features(val, every=cfg.pose_every)
        assert label is None and torch.equal(x, data.load().standardizer.transform(expected))
    batches = list(run.val_batches(None)(0, torch.Generator(), cfg.batch_size))
    served = torch.cat([batch[0] if name == "cvae" else batch for batch in batches])
    assert torch.equal(served, x)  # every sample, in its order, the last batch short

    validated, result = run.train(progress=False)
    assert result.history.val_step == [4, 6] and len(result.history.val_terms["objective"]) == 2
    plain_run = replace(run, train_config=replace(run.train_config, val_every=None), val_batches=None)
    plain, plain_result = plain_run.train(progress=False)
    assert plain_result.history.val_step == []
    for key, value in validated.state_dict().items():
        assert torch.equal(value, plain.state_dict()[key]), key
