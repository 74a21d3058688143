"""The real-data evaluator and ODMO's Table 2 protocol on a few clips, and the real-data preparations of
ODMO and MoGlow."""

from __future__ import annotations

import dataclasses
from functools import partial

import numpy as np
import pytest
import torch

from motionlab.data import cmu_mocap as cm
from motionlab.data.augment import mirror_positions
from motionlab.evaluation import real
from motionlab.models.moglow import data as moglow_data
from motionlab.models.moglow import real_experiment as moglow_real
from motionlab.models.odmo import experiment as odmo_experiment
from motionlab.models.odmo.data import prepare_real, to_positions


@pytest.fixture(scope="module")
def bench() -> real.RealBenchmark:
    return real.load_real_benchmark(n_clips=56)


@pytest.fixture(scope="module")
def evaluator(bench: real.RealBenchmark, tmp_path_factory: pytest.TempPathFactory) -> real.XYZEvaluator:
    mp = pytest.MonkeyPatch()
    mp.setenv("MOTIONLAB_BUILD", str(tmp_path_factory.mktemp("build")))
    try:
        cfg = real.RealEvaluatorConfig(steps=3, hidden=8, batch_size=16)
        model, result = real.load_real_evaluator(bench.train, cfg, progress=False)
    finally:
        mp.undo()
    assert not result.loaded_from_cache
    return model


def test_benchmark_is_stratified_and_levelled(bench: real.RealBenchmark) -> None:
    assert bench.train.action_names == bench.test.action_names and len(bench.train.action_names) == 7
    assert set(bench.test.action.tolist()) == set(range(7))
    floors = [np.quantile(p[..., 2].min(-1), 0.05) for p in bench.train.positions]
    np.testing.assert_allclose(floors, 0.0, atol=1e-5)


def test_canonical_is_invariant_to_place_and_heading(bench: real.RealBenchmark) -> None:
    window = cm.random_windows(bench.train, 30, rng=0).positions[:3].astype(np.float64)
    yaw = 0.7
    turn = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    moved = window @ turn.T + [3.0, -2.0, 0.4]
    np.testing.assert_allclose(real.canonical(moved), real.canonical(window), atol=1e-9)


def test_evaluator_reads_windows_of_any_place(
    bench: real.RealBenchmark, evaluator: real.XYZEvaluator
) -> None:
    windows = cm.random_windows(bench.test, 100, rng=0).positions
    features = evaluator.features(windows)
    assert features.shape == (bench.test.n_clips, 30)
    shifted = evaluator.features(windows + np.array([5.0, 1.0, 0.0], dtype=np.float32))
    torch.testing.assert_close(features, shifted, atol=1e-4, rtol=1e-4)
    with pytest.raises(ValueError, match=r"\(N, T, 20, 3\)"):
        evaluator.features(np.zeros((2, 10, 22, 3)))


def test_table2_row_gives_intervals_and_is_seeded(
    bench: real.RealBenchmark, evaluator: real.XYZEvaluator
) -> None:
    protocol = real.Protocol.build(evaluator, bench.train, n=56, n_sets=2, window=40)
    assert protocol.n_sets == 2 and protocol.reference_features[0].shape == (56, 30)
    draw = partial(real.draw_real, clips=bench.test, n=56, window=40)
    row = real.table2_row(evaluator, protocol, draw)
    assert tuple(row) == real.TABLE2_METRICS
    assert all(len(interval.values) == 2 for interval in row.values())
    assert 0.0 <= row["accuracy"].mean <= 1.0 and row["fid"].mean >= 0.0
    assert real.table2_row(evaluator, protocol, draw)["fid"].values == row["fid"].values


def test_config_refusals() -> None:
    with pytest.raises(ValueError, match="frame_stride"):
        real.RealEvaluatorConfig(window=4, frame_stride=4)
    with pytest.raises(ValueError, match="n_sets"):
        real.Protocol.build(None, None, n_sets=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="window"):
        odmo_experiment.RealExperimentConfig(window=90)


def test_odmo_real_windows_decode_back_to_the_clips(bench: real.RealBenchmark) -> None:
    data = prepare_real(bench.train, window=40, frame_stride=1, draws=2, seed=0)
    assert data.features.shape == (2 * bench.train.n_clips, 40, 3 * 19 + 3)
    assert (data.action[: bench.train.n_clips] == torch.as_tensor(bench.train.action)).all()
    windows = cm.random_windows(bench.train, 40, np.random.default_rng([0, 0]))
    decoded = to_positions(data.features[: bench.train.n_clips], 1, data.floor_clearance)
    expected = torch.as_tensor(real.canonical(windows.positions), dtype=torch.float32)
    torch.testing.assert_close(
        decoded - decoded[:, :1, :1], expected - expected[:, :1, :1], atol=2e-4, rtol=0
    )


def test_odmo_real_runs_name_their_caches() -> None:
    cfg = odmo_experiment.RealExperimentConfig.quick()
    assert cfg.model.n_frames * cfg.frame_stride == cfg.window
    long = odmo_experiment.RealExperimentConfig.long()
    assert long.steps > odmo_experiment.RealExperimentConfig.full().steps and long.window == cfg.window


def test_moglow_real_features_mirror_consistently(bench: real.RealBenchmark) -> None:
    clip = torch.as_tensor(next(p for p in bench.train.positions if len(p) > 30)[:30], dtype=torch.float32)
    features = moglow_data.real_features(clip)
    assert features.pose.shape == (30, 58) and features.control.shape == (30, 3)
    mirrored = moglow_data.real_features(mirror_positions(clip, torch.tensor(cm.MIRROR)))
    # a mirrored walk goes forward at the same speed, sideways and turning the other way
    torch.testing.assert_close(mirrored.control[1:, 0], features.control[1:, 0], atol=1e-4, rtol=1e-4)
    torch.testing.assert_close(mirrored.control[1:, 1:], -features.control[1:, 1:], atol=1e-4, rtol=1e-4)


def test_moglow_real_windows_and_runs(bench: real.RealBenchmark) -> None:
    cfg = moglow_real.ExperimentConfig.quick()
    data = moglow_real.prepare(cfg, bench)
    windows = data.windows
    assert windows.train.pose.shape[1:] == (cfg.window, 58) and windows.test.control.shape[1:] == (
        cfg.window,
        3,
    )
    # the validation windows come from training clips held out of the fit: none of them is a training window
    assert windows.val is not None and windows.val.pose.shape[1:] == (cfg.window, 58)
    train_rows = {tuple(w.flatten().tolist()) for w in windows.train.pose[:, :2]}
    assert not any(tuple(w.flatten().tolist()) in train_rows for w in windows.val.pose[:, :2])
    runs = moglow_real.runs(cfg, data)
    assert set(runs) == {moglow_real.DEFAULT_RUN, moglow_real.BASELINE}
    assert all(run.val_batches is not None and run.train_config.val_every for run in runs.values())
    other_share = moglow_real.runs(dataclasses.replace(cfg, val_share=0.3), data)["MoGlow"]
    assert other_share.data != runs["MoGlow"].data  # the validation share is part of the cache key
    with pytest.raises(ValueError, match="unknown actions"):
        moglow_data.real_clip_windows(
            bench.train, moglow_data.MoGlowDataConfig(actions=("Swim",)), 20, 20, False
        )
