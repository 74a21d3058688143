"""The chapter's experiment: configs per profile, the named runs (same budget for every Table 2 model),
schedules, data helpers."""

import math
import pickle

import pytest
import torch
from test_motion_cell_common import clips, codec, features

from motionlab.models.motion_cell.data import WindowBatches, cut_windows
from motionlab.models.motion_cell.denoise import PreparedData
from motionlab.models.motion_cell.evaluate import rotation_error_degrees
from motionlab.models.motion_cell.experiment import (
    TABLE,
    ExperimentConfig,
    learning_rate_decay,
    motion_cell_schedules,
    runs,
    uses_classifier,
)
from motionlab.train.run import Run


def _runs() -> dict[str, Run]:
    """The runs of the quick profile on stand-in data (a few short clips, not denoised)."""
    cfg = ExperimentConfig.quick()
    poses = codec().encode(features())
    batches = WindowBatches(poses, clips().action, clips().body, length=cfg.window)
    return runs(cfg, PreparedData(codec(), poses, batches, "fingerprint", None, None, {}))


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
