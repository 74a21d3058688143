"""Streaming clips from a folder: every clip exactly once across processes x DataLoader workers, a seeded
order per epoch, labels from pose_clip.csv, .bvh files, and clear errors for a bad folder or file."""

from pathlib import Path

import numpy as np
import pytest
import torch
from torch.utils.data import DataLoader

from motionlab.data.bvh import load_bvh
from motionlab.data.streaming import ClipStream, clip_files, read_clip

BVH = sorted((Path(__file__).parent / "data").rglob("*.bvh"))


def write_clips(folder: Path, n: int) -> list[str]:
    folder.mkdir(parents=True, exist_ok=True)
    names = [f"clip{i:03d}" for i in range(n)]
    for i, name in enumerate(names):
        np.save(folder / f"{name}.npy", np.full((3 + i % 4, 5, 3), float(i)))
    return names


def names_read(stream: ClipStream, workers: int) -> list[str]:
    loader = DataLoader(stream, batch_size=None, num_workers=workers, collate_fn=lambda clip: clip)
    return [clip.name for clip in loader]


@pytest.mark.parametrize("world_size, workers", [(1, 0), (2, 0), (3, 2), (2, 2)])
def test_every_clip_is_read_once_across_processes_and_workers(tmp_path, world_size, workers):
    names = write_clips(tmp_path / "clips", 11)
    seen = []
    for rank in range(world_size):
        stream = ClipStream(tmp_path / "clips", rank=rank, world_size=world_size, seed=3)
        stream.set_epoch(1)
        seen += names_read(stream, workers)
    assert sorted(seen) == names


def test_the_order_is_seeded_per_epoch_and_the_same_in_every_process(tmp_path):
    write_clips(tmp_path, 9)
    a, b = ClipStream(tmp_path, seed=0), ClipStream(tmp_path, seed=0)
    assert a.ordered_files() == b.ordered_files()
    first = a.ordered_files()
    a.set_epoch(1)
    assert a.ordered_files() != first and sorted(a.ordered_files()) == sorted(first)
    assert ClipStream(tmp_path, seed=None).ordered_files() == clip_files(tmp_path)


def test_clips_carry_their_positions_and_their_labels(tmp_path):
    write_clips(tmp_path / "mocap_3djoints", 3)
    (tmp_path / "pose_clip.csv").write_text("motion,action_type\nclip001,Walk\nclip002,Run\n")
    clips = {clip.name: clip for clip in ClipStream(tmp_path, seed=None)}
    assert clips["clip001"].label == "Walk" and clips["clip000"].label is None
    assert clips["clip002"].positions.shape == (5, 5, 3) and clips["clip002"].positions.dtype == torch.float32
    assert torch.all(clips["clip002"].positions == 2.0)


@pytest.mark.skipif(not BVH, reason="no .bvh file among the test data")
def test_bvh_files_stream_as_world_positions(tmp_path):
    positions = read_clip(BVH[0])
    expected = torch.as_tensor(np.asarray(load_bvh(BVH[0]).global_positions()), dtype=torch.float32)
    assert torch.equal(positions, expected)


def test_a_bad_folder_or_file_gets_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such folder"):
        ClipStream(tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="holds no clip files"):
        ClipStream(tmp_path / "empty")
    np.save(tmp_path / "a.npy", np.zeros((4, 3)))
    with pytest.raises(ValueError, match="not a folder"):
        ClipStream(tmp_path / "a.npy")
    with pytest.raises(ValueError, match=r"a\.npy: expected joint positions \(T, J, 3\), got shape \(4, 3\)"):
        read_clip(tmp_path / "a.npy")
    (tmp_path / "b.npy").write_bytes(b"not an array")
    with pytest.raises(ValueError, match="b.npy: not a readable .npy array"):
        read_clip(tmp_path / "b.npy")
    (tmp_path / "c.bvh").write_text("HIERARCHY\nROOT")
    with pytest.raises(ValueError, match="c.bvh: not a readable BVH file"):
        read_clip(tmp_path / "c.bvh")
    np.save(tmp_path / "d.npy", np.full((2, 2, 3), np.nan))
    with pytest.raises(ValueError, match="NaN"):
        read_clip(tmp_path / "d.npy")
    with pytest.raises(ValueError, match="rank"):
        ClipStream(tmp_path, rank=2, world_size=2)
