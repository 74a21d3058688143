"""Measurements kept for the rest of the build: an appendix that measures a chapter's models as the chapter
did (the same sample sets, the same metrics) reads the chapter's numbers instead of drawing them again.

A measurement is the ``then(name, model)`` of :func:`~motionlab.train.many.train_many`: seeded by its
arguments alone, so the same function with the same arguments, on the same weights, under the same code,
torch, thread count and numerical path, gives the same value. :func:`measure_once` keys its entry
``<build>/measurements/<source>/<name>-<hash>.pkl`` by all of these (the function and its bound arguments
pickled, every tensor among them and the weights by their bytes; ``<source>`` a digest of the package's
source), so an entry is only ever read where measuring again would give it bit for bit; anything else is
measured afresh. An entry that cannot be read is measured again and replaced; entries are written whole (a
temporary file renamed), so two notebooks measuring at once cannot leave half of one. The first entry of a
new version of the code removes the older versions' folders.
"""

from __future__ import annotations

import functools
import hashlib
import os
import pickle
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import torch
from torch import nn

from motionlab import config

M = TypeVar("M")

#: The package whose source is part of every key.
PACKAGE_DIR = Path(__file__).resolve().parents[1]


@functools.cache
def source_digest() -> str:
    """SHA-256 of the package's Python source (paths and contents): a measurement's code, whichever module
    it lives in."""
    digest = hashlib.sha256()
    for path in sorted(PACKAGE_DIR.rglob("*.py")):
        digest.update(path.relative_to(PACKAGE_DIR).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


class _DigestWriter:
    """A file that feeds what is written to it into a SHA-256 digest."""

    def __init__(self) -> None:
        self.digest = hashlib.sha256()

    def write(self, data: Any) -> int:  # bytes, or a buffer (pickle protocol 5)
        self.digest.update(data)
        return memoryview(data).nbytes


class _DigestPickler(pickle.Pickler):
    """A pickler whose output depends on values only: a tensor stands as its dtype, shape and the digest of
    its bytes (torch's own pickling of tensors writes a fresh serialization id each time)."""

    def persistent_id(self, obj: Any) -> Any:
        if isinstance(obj, torch.Tensor):
            data = obj.detach().reshape(-1).contiguous()
            content = hashlib.sha256(data.view(torch.uint8).numpy().tobytes()).hexdigest()
            return ("tensor", str(data.dtype), tuple(obj.shape), content)
        return None


def measurement_key(then: Callable[[str, nn.Module], Any], name: str, model: nn.Module) -> str:
    """The hash that names ``then(name, model)``'s entry: the function and its bound arguments, the model's
    class and weights, the package's source, torch's version, the thread count and the numerical path."""
    setting = (
        source_digest(),
        torch.__version__,
        torch.get_num_threads(),
        sorted(config.numerical_path().items()),
    )
    writer = _DigestWriter()
    what = (setting, then, name, type(model).__qualname__, model.state_dict())
    _DigestPickler(writer, protocol=pickle.HIGHEST_PROTOCOL).dump(what)
    return writer.digest.hexdigest()[:20]


def measurement_path(then: Callable[[str, nn.Module], Any], name: str, model: nn.Module) -> Path:
    """``<build>/measurements/<source>/<name>-<hash>.pkl``: ``<source>`` the first characters of
    :func:`source_digest` (entries of other code are stale), ``<hash>`` the :func:`measurement_key`."""
    folder = config.build_dir() / "measurements" / source_digest()[:16]
    return folder / f"{name}-{measurement_key(then, name, model)}.pkl"


def _drop_stale(folder: Path) -> None:
    """Remove the entries of other versions of the package's code beside ``folder`` (no measurement can
    read them again), so the store holds one version's measurements, not one per edit."""
    for other in folder.parent.iterdir():
        if other != folder and other.is_dir():
            shutil.rmtree(other, ignore_errors=True)


def measure_once(then: Callable[[str, nn.Module], M], name: str, model: nn.Module) -> M:
    """``then(name, model)``, read from its entry when this build has measured it before, else measured and
    kept."""
    path = measurement_path(then, name, model)
    if path.is_file():
        try:
            with path.open("rb") as file:
                return pickle.load(file)
        except Exception:  # noqa: BLE001 - truncated or unreadable: measured again below and replaced
            pass
    value = then(name, model)
    if not path.parent.is_dir():
        path.parent.mkdir(parents=True, exist_ok=True)
        _drop_stale(path.parent)
    with tempfile.NamedTemporaryFile(
        dir=path.parent, prefix=f".{name}-", suffix=".tmp", delete=False
    ) as file:
        pickle.dump(value, file, protocol=pickle.HIGHEST_PROTOCOL)
    os.replace(file.name, path)
    return value
