"""Clips streamed from a folder one file at a time: data larger than memory, split over processes and workers.

A folder of Action2Motion-style clips holds one ``.npy`` array of joint positions ``(T, J, 3)`` per clip
(directly or in ``mocap_3djoints/``), optionally with the table ``pose_clip.csv`` (columns ``motion``, the
file's stem, and ``action_type``) that labels them; ``.bvh`` files are read with
:func:`~motionlab.data.bvh.load_bvh` (their world positions). :class:`ClipStream` is an
:class:`~torch.utils.data.IterableDataset` over such a folder: it lists the files once, never loads more than
one clip at a time, and gives each data-parallel process (``rank`` of ``world_size``) and each of its
:class:`~torch.utils.data.DataLoader` workers its own share of the files, so that every clip is read exactly
once per epoch across all of them::

    stream = ClipStream("my_clips/", rank=rank, world_size=world_size, seed=0)
    stream.set_epoch(epoch)  # a new seeded order of the files, the same in every process
    for clip in DataLoader(stream, batch_size=None, num_workers=2):
        clip.positions  # (T, J, 3) float32 tensor; clip.name, clip.label
"""

from __future__ import annotations

import csv
import numbers
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor
from torch.utils.data import IterableDataset, get_worker_info

from motionlab.validation import check_scalar

#: The file endings a clip folder may hold.
CLIP_SUFFIXES = (".npy", ".bvh")

#: Action2Motion's clip table: file stem -> action.
LABEL_TABLE = "pose_clip.csv"


@dataclass(frozen=True)
class StreamedClip:
    """One clip of a folder.

    Attributes:
        name: the file's stem; path: the file; label: its action in ``pose_clip.csv`` (or ``None``).
        positions: joint positions ``(T, J, 3)`` (float32, the file's units).
    """

    name: str
    path: Path
    label: str | None
    positions: Tensor


def clip_files(folder: str | Path) -> list[Path]:
    """The clip files (``.npy``, ``.bvh``) under ``folder``, sorted by their path relative to it.

    Raises:
        FileNotFoundError: ``folder`` does not exist; ValueError: it is not a folder, or holds no clip file.
    """
    folder = Path(folder)
    if not folder.exists():
        raise FileNotFoundError(f"{folder}: no such folder")
    if not folder.is_dir():
        raise ValueError(f"{folder}: not a folder (expected a folder of .npy or .bvh clips)")
    files = sorted(
        (p for p in folder.rglob("*") if p.suffix.lower() in CLIP_SUFFIXES and p.is_file()),
        key=lambda p: p.relative_to(folder).as_posix(),
    )
    if not files:
        raise ValueError(f"{folder}: holds no clip files ({', '.join(CLIP_SUFFIXES)})")
    return files


def read_labels(folder: str | Path) -> dict[str, str]:
    """``{file stem: action}`` from the folder's ``pose_clip.csv`` (empty when there is none)."""
    table = Path(folder) / LABEL_TABLE
    if not table.is_file():
        return {}
    try:
        with open(table, newline="", encoding="utf-8") as handle:
            rows = list(csv.DictReader(handle))
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise ValueError(f"{table}: cannot read the clip table ({error})") from error
    if rows and not {"motion", "action_type"} <= set(rows[0]):
        raise ValueError(f"{table}: needs the columns 'motion' and 'action_type', got {sorted(rows[0])}")
    return {
        row["motion"].strip(): row["action_type"].strip() for row in rows if (row["motion"] or "").strip()
    }


def read_clip(path: str | Path) -> Tensor:
    """One clip's joint positions ``(T, J, 3)`` (float32) from a ``.npy`` or ``.bvh`` file.

    Raises:
        ValueError: naming the file, when it cannot be read or does not hold ``(T, J, 3)`` finite numbers.
    """
    path = Path(path)
    if path.suffix.lower() == ".bvh":
        from motionlab.data.bvh import load_bvh

        try:
            positions = load_bvh(path).global_positions()
        except (OSError, ValueError) as error:
            raise ValueError(f"{path}: not a readable BVH file ({error})") from error
        array = np.asarray(positions, dtype=np.float64)
    else:
        try:
            array = np.load(path, allow_pickle=False)
        except (OSError, ValueError, EOFError) as error:
            raise ValueError(f"{path}: not a readable .npy array ({error})") from error
        if array.dtype.kind not in "fiu":
            raise ValueError(f"{path}: holds {array.dtype}, not numbers")
    if array.ndim != 3 or array.shape[-1] != 3 or array.shape[0] < 1:
        raise ValueError(f"{path}: expected joint positions (T, J, 3), got shape {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{path}: holds NaN or infinite positions")
    return torch.from_numpy(np.ascontiguousarray(array, dtype=np.float32))


def shard_of(files: list[Any], shard: int, n_shards: int) -> list[Any]:
    """The files of shard ``shard`` of ``n_shards``: every ``n_shards``-th one from ``shard`` on."""
    return files[shard::n_shards]


class ClipStream(IterableDataset):
    """The clips of a folder, streamed file by file; see the module docstring.

    Args:
        folder: the folder (searched recursively for ``.npy`` and ``.bvh`` files).
        rank, world_size: this process among the data-parallel processes (``torch.distributed``'s rank).
        seed: seeds the order of the files in every epoch (:meth:`set_epoch`); ``None`` keeps sorted order.
        transform: applied to every clip before it is yielded (e.g. cutting a window); ``None``: the clip.

    Every process and every DataLoader worker reads only its own share (shard ``rank * workers + worker``
    of ``world_size * workers``), so each clip is read exactly once per epoch across all of them. The shares
    differ by at most one clip; a data-parallel training loop that needs equal step counts should stop
    every process after the smallest share (:meth:`min_share`).
    """

    def __init__(
        self,
        folder: str | Path,
        rank: int = 0,
        world_size: int = 1,
        seed: int | None = 0,
        transform: Callable[[StreamedClip], Any] | None = None,
    ) -> None:
        super().__init__()
        check_scalar(world_size, "world_size", "ClipStream", kind=numbers.Integral, minimum=1)
        check_scalar(rank, "rank", "ClipStream", kind=numbers.Integral, minimum=0, maximum=world_size - 1)
        if seed is not None:
            check_scalar(seed, "seed", "ClipStream", kind=numbers.Integral, minimum=0)
        if transform is not None and not callable(transform):
            raise TypeError(f"ClipStream: transform must be callable, got {type(transform).__name__}")
        self.folder = Path(folder)
        self.files = clip_files(self.folder)
        self.labels = read_labels(self.folder)
        self.rank, self.world_size, self.seed, self.transform = int(rank), int(world_size), seed, transform
        self.epoch = 0

    def __len__(self) -> int:
        """The number of clips in the folder (all processes together)."""
        return len(self.files)

    def set_epoch(self, epoch: int) -> None:
        """Use the file order of ``epoch`` (seeded by ``(seed, epoch)``; call it in every process)."""
        check_scalar(epoch, "epoch", "ClipStream.set_epoch", kind=numbers.Integral, minimum=0)
        self.epoch = int(epoch)

    def ordered_files(self) -> list[Path]:
        """Every file in this epoch's order (the same in every process and worker)."""
        if self.seed is None:
            return list(self.files)
        order = torch.randperm(
            len(self.files), generator=torch.Generator().manual_seed(self.seed + self.epoch)
        )
        return [self.files[i] for i in order.tolist()]

    def shard(self) -> tuple[int, int]:
        """``(shard, n_shards)`` of the calling process and DataLoader worker."""
        info = get_worker_info()
        workers, worker = (1, 0) if info is None else (info.num_workers, info.id)
        return self.rank * workers + worker, self.world_size * workers

    def __iter__(self) -> Iterator[Any]:
        shard, n_shards = self.shard()
        for path in shard_of(self.ordered_files(), shard, n_shards):
            clip = StreamedClip(path.stem, path, self.labels.get(path.stem), read_clip(path))
            yield clip if self.transform is None else self.transform(clip)
