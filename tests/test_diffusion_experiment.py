"""Chapter 11's experiment: its two runs, the ablation's zero weights, the config's limits and
``with_steps`` (the training command's quick run of it is in ``test_train_cli.py``)."""

from dataclasses import replace

import pytest
import torch

from motionlab.models.diffusion.data import MDMData
from motionlab.models.diffusion.experiment import (
    DEFAULT_RUN,
    VARIANTS,
    ChapterData,
    ExperimentConfig,
    runs,
    with_steps,
)
from motionlab.models.diffusion.model import MDMConfig


def toy_data(cfg: ExperimentConfig) -> ChapterData:
    """Random clips of the config's shape (the runs are only built, never trained, here)."""
    model = cfg.model
    n = 12
    train = MDMData(
        torch.randn(n, model.n_frames, model.n_features),
        torch.arange(n) % model.n_actions,
        torch.zeros(n, dtype=torch.int64),
        torch.zeros(n, dtype=torch.int64),
        cfg.frame_stride,
    )
    return ChapterData(train, evaluator=None, train_features=torch.zeros(1), fps=30.0, real_skating=0.0)


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
    assert built["mdm"].train_config.steps == cfg.steps == 4


def test_the_full_profile_is_the_course_model():
    cfg = ExperimentConfig.full()
    assert cfg.model == MDMConfig.course()
    assert ExperimentConfig.long().steps == 20 * cfg.steps


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
