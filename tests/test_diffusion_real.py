"""MDM on the CMU clips (chapter 10's ``diffusion_cmu``): the position representation, its windows, its one
run and its Table 2 row under the chapter's protocol."""

from dataclasses import replace

import numpy as np
import pytest
import torch

from motionlab.data import cmu_mocap as cm
from motionlab.evaluation import real
from motionlab.models.diffusion import real_experiment as rx
from motionlab.models.diffusion.losses import diffusion_objective
from motionlab.models.diffusion.model import MDM, MDMConfig, PositionMDMConfig


def test_a_position_model_reads_the_joints_xyz_as_its_channels():
    cfg = rx.real_model(latent_dim=16, ff_size=32, layers=1, heads=2, diffusion_steps=20)
    assert cfg.representation == "xyz" and MDMConfig.representation == "rot6d"
    assert cfg.n_features == 3 * cm.N_JOINTS == 60 and cfg.feet == cm.FEET
    # the repository's 0.01 m per frame at 20 fps, at the model's 6 fps
    assert cfg.contact_threshold == pytest.approx(0.2 / 6)
    model = MDM(cfg)
    features = torch.randn(3, cfg.n_frames, 60)
    positions = model.joint_positions(features)
    assert positions.shape == (3, cfg.n_frames, 20, 3)
    assert torch.equal(positions[1, 4, 7], features[1, 4, 21:24])
    model.fit_standardizer(features)
    terms = diffusion_objective(model, (features, torch.tensor([0, 3, 6])), 0, {})
    assert set(terms) == {"loss", "simple", "position", "velocity", "foot_contact"}
    assert torch.isfinite(terms["loss"])
    with pytest.raises(ValueError, match="foot_joints"):
        PositionMDMConfig(n_joints=20, foot_joints=(20,))


def test_the_windows_are_odmos_faced_and_strided():
    bench = real.load_real_benchmark(112)
    data = rx.prepare_real(bench.train, window=40, frame_stride=2, draws=2, seed=0)
    assert data.features.shape == (2 * bench.train.n_clips, 20, 60)
    assert torch.equal(data.action[: bench.train.n_clips], torch.as_tensor(bench.train.action))
    first = data.features[:, 0].unflatten(-1, (20, 3))
    assert torch.allclose(
        first[:, 0, :2], torch.zeros(len(first), 2), atol=1e-5
    )  # first root over the origin
    windows = cm.random_windows(bench.train, 40, np.random.default_rng([0, 0]))
    want = torch.as_tensor(cm.face_x(windows.positions)[:, ::2], dtype=torch.float32).flatten(2)
    assert torch.equal(data.features[: bench.train.n_clips], want)
    with pytest.raises(ValueError, match="frame_stride"):
        rx.prepare_real(bench.train, window=41, frame_stride=2)


def test_the_config_ties_the_window_to_the_model_frames():
    cfg = rx.ExperimentConfig.full()
    assert cfg.window == cfg.model.n_frames * cfg.frame_stride == 100
    assert (cfg.n_sets, cfg.n_per_set) == (10, 400)
    assert rx.ExperimentConfig.long().steps == 20 * cfg.steps
    with pytest.raises(ValueError, match="window"):
        replace(cfg, window=80)
    with pytest.raises(ValueError, match="sample_steps"):
        replace(cfg, sample_steps=2000)
    assert rx.with_steps(cfg, "mdm", 7).steps == 7


def test_the_quick_run_trains_and_gives_a_table2_row():
    cfg = rx.ExperimentConfig.quick()
    data = rx.load_data(cfg)
    built = rx.runs(cfg, data)
    assert list(built) == [rx.DEFAULT_RUN] and built["mdm"].name == "real_mdm"
    trained = rx.train_all(cfg, data, processes=1)["mdm"]
    row = trained.measured["table2"]
    assert set(row) == set(real.TABLE2_METRICS)
    assert all(len(interval.values) == cfg.n_sets for interval in row.values())
    assert 0.0 <= row["accuracy"].mean <= 1.0 and row["fid"].mean > 0
    # every sample set is seeded by the protocol: the same row again
    again = rx.measure(cfg, data, "mdm", trained.model)["table2"]
    assert all(again[m].values == row[m].values for m in row)
    action = torch.tensor([0, 6])
    clips = rx.generate_windows(trained.model, cfg, action, torch.Generator().manual_seed(0))
    assert clips.shape == (2, cfg.window, 20, 3)
    with pytest.raises(ValueError, match="only run"):
        rx.measure(cfg, data, "mdm_no_geometry", trained.model)
    with pytest.raises(TypeError, match="ExperimentConfig"):
        rx.load_data(object())
