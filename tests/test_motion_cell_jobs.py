"""The chapter's runs: settings, job configs (same budget for every Table 2 model), schedules, data
helpers."""

import math

import pytest
import torch
from test_motion_cell_common import codec, features

from motionlab.models.motion_cell import jobs
from motionlab.models.motion_cell.preparation import cut_windows, rotation_error_degrees
from motionlab.models.motion_cell.settings import chapter_settings
from motionlab.models.motion_cell.training import motion_cell_schedules


def test_every_job_has_a_run_and_table_rows_share_one_budget():
    settings = chapter_settings()
    all_jobs = jobs.chapter_jobs()
    assert len(all_jobs) == len(set(all_jobs)) == 9 and all_jobs[0] == ("variant", "sl")
    runs = {job: jobs.job_run(job, settings) for job in all_jobs}
    table = [job for job in all_jobs if job[0] != "output"]
    budgets = {
        (runs[j].train.steps, runs[j].train.batch_size, runs[j].train.lr, runs[j].train.lr_schedule)
        for j in table
    }
    assert len(budgets) == 1
    assert {runs[j].train.steps for j in all_jobs if j[0] == "output"} == {settings.representation_steps}
    assert len({run.name for run in runs.values()}) == 9


def test_ablations_change_one_thing_each():
    settings = chapter_settings()
    full = jobs.job_run(("variant", "mcell"), settings)
    sl = jobs.job_run(("variant", "sl"), settings)
    nl = jobs.job_run(("variant", "nl"), settings)
    nc = jobs.job_run(("variant", "nc"), settings)
    assert sl.model.word_length == 1 and full.model.word_length == 3
    assert nl.loss.joint_weights == "uniform" and full.loss.joint_weights == "impact"
    last = settings.steps - 1
    assert (
        nc.train.schedules["classifier"](last) == 0
        and full.train.schedules["classifier"](last) == settings.classifier
    )
    for run in (sl, nl, nc):
        assert run.train.schedules["beta"] == full.train.schedules["beta"]


def test_baselines_and_output_heads():
    settings = chapter_settings()
    erd = jobs.job_run(("baseline", "erd"), settings)
    quaternet = jobs.job_run(("baseline", "quaternet"), settings)
    assert erd.model.kind == "erd" and set(erd.train.schedules) == {"input_noise"}
    assert quaternet.model.kind == "quaternet" and set(quaternet.train.schedules) == {"sampling"}
    assert erd.model.hidden_dim == settings.motion_cell.hidden_dim
    for kind in ("quaternion", "matrix", "axis_angle"):
        assert jobs.job_run(("output", kind), settings).model.output == kind
    with pytest.raises(ValueError, match="unknown job"):
        jobs.job_run(("variant", "xl"), settings)


def test_learning_rate_decay_and_motion_cell_schedules():
    decay = jobs.learning_rate_decay(100)
    assert decay(0) == 1.0 and decay(60) == 1.0 and decay(100) == pytest.approx(0.1)
    assert decay(80) == pytest.approx(0.55)
    schedules = motion_cell_schedules(100, beta=0.2, classifier=1.0, word_drop=0.5)
    beta, classifier, word_drop = schedules["beta"], schedules["classifier"], schedules["word_drop"]
    assert (
        beta(5) == 0 and beta(40) == pytest.approx(0.2) and beta(100) == pytest.approx(0.1)
    )  # warm-up, hold, cool-down
    assert classifier(29) == 0 and classifier(50) == pytest.approx(1.0)
    assert word_drop(10) == 0 and word_drop(60) == pytest.approx(0.5)
    with pytest.raises(ValueError, match="steps"):
        motion_cell_schedules(5)


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
    settings = chapter_settings()
    needing = {job for job in jobs.chapter_jobs() if jobs.uses_classifier(job, settings)}
    assert needing == {("variant", "mcell"), ("variant", "nl"), ("variant", "sl")}
