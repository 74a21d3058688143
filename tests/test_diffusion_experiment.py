"""Chapter 11's experiment: its two runs, the ablation's zero weights, their validation on the val clips,
the config's limits, ``with_steps`` (the training command's quick run of it: ``test_train_cli.py``) and the
joint speed per action."""

from dataclasses import replace

import numpy as np
import pytest
import torch

from motionlab.data.synthetic import generate
from motionlab.evaluation import joint_speed
from motionlab.models.diffusion.data import MDMData
from motionlab.models.diffusion.experiment import (
    DEFAULT_RUN,
    VARIANTS,
    ChapterData,
    ExperimentConfig,
    action_speeds,
    runs,
    variant_runs,
    with_steps,
)
from motionlab.models.diffusion.losses import diffusion_objective
from motionlab.models.diffusion.model import MDMConfig
from motionlab.train.batches import epoch_seed
from motionlab.train.loop import VALIDATION_STREAM


def toy_clips(cfg: ExperimentConfig, n: int, generator: torch.Generator) -> MDMData:
    """``n`` random clips of the config's shape."""
    model = cfg.model
    return MDMData(
        torch.randn(n, model.n_frames, model.n_features, generator=generator),
        torch.arange(n) % model.n_actions,
        torch.zeros(n, dtype=torch.int64),
        torch.zeros(n, dtype=torch.int64),
        cfg.frame_stride,
    )


def toy_data(cfg: ExperimentConfig) -> ChapterData:
    """12 random training clips and 5 validation clips of the config's shape (no evaluator)."""
    generator = torch.Generator().manual_seed(0)
    return ChapterData(
        toy_clips(cfg, 12, generator),
        toy_clips(cfg, 5, generator),
        evaluator=None,
        train_features=torch.zeros(1),
        fps=30.0,
        real_skating=0.0,
        real_speed={},
    )


def test_the_runs_are_mdm_and_its_ablation_without_the_geometric_losses():
    cfg = ExperimentConfig.quick()
    built = runs(cfg, toy_data(cfg))
    assert list(built) == ["mdm", "mdm_no_geometry"] == list(VARIANTS)
    assert DEFAULT_RUN in built
    full, ablation = built["mdm"].model, built["mdm_no_geometry"].model
    assert (full.lambda_pos, full.lambda_vel, full.lambda_foot) == (1.0, 1.0, 1.0)
    assert (ablation.lambda_pos, ablation.lambda_vel, ablation.lambda_foot) == (0.0, 0.0, 0.0)
    assert ablation == MDMConfig.course(
        latent_dim=16,
        ff_size=32,
        layers=1,
        heads=2,
        diffusion_steps=100,
        lambda_pos=0,
        lambda_vel=0,
        lambda_foot=0,
    )
    assert {run.name for run in built.values()} == set(VARIANTS)
    assert (
        built["mdm"].train_config.steps == cfg.steps == 12 and built["mdm"].train_config.lr == cfg.lr == 5e-3
    )


def test_runs_validate_on_the_val_clips_without_changing_the_weights(tmp_path, monkeypatch):
    """Both runs validate on ``data.val`` every ``val_every`` steps, every clip once (the last batch short),
    standardised by the model's training statistics; the trained weights are those of the same run without
    validation, bit for bit (the diffusion steps, the noise, dropout and the null condition draw from the
    random state a validation pass must leave alone)."""
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    cfg = replace(ExperimentConfig.quick(), steps=6, batch_size=4)
    data = toy_data(cfg)
    built = runs(cfg, data)
    assert all(run.train_config == cfg.train_config(validate=True) for run in built.values())
    run = built["mdm"]
    assert run.train_config.val_every == 4  # 6 steps: at step 4 and the end
    validated, result = run.train(progress=False)
    assert result.history.val_step == [4, 6]
    assert set(result.history.val_terms) == {"loss", "simple", "position", "velocity", "foot_contact"}

    batches = list(run.val_batches(validated)(0, torch.Generator(), cfg.batch_size))
    assert [len(action) for _, action in batches] == [4, 1]
    assert torch.equal(torch.cat([features for features, _ in batches]), data.val.features)
    torch.manual_seed(epoch_seed(cfg.seed, 0, VALIDATION_STREAM))  # the draws of every validation pass
    with torch.no_grad():
        last = [diffusion_objective(validated, batch, cfg.steps, {})["loss"].item() for batch in batches]
    assert result.history.val_terms["loss"][-1] == pytest.approx(sum(last) / len(last), rel=1e-6)

    plain_run = variant_runs(cfg, data.train)["mdm"]  # no val clips: no validation
    assert plain_run.train_config.val_every is None and plain_run.val_batches is None
    plain, plain_result = plain_run.train(progress=False)
    assert plain_result.history.val_step == []
    for key, value in validated.state_dict().items():
        assert torch.equal(value, plain.state_dict()[key]), key
    with pytest.raises(ValueError, match="give both val_batches and train_config.val_every"):
        replace(run, val_batches=None)


def test_the_full_profile_is_the_course_model():
    cfg = ExperimentConfig.full()
    assert cfg.model == MDMConfig.course()
    assert ExperimentConfig.long().steps == 2 * cfg.steps


@pytest.mark.parametrize(
    "field, value",
    [("steps", 0), ("lr", 0.0), ("frame_stride", 0), ("n_sets", 1), ("guidance", -1.0), ("sample_steps", 0)],
)
def test_a_bad_value_is_refused_with_the_fields_name(field, value):
    with pytest.raises(ValueError, match=field):
        ExperimentConfig(**{field: value})


def test_more_sampling_steps_than_diffusion_steps_are_refused():
    with pytest.raises(ValueError, match="sample_steps"):
        ExperimentConfig(model=MDMConfig.course(diffusion_steps=10), sample_steps=20)


def test_a_wrong_frame_stride_or_clip_shape_is_refused():
    cfg = ExperimentConfig.quick()
    with pytest.raises(ValueError, match="frame_stride"):
        runs(replace(cfg, frame_stride=3), toy_data(cfg))
    short = replace(cfg, model=MDMConfig.course(n_frames=30, latent_dim=16, heads=2))
    with pytest.raises(ValueError, match="expects clips of 30 frames"):
        runs(short, toy_data(cfg))


def test_with_steps_changes_every_runs_steps_and_nothing_else():
    cfg = ExperimentConfig.quick()
    longer = with_steps(cfg, "mdm_no_geometry", 17)
    assert longer.steps == 17
    assert all(run.train_config.steps == 17 for run in runs(longer, toy_data(longer)).values())
    assert longer.model == cfg.model and longer.batch_size == cfg.batch_size


def test_action_speeds_average_each_actions_clips_and_leave_out_an_action_without_clips():
    clips = generate(seed=2, n_per_mode=2)
    positions, action = clips.positions[:, :20], np.asarray(clips.action)
    names = [*clips.action_names, "absent"]
    speeds = action_speeds(positions, action, names, fps=30.0)
    per_clip = joint_speed(positions, fps=30.0).mean(-1).numpy()
    assert list(speeds) == list(clips.action_names)
    for index, name in enumerate(clips.action_names):
        assert speeds[name] == pytest.approx(per_clip[action == index].mean(), rel=1e-6)
    assert speeds["walk"] > 4 * speeds["wave"]  # a walking body moves more than a waving one
    with pytest.raises(ValueError, match="one action per clip"):
        action_speeds(positions, action[:-1], names, fps=30.0)
