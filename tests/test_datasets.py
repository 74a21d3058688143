"""Tests of motionlab.data.datasets: windows, stratified clip splits, the standardiser.

Oracles: window counts by hand, NumPy statistics, and the representations applied to single windows.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
import torch
from test_representations import make_clips
from torch.utils.data import DataLoader

from motionlab.data.augment import random_yaw
from motionlab.data.datasets import (
    Standardizer,
    build_splits,
    motion_windows,
    split_clips,
    window_starts,
)
from motionlab.data.representations import REPRESENTATION_NAMES, RootStart, representation
from motionlab.skeleton import PARENTS


@pytest.fixture(scope="module")
def clips():
    return make_clips(n_clips=30, n_frames=24, seed=4, dtype=torch.float32)


@pytest.mark.parametrize(
    "n_frames, length, stride, count",
    [(24, 24, 1, 1), (24, 8, 4, 5), (24, 10, 7, 3), (24, 1, 1, 24), (25, 8, 4, 5)],
)
def test_window_counts(n_frames, length, stride, count):
    starts = window_starts(n_frames, length, stride)
    assert starts.numel() == count == (n_frames - length) // stride + 1
    assert starts[0] == 0 and bool((starts[1:] - starts[:-1] == stride).all())
    assert int(starts[-1]) + length <= n_frames


def test_window_longer_than_clip_raises(clips):
    with pytest.raises(ValueError, match="window length 25 is longer than the clips \\(24 frames\\)"):
        motion_windows(clips, representation("odmo"), length=25, stride=1)
    with pytest.raises(ValueError, match="window_starts: stride must be at least 1, got 0"):
        window_starts(24, 8, 0)
    with pytest.raises(TypeError, match=r"window_starts: length must be an integer, got 8.0 \(float\)"):
        window_starts(24, 8.0, 1)


@pytest.mark.parametrize("name", REPRESENTATION_NAMES)
def test_windows_are_encoded_as_clips_of_their_own(clips, name):
    rep = representation(name)
    dataset = motion_windows(clips, rep, length=8, stride=4, clip_indices=[3, 17])
    assert len(dataset) == 2 * 5
    item = dataset[7]  # clip 17, its third window
    assert set(item) == {"features", "action", "mode", "body", "clip", "start", "root_position", "root_yaw"}
    assert item["features"].shape == (8, rep.dim) and item["features"].dtype == torch.float32
    assert (int(item["clip"]), int(item["start"])) == (17, 8)
    for label in ("action", "mode", "body"):
        assert item[label].dtype == torch.int64 and item[label] == getattr(clips, label)[17]
    window = slice(8, 16)
    expected = rep.encode(clips.positions[17, window], clips.rotations[17, window])
    torch.testing.assert_close(item["features"], expected)
    start = RootStart(item["root_position"], item["root_yaw"])
    decoded = rep.decode(item["features"], start, clips.offsets[clips.body[17]], PARENTS)
    torch.testing.assert_close(decoded, clips.positions[17, window], rtol=0, atol=2e-5)


def test_dataloader_batches_the_dicts(clips):
    dataset = motion_windows(clips, representation("moglow"), length=12, stride=6)
    batch = next(iter(DataLoader(dataset, batch_size=5, shuffle=False)))
    assert batch["features"].shape == (5, 12, 67)
    assert batch["clip"].tolist() == [0, 0, 0, 1, 1] and batch["start"].tolist() == [0, 6, 12, 0, 6]


def test_split_is_disjoint_complete_stratified_and_seeded():
    mode = torch.arange(103) % 4  # modes of 26, 26, 26 and 25 clips
    split = split_clips(mode, (0.7, 0.2, 0.1), seed=3)
    parts = [set(s.tolist()) for s in split]
    assert parts[0].isdisjoint(parts[1]) and parts[0].isdisjoint(parts[2]) and parts[1].isdisjoint(parts[2])
    assert set.union(*parts) == set(range(103))
    for fraction, indices in zip((0.7, 0.2, 0.1), split):
        assert abs(indices.numel() - fraction * 103) < 1
        counts = torch.bincount(mode[indices], minlength=4)
        expected = fraction * torch.bincount(mode).double()
        assert bool(((counts - expected).abs() < 2).all()), (fraction, counts, expected)
    again = split_clips(mode.numpy(), (0.7, 0.2, 0.1), seed=3)
    assert all(torch.equal(a, b) for a, b in zip(split, again))
    other = split_clips(mode, (0.7, 0.2, 0.1), seed=4)
    assert not torch.equal(split.train, other.train)


@pytest.mark.parametrize("seed", range(5))
def test_small_modes_still_fill_every_split(seed):
    # 12 modes of 4 clips: 10 % of a mode is 0.4 clips, yet val and test get about 5 clips each
    mode = torch.arange(48) // 4
    split = split_clips(mode, (0.8, 0.1, 0.1), seed=seed)
    assert [s.numel() for s in split] == [38, 5, 5]
    for indices in split[1:]:
        assert torch.bincount(mode[indices], minlength=12).max() == 1  # five different modes


def test_empty_split_raises():
    with pytest.raises(ValueError, match="the test split is empty"):
        split_clips(torch.zeros(4, dtype=torch.long), (0.8, 0.1, 0.1))
    with pytest.raises(ValueError, match="fractions must be three positive numbers"):
        split_clips(torch.zeros(40, dtype=torch.long), (0.8, 0.2, 0.0))
    with pytest.raises(
        TypeError, match="split_clips: mode must be a 1-D integer array .N,., got dtype torch.float32"
    ):
        split_clips(torch.zeros(40), (0.8, 0.1, 0.1))
    with pytest.raises(
        ValueError, match=r"split_clips: mode must be a 1-D integer array \(N,\), got shape \(4, 10\)"
    ):
        split_clips(torch.zeros(4, 10, dtype=torch.long), (0.8, 0.1, 0.1))
    with pytest.raises(ValueError, match="split_clips: seed must be at least 0, got -1"):
        split_clips(torch.zeros(40, dtype=torch.long), (0.8, 0.1, 0.1), seed=-1)


def test_standardizer_round_trip_floor_and_state_dict():
    gen = torch.Generator().manual_seed(0)
    features = torch.randn(50, 6, 4, generator=gen) * torch.tensor([1.0, 10.0, 0.01, 0.0]) + 3.0
    standardizer = Standardizer(4, min_std=1e-3).fit(features)
    flat = features.reshape(-1, 4).double().numpy()
    np.testing.assert_allclose(standardizer.mean.numpy(), flat.mean(axis=0), rtol=1e-6)
    np.testing.assert_allclose(standardizer.std.numpy(), np.maximum(flat.std(axis=0), 1e-3), rtol=1e-5)
    assert standardizer.std[3] == pytest.approx(1e-3)  # the constant channel sits on the floor
    z = standardizer.transform(features)
    torch.testing.assert_close(z[..., :3].reshape(-1, 3).mean(0), torch.zeros(3), rtol=0, atol=1e-5)
    torch.testing.assert_close(
        z[..., :3].reshape(-1, 3).std(0, correction=0), torch.ones(3), rtol=0, atol=1e-5
    )
    torch.testing.assert_close(standardizer.inverse(z), features, rtol=1e-6, atol=1e-6)
    restored = Standardizer(4)
    restored.load_state_dict(standardizer.state_dict())
    assert restored.fitted and int(restored.count) == 300
    torch.testing.assert_close(restored.transform(features), z, rtol=0, atol=0)


def test_standardizer_errors():
    standardizer = Standardizer(3)
    with pytest.raises(RuntimeError, match="not fitted"):
        standardizer.transform(torch.zeros(2, 3))
    with pytest.raises(ValueError, match=r"Standardizer.fit: features must have shape \(\.\.\., 3\)"):
        standardizer.fit(torch.zeros(5, 4))
    with pytest.raises(
        ValueError, match=r"Standardizer.fit: features contains NaN .* \(first at index \(0, 2\)\)"
    ):
        standardizer.fit(torch.tensor([[0.0, 1.0, float("nan")], [0.0, 1.0, 2.0]]))
    with pytest.raises(TypeError, match="Standardizer.fit: features must have a floating-point dtype"):
        standardizer.fit(torch.zeros(5, 3, dtype=torch.long))
    with pytest.raises(ValueError, match="Standardizer: min_std must be greater than 0, got 0.0"):
        Standardizer(3, min_std=0.0)
    with pytest.raises(TypeError, match="Standardizer: n_features must be an integer"):
        Standardizer(3.0)


def test_build_splits_uses_train_statistics_only(clips):
    rep = representation("trajevae")
    data = build_splits(clips, rep, length=12, stride=6, seed=1, fractions=(0.6, 0.2, 0.2))
    clips_of = [set(d.clip.tolist()) for d in (data.train, data.val, data.test)]
    assert clips_of == [set(s.tolist()) for s in data.split]
    assert clips_of[0].isdisjoint(clips_of[1] | clips_of[2]) and clips_of[1].isdisjoint(clips_of[2])
    assert [len(d) for d in (data.train, data.val, data.test)] == [3 * len(s) for s in data.split]
    raw_train = motion_windows(clips, rep, 12, 6, data.split.train).features.reshape(-1, rep.dim).double()
    torch.testing.assert_close(data.standardizer.mean.double(), raw_train.mean(0), rtol=1e-5, atol=1e-6)
    raw_all = motion_windows(clips, rep, 12, 6).features.reshape(-1, rep.dim).double()
    assert not torch.allclose(data.standardizer.mean.double(), raw_all.mean(0), rtol=1e-3, atol=1e-4)
    raw_val = motion_windows(clips, rep, 12, 6, data.split.val).features
    torch.testing.assert_close(data.standardizer.inverse(data.val.features), raw_val, rtol=1e-5, atol=1e-5)
    train = data.train.features.reshape(-1, rep.dim)
    torch.testing.assert_close(train.mean(0), torch.zeros(rep.dim), rtol=0, atol=1e-4)


def test_build_splits_augments_train_windows_only(clips):
    rep = representation("odmo")
    plain = build_splits(clips, rep, length=12, stride=6, seed=1, fractions=(0.6, 0.2, 0.2))
    augment = partial(random_yaw, generator=torch.Generator().manual_seed(0))
    turned = build_splits(clips, rep, length=12, stride=6, seed=1, fractions=(0.6, 0.2, 0.2), augment=augment)
    assert not torch.allclose(turned.standardizer.mean, plain.standardizer.mean)
    torch.testing.assert_close(
        turned.standardizer.inverse(turned.val.features),
        plain.standardizer.inverse(plain.val.features),
        rtol=1e-5,
        atol=1e-5,
    )


def test_motion_windows_input_errors(clips):
    rep = representation("odmo")
    with pytest.raises(ValueError, match="clip_indices must lie in \\[0, 30\\)"):
        motion_windows(clips, rep, 8, 4, clip_indices=[0, 30])
    with pytest.raises(ValueError, match="clip_indices is empty"):
        motion_windows(clips, rep, 8, 4, clip_indices=[])
    with pytest.raises(ValueError, match="clips have 22 joints but the odmo representation expects 5"):
        motion_windows(clips, representation("odmo", n_joints=5), 8, 4)


def test_chunked_encoding_matches_one_pass(clips, monkeypatch):
    rep = representation("motion_cell")
    whole = motion_windows(clips, rep, length=10, stride=7)
    monkeypatch.setattr("motionlab.data.datasets.ENCODE_CHUNK", 4)
    chunked = motion_windows(clips, rep, length=10, stride=7)
    assert torch.equal(chunked.features, whole.features) and torch.equal(chunked.clip, whole.clip)
