"""Chapter 06's experiment: the profiles' configs, the named runs, and train_all (tiny models)."""

import dataclasses
import pickle

import pytest
import torch

from motionlab.models.moglow import MoGlowConfig, MoGlowFeatures, PreparedData, experiment, fit_scalers


def test_experiment_config_profiles_and_runs():
    quick, full = experiment.ExperimentConfig.quick(), experiment.ExperimentConfig.full()
    assert quick.moglow_steps < full.moglow_steps and quick.moglow_train_steps < full.moglow_train_steps
    assert experiment.ExperimentConfig.current() in (quick, full)
    assert full.moglow(0.5) == MoGlowConfig(steps=4, hidden=64, cond_features=64, dropout=0.5)
    named = experiment.runs(quick, data=None)
    assert list(named) == [
        "MoGlow p=0.0",
        "MoGlow p=0.5",
        "MoGlow p=0.95",
        "MoGlow p=0.95 unscaled",
        experiment.BASELINE,
    ]
    assert named["MoGlow p=0.5"].model.dropout == 0.5 and named["MoGlow p=0.5"].model.dropout_rescale
    assert not named["MoGlow p=0.95 unscaled"].model.dropout_rescale
    assert named[experiment.BASELINE].name == "moglow_gaussian_ar"
    with pytest.raises(ValueError, match="ExperimentConfig: window"):
        experiment.ExperimentConfig(window=0)
    with pytest.raises(TypeError, match="ExperimentConfig: n_commands"):
        experiment.ExperimentConfig(n_commands=2.5)


def test_train_all_trains_then_loads_every_run(tmp_path, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    cfg = dataclasses.replace(
        experiment.ExperimentConfig.quick(),
        dropout_rates=(0.0, 0.5),
        unscaled_rates=(),
        moglow_train_steps=2,
        batch_size=4,
        baseline_train_steps=2,
    )
    generator = torch.Generator().manual_seed(0)
    windows = MoGlowFeatures(
        torch.randn(8, 12, 64, generator=generator), torch.randn(8, 12, 3, generator=generator)
    )
    data = PreparedData(windows, windows, fit_scalers(windows), windows)
    named = experiment.runs(cfg, data)
    assert pickle.loads(pickle.dumps(named["MoGlow p=0.5"])).model == cfg.moglow(0.5)
    assert not any(run.is_cached() for run in named.values())
    first = experiment.train_all(cfg, data, processes=1, progress=False)
    assert list(first) == ["MoGlow p=0.0", "MoGlow p=0.5", experiment.BASELINE]
    assert all(run.is_cached() for run in named.values())
    again = experiment.train_all(cfg, data, processes=1, progress=False)
    for name, trained in first.items():
        assert trained.model.linear.fit_rms is None  # loaded from the cache: the fit is in its weights
        run = named[name]
        fresh = run.build(run.train_config.seed)
        run.initialize(fresh)  # what training starts from
        assert fresh.linear.fit_rms > 0
        # the predictor's buffers came through training and the cache as fitted
        loaded_rms = trained.model.initialize(windows.pose, windows.control, solve=False)
        assert loaded_rms == pytest.approx(fresh.linear.fit_rms, rel=1e-4, abs=1e-6)  # float32 weights
        assert again[name].result.loaded_from_cache
        for key, value in trained.model.state_dict().items():
            assert torch.equal(value, again[name].model.state_dict()[key])


def test_runs_validate_on_the_val_windows_without_changing_the_weights(
    tmp_path, monkeypatch, check_validation_leaves_weights
):
    """With validation windows a run records its held-out curve every ``val_every`` steps; the trained
    weights are those of the same run without validation, bit for bit (MoGlow's dropout and noise draw from
    the random state a validation pass must leave alone)."""
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    cfg = dataclasses.replace(
        experiment.ExperimentConfig.quick(),
        dropout_rates=(0.5,),
        unscaled_rates=(),
        moglow_train_steps=6,
        batch_size=4,
    )
    generator = torch.Generator().manual_seed(0)
    windows = MoGlowFeatures(
        torch.randn(8, 12, 64, generator=generator), torch.randn(8, 12, 3, generator=generator)
    )
    held_out = MoGlowFeatures(windows.pose[:3] + 0.1, windows.control[:3])
    run = experiment.runs(cfg, PreparedData(windows, windows, fit_scalers(windows), held_out))["MoGlow p=0.5"]
    assert run.train_config.val_every == 4 and run.val_batches is not None  # 6 steps: at step 4 and the end
    validated, result = run.train(progress=False)
    assert result.history.val_step == [4, 6] and len(result.history.val_terms["loss"]) == 2

    without_val = experiment.runs(cfg, PreparedData(windows, windows, fit_scalers(windows)))["MoGlow p=0.5"]
    with pytest.raises(ValueError, match=r"no validation windows \(data.val is None\)"):
        without_val.val_batches(validated)  # what training it would call first
    check_validation_leaves_weights(run, validated)

    with pytest.raises(ValueError, match="give both val_batches and train_config.val_every"):
        dataclasses.replace(run, val_batches=None)
