"""The chapter's experiment: configs per profile, the named runs (same budget for every Table 2 model),
schedules, data helpers."""

import dataclasses
import math
import pickle

import pytest
import torch
from test_motion_cell_common import clips, codec, features

from motionlab.data.synthetic import generate
from motionlab.models.motion_cell.data import WindowBatch, WindowBatches, cut_windows
from motionlab.models.motion_cell.denoise import VAL_CAPTURE_SEED, PreparedData, noisy_features
from motionlab.models.motion_cell.evaluate import rotation_error_degrees
from motionlab.models.motion_cell.experiment import (
    TABLE,
    ExperimentConfig,
    learning_rate_decay,
    motion_cell_schedules,
    prepare_training_data,
    runs,
    uses_classifier,
)
from motionlab.train import validation_every
from motionlab.train.run import Run


def _prepared(cfg: ExperimentConfig, with_val: bool = True) -> PreparedData:
    """Stand-in prepared data (a few short clips, not denoised); the validation windows are five of the clips,
    moved a little (``None`` without ``with_val``)."""
    poses = codec().encode(features())
    batches = WindowBatches(poses, clips().action, clips().body, length=cfg.window)
    val = WindowBatches(
        poses[:5] + 0.01, clips().action[:5], clips().body[:5], cfg.window, shuffle=False, drop_last=False
    )
    return PreparedData(codec(), poses, batches, "fingerprint", None, None, {}, val if with_val else None)


def _runs() -> dict[str, Run]:
    """The runs of the quick profile on stand-in data."""
    return runs(ExperimentConfig.quick(), _prepared(ExperimentConfig.quick()))


def test_quick_full_and_current_profiles():
    quick, full = ExperimentConfig.quick(), ExperimentConfig.full()
    assert quick.steps < full.steps and quick.motion_cell.hidden_dim < full.motion_cell.hidden_dim
    assert ExperimentConfig.current() in (quick, full)
    with pytest.raises(ValueError, match="ExperimentConfig: window"):
        ExperimentConfig(window=25)
    with pytest.raises(TypeError, match="ExperimentConfig: steps"):
        ExperimentConfig(steps=12.0)
    with pytest.raises(ValueError, match="ExperimentConfig: word_drop"):
        ExperimentConfig(word_drop=1.5)


def test_every_run_is_named_and_table_rows_share_one_budget():
    cfg = ExperimentConfig.quick()
    all_runs = _runs()
    assert len(all_runs) == 11 and next(iter(all_runs)) == "mcell_long"
    assert set(TABLE) < set(all_runs)
    budgets = {
        (
            run.train_config.steps,
            run.train_config.batch_size,
            run.train_config.lr,
            run.train_config.lr_schedule,
        )
        for name, run in all_runs.items()
        if name in TABLE
    }
    assert len(budgets) == 1
    outputs = [run for name, run in all_runs.items() if name.startswith("output_")]
    assert {run.train_config.steps for run in outputs} == {cfg.representation_steps}
    longer = {name: all_runs[name] for name in ("mcell_long", "erd_long")}
    assert {run.train_config.steps for run in longer.values()} == {cfg.collapse_steps}
    assert longer["mcell_long"].model == all_runs["mcell"].model  # the same models, trained longer
    assert longer["erd_long"].model == all_runs["erd"].model
    assert len({run.name for run in all_runs.values()}) == 11


def test_runs_are_picklable():
    run = _runs()["mcell"]
    copy = pickle.loads(pickle.dumps(run))
    assert copy.name == run.name and copy.model == run.model and copy.train_config == run.train_config


def test_ablations_change_one_thing_each():
    cfg = ExperimentConfig.quick()
    all_runs = _runs()
    full, sl, nl, nc = (all_runs[name] for name in ("mcell", "sl", "nl", "nc"))
    assert sl.model["model"].word_length == 1 and full.model["model"].word_length == 3
    assert nl.model["loss"].joint_weights == "uniform" and full.model["loss"].joint_weights == "impact"
    last = cfg.steps - 1
    assert (
        nc.train_config.schedules["classifier"](last) == 0
        and full.train_config.schedules["classifier"](last) == cfg.classifier
    )
    for run in (sl, nl, nc):
        assert run.train_config.schedules["beta"] == full.train_config.schedules["beta"]


def test_baselines_and_output_heads():
    cfg = ExperimentConfig.quick()
    all_runs = _runs()
    erd, quaternet = all_runs["erd"], all_runs["quaternet"]
    assert erd.model["model"].kind == "erd" and set(erd.train_config.schedules) == {"input_noise"}
    assert quaternet.model["model"].kind == "quaternet" and set(quaternet.train_config.schedules) == {
        "sampling"
    }
    assert erd.model["model"].hidden_dim == cfg.motion_cell.hidden_dim
    for kind in ("quaternion", "matrix", "axis_angle"):
        assert all_runs[f"output_{kind}"].model["model"].output == kind


def test_learning_rate_decay_and_motion_cell_schedules():
    decay = learning_rate_decay(100)
    assert decay(0) == 1.0 and decay(60) == 1.0 and decay(70) == pytest.approx(0.55)
    assert decay(80) == pytest.approx(0.1) and decay(100) == pytest.approx(0.1)  # held over the last fifth
    assert learning_rate_decay(1)(0) == 1.0  # the decay never starts before the first step
    schedules = motion_cell_schedules(100, beta=1.0, classifier=1.0, word_drop=0.5)
    beta, classifier, word_drop = schedules["beta"], schedules["classifier"], schedules["word_drop"]
    # §3.5.1: warm-up at 0, annealing 0 -> 1, cool-down at lambda_KL = 1 until the end
    assert beta(5) == 0 and beta(10) == 0 and beta(40) == pytest.approx(0.5)
    assert beta(70) == pytest.approx(1.0) and beta(100) == pytest.approx(1.0)
    assert classifier(29) == 0 and classifier(50) == pytest.approx(1.0)
    assert word_drop(10) == 0 and word_drop(60) == pytest.approx(0.5)
    with pytest.raises(ValueError, match="steps"):
        motion_cell_schedules(5)
    with pytest.raises(TypeError, match="steps"):
        motion_cell_schedules(50.0)


def test_cut_windows_and_rotation_error():
    x = torch.arange(2 * 7 * 3, dtype=torch.float32).reshape(2, 7, 3)
    windows = cut_windows(x, 3)
    assert windows.shape == (4, 3, 3)
    torch.testing.assert_close(windows[1], x[0, 3:6])
    with pytest.raises(ValueError, match="shorter"):
        cut_windows(x, 8)
    c = codec()
    poses = c.encode(features())
    turned = poses.clone()
    half = math.radians(10) / 2  # every joint turned by 10 degrees about x
    turned[..., :84] = torch.tensor([math.cos(half), math.sin(half), 0.0, 0.0]).repeat(21)
    reference = poses.clone()
    reference[..., :84] = torch.tensor([1.0, 0.0, 0.0, 0.0]).repeat(21)
    assert rotation_error_degrees(c, turned, reference) == pytest.approx(10.0, rel=1e-4)
    assert rotation_error_degrees(c, poses, poses) == pytest.approx(0.0, abs=1e-2)


def test_only_the_variants_with_a_classifier_loss_need_the_evaluator():
    needing = {name for name, run in _runs().items() if uses_classifier(run.train_config)}
    assert needing == {"mcell", "mcell_long", "nl", "sl"}


def test_every_run_validates_40_times_on_the_validation_windows():
    for name, run in _runs().items():
        assert run.train_config.val_every == validation_every(run.train_config.steps), name
        assert run.val_batches(None) is run.val_batches.args[0].val, name


def test_runs_validate_on_the_val_windows_without_changing_the_weights(
    tmp_path, monkeypatch, check_validation_leaves_weights
):
    """With validation windows a run records its held-out curve every ``val_every`` steps; the trained
    weights are those of the same run without validation, bit for bit (the Motion Cell's latent samples and
    word dropping draw from the random state a validation pass must leave alone)."""
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    cfg = dataclasses.replace(ExperimentConfig.quick(), steps=10, batch_size=4)
    run = runs(cfg, _prepared(cfg))["nc"]
    assert run.train_config.val_every == 4 and run.val_batches is not None  # 10 steps: 4, 8 and the end
    validated, result = run.train(progress=False)
    assert result.history.val_step == [4, 8, 10] and len(result.history.val_terms["loss"]) == 3

    without_val = runs(cfg, _prepared(cfg, with_val=False))["nc"]
    with pytest.raises(ValueError, match=r"no validation windows \(data.val is None\)"):
        without_val.val_batches(validated)  # what training it would call first
    check_validation_leaves_weights(run, validated)


def test_prepared_data_validates_the_denoiser_and_carries_denoised_validation_windows(tmp_path, monkeypatch):
    """The denoiser validates every ``val_every`` steps on the captured training split against its clean
    clips (held out: it trains on the validation split); the models' validation windows are the validation
    clips captured with their own noise, denoised, in order, every clip."""
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    cfg = ExperimentConfig.quick()
    train, val = clips(), generate(seed=1, n_per_mode=1, seconds=1.0)
    data = prepare_training_data(train, val, cfg, progress=False)
    history = data.denoiser_result.history
    assert history.val_step == [4, 8, 10] and cfg.denoiser_steps == 10 and "pose" in history.val_terms
    captured = data.codec.encode(noisy_features(val.rotations, val.positions, VAL_CAPTURE_SEED))
    assert torch.equal(data.val.poses, data.denoiser.denoise(captured))
    assert not data.val.shuffle and not data.val.drop_last and data.val.length == cfg.window
    batches = list(data.val(0, torch.Generator().manual_seed(0), 5))
    assert [len(b.action) for b in batches] == [5, 5, 2] and all(isinstance(b, WindowBatch) for b in batches)
    assert torch.equal(torch.cat([b.action for b in batches]), torch.as_tensor(val.action))
    assert torch.equal(torch.cat([b.body for b in batches]), torch.as_tensor(val.body))
