"""The synthetic data's container and file format: :class:`MotionSet`, saved as an ``.npz`` archive.

=================  ===================  =========
=============================================================== key                shape                dtype
    meaning =================  ===================  =========
    ===============================================================
``positions``      ``(N, T, J, 3)``     float32    global joint positions, metres, z up
``rotations``      ``(N, T, J, 4)``     float32    local joint quaternions, w first (the root's: its global
                                                   orientation), sign-continuous in time
``action``         ``(N,)``             int64      action id (index into ``action_names``)
``mode``           ``(N,)``             int64      style mode id (index into ``mode_names``), unique across
actions ``body``           ``(N,)``             int64      body type (index into ``offsets``)
``contacts``       ``(N, T, 4)``        bool       planted on the floor: left ankle, right ankle, left foot,
right foot ``action_names``   ``(A,)``             str
``mode_names``     ``(M,)``             str
``mode_action``    ``(M,)``             int64      the action of each mode
``parents``        ``(J,)``             int64      the kinematic tree (-1 for the root)
``offsets``        ``(n_body, J, 3)``   float32    rest offsets of each body type, metres
``fps``            ``()``               int64      frames per second
=================  ===================  =========
===============================================================

Invariant: forward kinematics of ``rotations`` with ``offsets[body]`` from ``positions[:, :, 0]`` gives
``positions`` (to float32 precision).
"""

from __future__ import annotations

import hashlib
import os
import zipfile
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

#: Expected dtype kind and symbolic shape of every key (``N`` clips, ``T`` frames, ``J`` joints, ...).
SCHEMA: dict[str, tuple[str, tuple[str | int, ...]]] = {
    "positions": ("float32", ("N", "T", "J", 3)),
    "rotations": ("float32", ("N", "T", "J", 4)),
    "action": ("int64", ("N",)),
    "mode": ("int64", ("N",)),
    "body": ("int64", ("N",)),
    "contacts": ("bool", ("N", "T", 4)),
    "action_names": ("str", ("A",)),
    "mode_names": ("str", ("M",)),
    "mode_action": ("int64", ("M",)),
    "parents": ("int64", ("J",)),
    "offsets": ("float32", ("K", "J", 3)),
    "fps": ("int64", ()),
}


#: The keys with one entry per clip (what :meth:`MotionSet.subset` selects).
_PER_CLIP = ("positions", "rotations", "action", "mode", "body", "contacts")


def _check_schema(arrays: dict[str, np.ndarray], where: str) -> None:
    """Raise naming ``where`` and the key: ``TypeError`` for a wrong dtype, ``ValueError`` when keys, shapes
    or values are wrong."""
    missing = sorted(set(SCHEMA) - set(arrays))
    unknown = sorted(set(arrays) - set(SCHEMA))
    if missing or unknown:
        raise ValueError(
            f"{where}: missing keys {missing}, unknown keys {unknown}; expected {sorted(SCHEMA)}"
        )
    sizes: dict[str, int] = {}
    for key, (dtype, shape) in SCHEMA.items():
        value = arrays[key]
        ok_dtype = value.dtype.kind == "U" if dtype == "str" else value.dtype == np.dtype(dtype)
        if not ok_dtype:
            raise TypeError(f"{where}: '{key}' must have dtype {dtype}, got {value.dtype}")
        if value.ndim != len(shape):
            raise ValueError(f"{where}: '{key}' must have shape {shape}, got {value.shape}")
        for axis, (name, size) in enumerate(zip(shape, value.shape)):
            expected = name if isinstance(name, int) else sizes.setdefault(name, size)
            if size != expected:
                raise ValueError(
                    f"{where}: '{key}' axis {axis} ({name}) has size {size}, expected {expected} "
                    f"from the other keys; shapes must be {shape}"
                )
    for key in ("positions", "rotations", "offsets"):
        if not np.isfinite(arrays[key]).all():
            raise ValueError(f"{where}: '{key}' contains NaN or infinite values")
    rotations = arrays["rotations"]
    norm_error = (
        np.abs(np.einsum("...i,...i->...", rotations, rotations) - 1) if rotations.size else np.zeros(1)
    )
    if norm_error.max() > 2e-3:
        raise ValueError(
            f"{where}: 'rotations' must be unit quaternions (largest |norm^2 - 1| is {norm_error.max():.3g})"
        )
    for key, bound in (("action", "A"), ("mode", "M"), ("body", "K"), ("mode_action", "A")):
        value = arrays[key]
        if value.size and (value.min() < 0 or value.max() >= sizes[bound]):
            raise ValueError(
                f"{where}: '{key}' values must lie in [0, {sizes[bound]}), got [{value.min()}, {value.max()}]"
            )
    if not np.array_equal(arrays["mode_action"][arrays["mode"]], arrays["action"]):
        raise ValueError(f"{where}: 'action' disagrees with 'mode_action[mode]' for some clips")
    parents = arrays["parents"]
    earlier = np.all((parents[1:] >= 0) & (parents[1:] < np.arange(1, parents.size)))
    if parents.size == 0 or parents[0] != -1 or not earlier:
        raise ValueError(
            f"{where}: 'parents' must be -1 for joint 0 and an earlier joint for every other, "
            f"got {parents.tolist()}"
        )
    if arrays["fps"] <= 0:
        raise ValueError(f"{where}: 'fps' must be positive, got {arrays['fps']}")


@dataclass(frozen=True, eq=False)
class MotionSet:
    """A set of ``N`` clips of ``T`` frames with their labels and skeletons (see the module notes for keys).

    Build one with :func:`motionlab.data.synthetic.generate`, or read one with :meth:`load`. The
    constructor validates keys, dtypes, shapes and values and raises ``ValueError`` naming what is wrong.
    """

    positions: np.ndarray
    rotations: np.ndarray
    action: np.ndarray
    mode: np.ndarray
    body: np.ndarray
    contacts: np.ndarray
    action_names: np.ndarray
    mode_names: np.ndarray
    mode_action: np.ndarray
    parents: np.ndarray
    offsets: np.ndarray
    fps: np.ndarray

    def __post_init__(self) -> None:
        _check_schema(self.arrays(), "MotionSet")

    def arrays(self) -> dict[str, np.ndarray]:
        """Every field as ``key -> array`` (the arrays themselves, not copies)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @property
    def n_clips(self) -> int:
        """Number of clips ``N``."""
        return int(self.positions.shape[0])

    @property
    def n_frames(self) -> int:
        """Frames per clip ``T``."""
        return int(self.positions.shape[1])

    def clip_offsets(self) -> np.ndarray:
        """Rest offsets of each clip's body ``(N, J, 3)`` float32."""
        return self.offsets[self.body]

    def subset(self, selection: np.ndarray) -> MotionSet:
        """The clips picked by a boolean mask ``(N,)`` or an array of clip indices (copies)."""
        selection = np.asarray(selection)
        if selection.dtype == bool and selection.shape != (self.n_clips,):
            raise ValueError(
                f"MotionSet.subset: a mask must have shape ({self.n_clips},), got {selection.shape}"
            )
        if selection.dtype != bool and selection.dtype.kind not in "iu":
            raise TypeError(
                f"MotionSet.subset: selection must be a boolean mask or integer indices, "
                f"got {selection.dtype}"
            )
        arrays = self.arrays()
        picked = {key: arrays[key][selection] for key in _PER_CLIP}
        shared = {key: value.copy() for key, value in arrays.items() if key not in _PER_CLIP}
        return MotionSet(**picked, **shared)

    def checksums(self) -> dict[str, str]:
        """SHA-256 of every array's bytes (C order), ``key -> hex digest``: a bitwise fingerprint of the
        data."""
        return {
            key: hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest()
            for key, value in self.arrays().items()
        }

    def save(self, path: str | Path, compress: bool = False) -> Path:
        """Write the ``.npz`` archive to exactly ``path`` (atomically: a crash leaves no half file)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        write = np.savez_compressed if compress else np.savez
        temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            with open(temporary, "wb") as handle:
                write(handle, **self.arrays())
            os.replace(temporary, path)
        finally:
            temporary.unlink(missing_ok=True)
        return path

    @classmethod
    def load(cls, path: str | Path) -> MotionSet:
        """Read and validate an archive written by :meth:`save`; ``ValueError`` names the file and the bad
        key."""
        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"MotionSet.load: no such file {path}")
        try:
            with np.load(path, allow_pickle=False) as archive:
                arrays = {key: archive[key] for key in archive.files}
        except (zipfile.BadZipFile, OSError, ValueError, EOFError) as exc:
            raise ValueError(f"MotionSet.load: {path} is not a readable .npz archive ({exc})") from exc
        if set(arrays) != set(SCHEMA):
            raise ValueError(
                f"MotionSet.load: {path} has missing keys {sorted(set(SCHEMA) - set(arrays))} and unknown "
                f"keys {sorted(set(arrays) - set(SCHEMA))}"
            )
        try:
            return cls(**arrays)
        except (TypeError, ValueError) as exc:  # a bad file is a bad value, whatever is wrong inside it
            raise ValueError(f"MotionSet.load: {path}: {exc}") from exc
