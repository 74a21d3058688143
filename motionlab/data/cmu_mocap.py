"""Real motion capture: the CMU clips of Action2Motion, the benchmark ODMO calls "MoCap".

1,088 labelled clips of the CMU Graphics Lab Motion Capture Database, as Action2Motion (Guo et al., ACM MM
2020) cut, subsampled (about 12 fps) and labelled them with eight actions. Joint positions only: 20 joints,
no rotations. The data card is ``data_real/README.md``.

**Sources.** :func:`load_cmu_mocap` reads any of

* the compact copy shipped in ``data_real/`` (the default; a fresh clone needs nothing else): positions in
  metres quantised to :data:`QUANTUM`, stored as per-clip frame differences, every array checked against
  its SHA-256 in ``data_real/checksums.json``;
* the repacked original, one ``.npz`` with ``positions (F, 20, 3)`` in CMU units and ``clip_start``,
  ``clip_length``, ``clip_id``, ``action``, ``action_names``, ``kinematic_chain``;
* Action2Motion's download: a folder with ``pose_clip.csv`` (columns ``motion`` and ``action_type``, the
  action an index 0..7 into :data:`ACTION_NAMES` or its name) and one ``<motion>.npy`` ``(T, 20, 3)`` per
  clip in CMU units, either beside the table or in its ``mocap_3djoints/`` subfolder.

**Frames.** Every source has y up in its own axes; the loader returns the course's frame: metres (one CMU
length unit is :data:`motionlab.data.bvh.CMU_SCALE` m) and z up, by a rotation of +90 degrees about x
(``(x, y, z) -> (x, -z, y)``, a proper rotation, so left stays left). Clips keep where they were captured
and which way they face; :func:`face_x`, :func:`first_root_at_origin` and :func:`root_relative` normalise
that.

**Joints** (:data:`JOINT_NAMES`): pelvis, spine, neck, head, then the left arm (shoulder, elbow, wrist,
hand), the right arm, the left leg (hip, knee, ankle, toe) and the right leg. Left and right were read off
the data: with the course's left = up x forward, 80 % of the 358 walk clips that travel more than 0.3 m
end up within 60 degrees of the first frame's forward direction (12 % within 60 degrees of backwards).

**ODMO's protocol** (Table 2): :func:`odmo_clips` drops Wash (970 clips, 7 classes),
:func:`random_windows` cuts one random 100-frame window per clip (shorter clips padded with their last
frame; each window's first root at the origin), :func:`stratified_indices` draws clips with the classes in
proportion.

Refusals follow :mod:`motionlab.validation`: a clip the course cannot use (too short, NaN or infinite,
wrong joint count, unknown label) raises ``ValueError`` naming the clip; a malformed or corrupt file raises
``ValueError`` naming the file and what is wrong with it.
"""

from __future__ import annotations

import argparse
import ast
import csv
import hashlib
import json
import numbers
import os
import sys
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motionlab import arguments
from motionlab.data.bvh import CMU_SCALE
from motionlab.paths import REPO_ROOT
from motionlab.skeleton import Skeleton
from motionlab.validation import (
    ArrayLike,
    Checked,
    RngLike,
    as_labels,
    as_rng,
    check_array,
    check_choice,
    check_scalar,
    flag,
    integer,
    real,
)

FPS = 12.0
"""Nominal frame rate: Action2Motion kept every 10th frame of the 120-fps takes (a few 60-fps takes are
about 6 fps; the files do not say which)."""

ACTION_NAMES = ("Walk", "Wash", "Run", "Jump", "Animal Behavior", "Dance", "Step", "Climb")
"""Action2Motion's eight classes, in the order of its label indices."""

ODMO_DROPPED = ("Wash",)
"""The class ODMO leaves out of its benchmark (mostly mislabelled clips)."""

JOINT_NAMES = (
    "pelvis",
    "spine",
    "neck",
    "head",
    "left_shoulder",
    "left_elbow",
    "left_wrist",
    "left_hand",
    "right_shoulder",
    "right_elbow",
    "right_wrist",
    "right_hand",
    "left_hip",
    "left_knee",
    "left_ankle",
    "left_toe",
    "right_hip",
    "right_knee",
    "right_ankle",
    "right_toe",
)
"""The 20 joints in the files' order; joint 0 is the root."""

N_JOINTS = len(JOINT_NAMES)

KINEMATIC_CHAIN = ((0, 1, 2, 3), (0, 12, 13, 14, 15), (0, 16, 17, 18, 19), (1, 4, 5, 6, 7), (1, 8, 9, 10, 11))
"""Action2Motion's five chains (spine, left leg, right leg, left arm, right arm), each from its parent
joint outwards."""

JOINT = {name: index for index, name in enumerate(JOINT_NAMES)}

DATA_DIR = REPO_ROOT / "data_real"
"""Where the compact copy lives (the default source of :func:`load_cmu_mocap`)."""

COMPACT_FILE = "cmu_mocap_a2m_compact.npz"
CHECKSUM_FILE = "checksums.json"

QUANTUM = 2e-4
"""Step (metres) of the compact copy's positions: every coordinate is off by at most half of it."""

Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
"""The rotation (+90 degrees about x) that takes the files' y-up axes to the course's z-up axes."""

_ORIGINAL_KEYS = ("positions", "clip_start", "clip_length", "clip_id", "action", "action_names")
_COMPACT_KEYS = ("positions_delta", "quantum", "clip_length", "clip_id", "action", "action_names")


def parents_from_chains(chains: Sequence[Sequence[int]], n_joints: int) -> tuple[int, ...]:
    """Parent of every joint ``(J,)`` (-1 for the root) from chains that each run from a parent outwards.

    Raises:
        ValueError: a joint gets two parents, a joint other than 0 gets none, or the order is not
            parents-first (``parents[j] < j``).
    """
    parents = [-2] * n_joints
    parents[0] = -1
    for chain in chains:
        for parent, child in zip(chain[:-1], chain[1:]):
            if not 0 < child < n_joints or parents[child] not in (-2, parent):
                raise ValueError(f"parents_from_chains: joint {child} of chain {list(chain)} is invalid here")
            parents[child] = parent
    if any(not -1 <= p < j for j, p in enumerate(parents)):
        raise ValueError(f"parents_from_chains: chains {chains} do not give a parents-first tree: {parents}")
    return tuple(parents)


PARENTS = parents_from_chains(KINEMATIC_CHAIN, N_JOINTS)
"""Parent of each joint, what :mod:`motionlab.viz` draws with (``filmstrip(clip, PARENTS)``)."""


def _mirror_permutation(names: Sequence[str]) -> tuple[int, ...]:
    """Index of each joint's mirror image (``left_*`` <-> ``right_*``; the others map to themselves)."""
    swapped = [n.replace("left_", "@").replace("right_", "left_").replace("@", "right_") for n in names]
    return tuple(list(names).index(n) for n in swapped)


MIRROR = _mirror_permutation(JOINT_NAMES)
"""The left/right joint map ``(J,)``: joint ``j`` of a mirrored pose is joint ``MIRROR[j]`` of the original
reflected (``motionlab.data.augment.mirror_positions(x, torch.tensor(MIRROR))``)."""

FEET = (JOINT["left_ankle"], JOINT["left_toe"], JOINT["right_ankle"], JOINT["right_toe"])
"""The joints that touch the floor in locomotion (foot contact, floor levelling)."""


# ----------------------------------------------------------------------------------------------------
# the clips


@dataclass(frozen=True)
class LoadConfig(Checked):
    """What :func:`load_cmu_mocap` accepts.

    Attributes:
        min_frames: the fewest frames a clip may have (2 by default: velocities need two frames; the
            shortest clips of the data have 3).
        verify: check the compact copy against its SHA-256 checksums (about 0.3 s of a 0.8 s load).
    """

    min_frames: int = integer(2, minimum=1)
    verify: bool = flag(True)


@dataclass(frozen=True, eq=False)
class MocapClips(Checked):
    """Clips of different lengths with their labels.

    Attributes:
        positions: one array ``(T_i, J, 3)`` float32 per clip, global joint positions, metres, z up.
        action: ``(N,)`` int64 class of each clip, an index into ``action_names``.
        clip_id: ``(N,)`` CMU trial of each clip, e.g. ``"02_01"`` (subject 02, trial 01).
        action_names: the class names.
        parents: ``(J,)`` parent of each joint (-1 for the root), from the file's kinematic chain; what
            :mod:`motionlab.viz` draws with.
        fps: frames per second (nominal).
    """

    positions: tuple[np.ndarray, ...]
    action: np.ndarray
    clip_id: tuple[str, ...]
    action_names: tuple[str, ...]
    parents: tuple[int, ...] = PARENTS
    fps: float = real(FPS, above=0)

    def __post_init__(self) -> None:
        super().__post_init__()
        where = "MocapClips"
        object.__setattr__(self, "positions", tuple(self.positions))
        object.__setattr__(self, "clip_id", tuple(str(c) for c in self.clip_id))
        object.__setattr__(self, "action_names", tuple(str(a) for a in self.action_names))
        action = np.asarray(self.action)
        if action.dtype.kind not in "iu":
            raise TypeError(f"{where}: action must be a 1-D integer array, got dtype {action.dtype}")
        if action.ndim != 1:
            raise ValueError(f"{where}: action must be a 1-D integer array, got shape {action.shape}")
        object.__setattr__(self, "action", action.astype(np.int64))
        object.__setattr__(self, "parents", tuple(int(p) for p in self.parents))
        if not len(self.positions) == len(self.action) == len(self.clip_id):
            raise ValueError(
                f"{where}: positions, action and clip_id need one entry per clip, got "
                f"{len(self.positions)}, {len(self.action)} and {len(self.clip_id)}"
            )
        for clip, action_index, positions in zip(self.clip_id, self.action, self.positions):
            if not 0 <= action_index < len(self.action_names):
                raise ValueError(
                    f"{where}: clip {clip}: unknown label {action_index} "
                    f"(classes 0..{len(self.action_names) - 1})"
                )
            if not isinstance(positions, np.ndarray):
                raise TypeError(
                    f"{where}: clip {clip}: positions must be a NumPy array (T, J, 3), "
                    f"got {type(positions).__name__}"
                )
            if positions.ndim != 3 or positions.shape[2] != 3:
                raise ValueError(
                    f"{where}: clip {clip}: positions must be an array (T, J, 3), got shape {positions.shape}"
                )

    @property
    def n_clips(self) -> int:
        """Number of clips ``N``."""
        return len(self.positions)

    @property
    def lengths(self) -> np.ndarray:
        """Frames of every clip ``(N,)`` int64."""
        return np.array([len(p) for p in self.positions], dtype=np.int64)

    def class_counts(self) -> dict[str, int]:
        """Clips per class, ``name -> count``, in the order of ``action_names``."""
        counts = np.bincount(self.action, minlength=len(self.action_names))
        return dict(zip(self.action_names, counts.tolist()))

    def subset(self, selection: ArrayLike) -> MocapClips:
        """The clips picked by a boolean mask ``(N,)`` or integer indices (the arrays are shared, not
        copied)."""
        selection = np.asarray(selection)
        if selection.dtype == bool:
            if selection.shape != (self.n_clips,):
                raise ValueError(
                    f"MocapClips.subset: a mask must have shape ({self.n_clips},), got {selection.shape}"
                )
            selection = np.nonzero(selection)[0]
        elif selection.dtype.kind not in "iu":
            raise TypeError(
                "MocapClips.subset: selection must be a boolean mask or integer indices, "
                f"got {selection.dtype}"
            )
        picked = selection.reshape(-1).tolist()
        return MocapClips(
            tuple(self.positions[i] for i in picked),
            self.action[picked],
            tuple(self.clip_id[i] for i in picked),
            self.action_names,
            self.parents,
            self.fps,
        )

    def map(self, transform: Callable[[np.ndarray], np.ndarray]) -> MocapClips:
        """The same clips with ``transform`` applied to each clip's positions ``(T, J, 3)`` (the result
        stored as float32), e.g. ``clips.map(face_x)``."""
        moved = tuple(np.asarray(transform(p), dtype=np.float32) for p in self.positions)
        return MocapClips(moved, self.action, self.clip_id, self.action_names, self.parents, self.fps)

    def without_actions(self, names: Sequence[str]) -> MocapClips:
        """The clips of every class except ``names``, relabelled ``0..A'-1`` in the remaining order."""
        for name in names:
            check_choice(name, "names (an action to drop)", "MocapClips.without_actions", self.action_names)
        kept = [a for a in self.action_names if a not in names]
        relabel = np.array([kept.index(a) if a in kept else -1 for a in self.action_names], dtype=np.int64)
        subset = self.subset(relabel[self.action] >= 0)
        return MocapClips(
            subset.positions, relabel[subset.action], subset.clip_id, tuple(kept), self.parents, self.fps
        )

    def skeleton(self) -> Skeleton:
        """A :class:`motionlab.skeleton.Skeleton` of these clips' body: :data:`JOINT_NAMES`, ``parents``
        and, as offsets, the median bone vector over all frames, seen in each frame's heading frame (x
        forward, y left, z up) and scaled to the median bone length, metres."""
        frames = np.concatenate([face_every_frame(p) for p in self.positions])
        bones = frames[:, 1:] - frames[:, np.asarray(self.parents[1:])]
        direction = np.median(bones, axis=0)
        norms = np.linalg.norm(direction, axis=-1, keepdims=True)
        offsets = np.zeros((N_JOINTS, 3))
        offsets[1:] = (
            direction / np.maximum(norms, 1e-12) * np.median(np.linalg.norm(bones, axis=-1), axis=0)[:, None]
        )
        return Skeleton(JOINT_NAMES, self.parents, offsets)


# ----------------------------------------------------------------------------------------------------
# conversions (NumPy, course frame unless said otherwise)


def y_up_to_z_up(positions: ArrayLike) -> np.ndarray:
    """Positions ``(..., 3)`` from the files' y-up axes to the course's z-up axes (a rotation; float64)."""
    array = check_array(positions, "positions", "y_up_to_z_up", trailing=(3,))
    return np.asarray(array, dtype=np.float64) @ Y_UP_TO_Z_UP.T


def heading_yaw(positions: ArrayLike) -> np.ndarray:
    """Heading ``(...,)`` (radians) of poses ``(..., 20, 3)`` (z up), from the hips and the shoulders.

    The character's left is the sum of the right-to-left hip and right-to-left shoulder vectors on the
    floor; forward is left x up. A character facing +x has yaw 0, facing +y yaw pi/2.

    Raises:
        ValueError: both vectors vanish on the floor (the heading is undefined) in some pose.
    """
    where = "heading_yaw"
    array = np.asarray(check_array(positions, "positions", where, trailing=(N_JOINTS, 3)), dtype=np.float64)
    across = (array[..., JOINT["left_hip"], :2] - array[..., JOINT["right_hip"], :2]) + (
        array[..., JOINT["left_shoulder"], :2] - array[..., JOINT["right_shoulder"], :2]
    )
    degenerate = np.linalg.norm(across, axis=-1) < 1e-9
    if degenerate.any():
        index = tuple(int(i) for i in np.argwhere(degenerate)[0])
        raise ValueError(f"{where}: hips and shoulders give no horizontal direction at pose {index}")
    return np.arctan2(-across[..., 0], across[..., 1])


def _rotate_about_z(positions: np.ndarray, yaw: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """``positions (..., T, J, 3)`` turned by ``yaw (...,)`` about the vertical through ``pivot (..., 3)``."""
    cos, sin = np.cos(yaw)[..., None, None], np.sin(yaw)[..., None, None]
    x = positions[..., 0] - pivot[..., None, None, 0]
    y = positions[..., 1] - pivot[..., None, None, 1]
    out = positions.copy()
    out[..., 0] = cos * x - sin * y + pivot[..., None, None, 0]
    out[..., 1] = sin * x + cos * y + pivot[..., None, None, 1]
    return out


def face_x(positions: ArrayLike) -> np.ndarray:
    """Clips ``(..., T, 20, 3)`` (z up) turned about the vertical through their first root so that the
    first frame faces +x (:func:`heading_yaw` 0). Float64."""
    array = np.asarray(
        check_array(positions, "positions", "face_x", trailing=(N_JOINTS, 3), min_leading=1), dtype=np.float64
    )
    first = array[..., 0, :, :]
    return _rotate_about_z(array, -heading_yaw(first), first[..., 0, :])


def face_every_frame(positions: ArrayLike) -> np.ndarray:
    """Poses ``(T, 20, 3)`` (z up), each turned about its own root's vertical to face +x and moved so that
    its root is at the origin: the body seen from its heading frame. Float64."""
    array = np.asarray(
        check_array(positions, "positions", "face_every_frame", trailing=(N_JOINTS, 3)), dtype=np.float64
    )
    local = array - array[..., :1, :]
    return _rotate_about_z(local[..., None, :, :], -heading_yaw(array), np.zeros(array.shape[:-2] + (3,)))[
        ..., 0, :, :
    ]


def first_root_at_origin(positions: ArrayLike) -> np.ndarray:
    """Clips ``(..., T, J, 3)`` moved (all three axes) so that the first frame's root is at the origin, as
    Action2Motion and ODMO do. Keeps the dtype."""
    array = check_array(positions, "positions", "first_root_at_origin", trailing=(None, 3), min_leading=1)
    return array - array[..., :1, :1, :]


def root_relative(positions: ArrayLike) -> np.ndarray:
    """Poses ``(..., J, 3)`` with each frame's root subtracted (the root becomes zero; the trajectory is
    lost). Keeps the dtype."""
    array = check_array(positions, "positions", "root_relative", trailing=(None, 3))
    return array - array[..., :1, :]


def level_floor(positions: ArrayLike, quantile: float = 0.05) -> np.ndarray:
    """A clip ``(T, J, 3)`` (z up) moved vertically so that its floor is at height 0. Float64.

    The floor is the ``quantile`` of the lowest joint's height over the frames (a low quantile rather than
    the minimum, so that a few frames of marker noise below the floor do not lift the whole clip).
    """
    where = "level_floor"
    array = np.asarray(check_array(positions, "positions", where, trailing=(None, None, 3)), dtype=np.float64)
    check_scalar(quantile, "quantile", where, minimum=0, maximum=1)
    floor = np.quantile(array[..., 2].min(axis=-1), quantile)
    return array - np.array([0.0, 0.0, floor])


# ----------------------------------------------------------------------------------------------------
# ODMO's protocol


@dataclass(frozen=True)
class Windows:
    """One fixed-length window per clip.

    Attributes:
        positions: ``(N, L, J, 3)`` float32, metres, z up, each window's first root at the origin.
        action: ``(N,)`` int64 class of each window.
        clip: ``(N,)`` int64 index of the clip it was cut from.
        start: ``(N,)`` int64 first frame of the window in its clip.
        n_real: ``(N,)`` int64 frames taken from the clip; the rest (``L - n_real``) repeat its last frame.
    """

    positions: np.ndarray
    action: np.ndarray
    clip: np.ndarray
    start: np.ndarray
    n_real: np.ndarray


def odmo_clips(clips: MocapClips) -> MocapClips:
    """ODMO's benchmark set: every class but :data:`ODMO_DROPPED` (on the full data: 970 clips, 7 classes)."""
    return clips.without_actions(ODMO_DROPPED)


def random_windows(clips: MocapClips, length: int = 100, rng: RngLike = 0) -> Windows:
    """One random ``length``-frame window of every clip, as ODMO trains and evaluates.

    A clip of ``T >= length`` frames gives frames ``s .. s + length - 1`` with ``s`` uniform in
    ``0 .. T - length`` (Action2Motion's sampler never draws the last start, ``T - length``; here it can);
    a shorter clip gives all its frames followed by copies of its last frame. Every window is then moved
    so that its first frame's root is at the origin.
    """
    where = "random_windows"
    check_scalar(length, "length", where, kind=numbers.Integral, minimum=1)
    generator = as_rng(rng, where)
    if clips.n_clips == 0:
        raise ValueError(f"{where}: there are no clips")
    lengths = clips.lengths
    starts = np.array([generator.integers(0, max(t - length, 0) + 1) for t in lengths], dtype=np.int64)
    n_real = np.minimum(lengths, length)
    out = np.empty((clips.n_clips, length) + clips.positions[0].shape[1:], dtype=np.float32)
    for i, (positions, start, n) in enumerate(zip(clips.positions, starts, n_real)):
        out[i, :n] = positions[start : start + n]
        out[i, n:] = positions[start + n - 1]
    return Windows(
        first_root_at_origin(out),
        clips.action.copy(),
        np.arange(clips.n_clips, dtype=np.int64),
        starts,
        n_real,
    )


def stratified_indices(action: ArrayLike, n: int, rng: RngLike = 0) -> np.ndarray:
    """``n`` clip indices ``(n,)`` whose classes are in proportion to ``action (N,)``.

    Class ``c`` gets ``n * N_c / N`` clips rounded by largest remainder (so the counts sum to ``n``), drawn
    without replacement from its clips while they last and cycling through a fresh shuffle after that.
    """
    where = "stratified_indices"
    labels = as_labels(action, "action", where)
    check_scalar(n, "n", where, kind=numbers.Integral, minimum=1)
    generator = as_rng(rng, where)
    classes, sizes = np.unique(labels, return_counts=True)
    share = n * sizes / sizes.sum()
    counts = np.floor(share).astype(np.int64)
    counts[np.argsort(-(share - counts), kind="stable")[: n - counts.sum()]] += 1
    picked = []
    for value, count in zip(classes, counts):
        members = np.nonzero(labels == value)[0]
        rounds = -(-count // members.size)
        order = (
            np.concatenate([generator.permutation(members) for _ in range(rounds)]) if count else members[:0]
        )
        picked.append(order[:count])
    return generator.permutation(np.concatenate(picked))


def split_clips(
    clips: MocapClips, test_share: float = 0.2, rng: RngLike = 0
) -> tuple[MocapClips, MocapClips]:
    """A stratified train/test split: ``round(test_share * N_c)`` clips of every class ``c`` (at least one,
    at most ``N_c - 1``) go to the test set, drawn at random. Returns ``(train, test)``, each in the original
    clip order."""
    where = "split_clips"
    check_scalar(
        test_share, "test_share", where, minimum=0, maximum=1, include_minimum=False, include_maximum=False
    )
    generator = as_rng(rng, where)
    test = np.zeros(clips.n_clips, dtype=bool)
    for value in np.unique(clips.action):
        members = np.flatnonzero(clips.action == value)
        if members.size < 2:
            raise ValueError(
                f"{where}: class {clips.action_names[value]} has {members.size} clip; a split needs 2"
            )
        count = min(max(round(test_share * members.size), 1), members.size - 1)
        test[generator.choice(members, size=count, replace=False)] = True
    return clips.subset(~test), clips.subset(test)


# ----------------------------------------------------------------------------------------------------
# reading


@dataclass(frozen=True)
class _Raw:
    """What every source yields before the checks: positions per clip, metres, y up."""

    positions: list[np.ndarray]
    action: list[object]
    clip_id: list[str]
    action_names: tuple[str, ...]
    parents: tuple[int, ...]
    where: str


def _open_npz(path: Path, keys: Sequence[str]) -> dict[str, np.ndarray]:
    """Every array of the archive ``path``; ``ValueError`` if it is unreadable or lacks one of ``keys``."""
    try:
        with np.load(path, allow_pickle=False) as archive:
            arrays = {key: archive[key] for key in archive.files}
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
        raise ValueError(f"{path} is not a readable .npz archive ({exc})") from exc
    missing = [key for key in keys if key not in arrays]
    if missing:
        raise ValueError(f"{path}: missing arrays {missing} (has {sorted(arrays)})")
    return arrays


def _decode_positions(arrays: dict[str, np.ndarray], where: str) -> list[np.ndarray]:
    """The compact copy's clips ``(T_i, J, 3)`` float64, metres: cumulative sums of the int16 steps."""
    delta, lengths = arrays["positions_delta"], arrays["clip_length"]
    if delta.ndim != 3 or delta.shape[2] != 3 or delta.dtype.kind != "i":
        raise ValueError(f"{where}: positions_delta must be an integer array (F, J, 3), got {delta.shape}")
    clips = _split(delta, lengths, np.cumsum(lengths) - lengths, where)
    quantum = float(arrays["quantum"])
    return [np.cumsum(c, axis=0, dtype=np.int64) * quantum for c in clips]


def _parents_of(arrays: dict[str, np.ndarray], where: str) -> tuple[int, ...]:
    """Parents from the archive's ``kinematic_chain`` strings (e.g. ``"[0, 1, 2, 3]"``); :data:`PARENTS`
    when it has none."""
    if "kinematic_chain" not in arrays:
        return PARENTS
    try:
        chains = [[int(j) for j in ast.literal_eval(str(chain))] for chain in arrays["kinematic_chain"]]
        return parents_from_chains(chains, N_JOINTS)
    except (ValueError, SyntaxError, TypeError) as exc:
        raise ValueError(f"{where}: kinematic_chain is not a list of joint chains ({exc})") from exc


def _split(flat: np.ndarray, lengths: np.ndarray, starts: np.ndarray, where: str) -> list[np.ndarray]:
    lengths = np.asarray(lengths)
    starts = np.asarray(starts)
    if lengths.ndim != 1 or starts.shape != lengths.shape or lengths.dtype.kind not in "iu":
        raise ValueError(f"{where}: clip_start and clip_length must be integer arrays of one shape")
    if lengths.size and ((starts < 0).any() or (lengths < 0).any() or (starts + lengths > len(flat)).any()):
        raise ValueError(f"{where}: clip_start / clip_length point outside positions ({len(flat)} frames)")
    return [flat[s : s + t] for s, t in zip(starts.tolist(), lengths.tolist())]


def _read_original(path: Path) -> _Raw:
    arrays = _open_npz(path, _ORIGINAL_KEYS)
    flat = arrays["positions"]
    if flat.ndim != 3 or flat.shape[2] != 3 or flat.dtype.kind != "f":
        raise ValueError(f"{path}: positions must be a float array (F, J, 3), got {flat.dtype} {flat.shape}")
    clips = _split(flat, arrays["clip_length"], arrays["clip_start"], str(path))
    return _Raw(
        [c.astype(np.float64) * CMU_SCALE for c in clips],
        arrays["action"].tolist(),
        [str(c) for c in arrays["clip_id"]],
        tuple(str(a) for a in arrays["action_names"]),
        _parents_of(arrays, str(path)),
        str(path),
    )


def _sha256(array: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(array).tobytes()).hexdigest()


def _read_compact(folder: Path, verify: bool) -> _Raw:
    path, record_path = folder / COMPACT_FILE, folder / CHECKSUM_FILE
    arrays = _open_npz(path, _COMPACT_KEYS)
    if verify:
        try:
            expected = json.loads(record_path.read_text())["sha256"]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise ValueError(f"{record_path}: cannot read the checksums ({exc!r})") from exc
        for key in sorted(set(expected) | set(arrays)):
            got = _sha256(arrays[key]) if key in arrays else "missing"
            if got != expected.get(key):
                raise ValueError(
                    f"{path}: array '{key}' does not match its SHA-256 in {record_path} (expected "
                    f"{expected.get(key)}, got {got}); the file is damaged or changed: regenerate it with "
                    "python -m motionlab.data.cmu_mocap --source <original .npz> --out data_real"
                )
    return _Raw(
        _decode_positions(arrays, str(path)),
        arrays["action"].tolist(),
        [str(c) for c in arrays["clip_id"]],
        tuple(str(a) for a in arrays["action_names"]),
        _parents_of(arrays, str(path)),
        str(path),
    )


def _label(value: str) -> int | str:
    """A ``pose_clip.csv`` action: an integer index if it reads as one, else the name itself."""
    text = value.strip()
    try:
        return int(float(text)) if float(text).is_integer() else text
    except ValueError:
        names = {name.lower(): i for i, name in enumerate(ACTION_NAMES)}
        return names.get(text.lower(), text)


def _read_folder(table: Path) -> _Raw:
    folder = table.parent
    npy_folder = folder / "mocap_3djoints" if (folder / "mocap_3djoints").is_dir() else folder
    try:
        with open(table, newline="", encoding="utf-8") as handle:
            rows = list(csv.DictReader(handle))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ValueError(f"{table}: cannot read the clip table ({exc})") from exc
    if not rows or not {"motion", "action_type"} <= set(rows[0]):
        header = sorted(rows[0]) if rows else []
        raise ValueError(f"{table}: needs the columns 'motion' and 'action_type', got {header}")
    positions, action, clip_id = [], [], []
    for row in rows:
        motion = (row["motion"] or "").strip()
        if not motion and not (row["action_type"] or "").strip():
            continue  # a blank line
        path = npy_folder / f"{motion}.npy"
        try:
            clip = np.load(path, allow_pickle=False)
        except FileNotFoundError as exc:
            raise ValueError(f"{table}: clip {motion}: no file {path}") from exc
        except (OSError, ValueError, EOFError) as exc:
            raise ValueError(f"{table}: clip {motion}: {path} is not a readable .npy array ({exc})") from exc
        if clip.dtype.kind not in "fiu":
            raise ValueError(f"{table}: clip {motion}: {path} holds {clip.dtype}, not numbers")
        positions.append(clip.astype(np.float64) * CMU_SCALE)
        action.append(_label(row["action_type"] or ""))
        clip_id.append(motion)
    return _Raw(positions, action, clip_id, ACTION_NAMES, PARENTS, str(table))


def _checked(raw: _Raw, config: LoadConfig) -> MocapClips:
    """The clips in the course frame; ``ValueError`` naming the first clip the course cannot use."""
    converted = []
    labels = []
    for clip, positions, label in zip(raw.clip_id, raw.positions, raw.action):
        prefix = f"{raw.where}: clip {clip}"
        if isinstance(label, str) or not 0 <= int(label) < len(raw.action_names):
            raise ValueError(
                f"{prefix}: unknown label {label!r} (known: 0..{len(raw.action_names) - 1}, "
                f"{', '.join(raw.action_names)})"
            )
        if positions.ndim != 3 or positions.shape[1:] != (N_JOINTS, 3):
            raise ValueError(
                f"{prefix}: positions must have shape (T, {N_JOINTS}, 3), got {positions.shape} "
                f"(wrong joint count?)"
            )
        if len(positions) < config.min_frames:
            raise ValueError(f"{prefix}: too short ({len(positions)} frames, at least {config.min_frames})")
        bad = ~np.isfinite(positions)
        if bad.any():
            index = tuple(int(i) for i in np.argwhere(bad)[0])
            raise ValueError(f"{prefix}: NaN or infinite position at (frame, joint, axis) {index}")
        converted.append(y_up_to_z_up(positions).astype(np.float32))
        labels.append(int(label))
    return MocapClips(
        tuple(converted), np.array(labels, dtype=np.int64), tuple(raw.clip_id), raw.action_names, raw.parents
    )


def load_cmu_mocap(source: str | Path | None = None, config: LoadConfig | None = None) -> MocapClips:
    """The clips of ``source`` in the course frame (metres, z up), as captured (position and facing kept).

    Args:
        source: ``None`` for the compact copy in ``data_real/``; a folder holding a compact copy or a
            ``pose_clip.csv``; a ``pose_clip.csv``; or an ``.npz`` archive (compact or original layout).
        config: what to accept (:class:`LoadConfig`).

    Raises:
        FileNotFoundError: ``source`` does not exist.
        ValueError: a malformed file, a checksum mismatch, or a clip the course cannot use (too short, NaN
            or infinite, wrong joint count, unknown label), naming the file and the clip.
    """
    config = LoadConfig() if config is None else config
    if not isinstance(config, LoadConfig):
        raise TypeError(f"load_cmu_mocap: config must be a LoadConfig, got {type(config).__name__}")
    path = DATA_DIR if source is None else Path(source)
    if not path.exists():
        raise FileNotFoundError(f"load_cmu_mocap: no such file or folder {path}")
    if path.is_dir():
        if (path / COMPACT_FILE).is_file():
            raw = _read_compact(path, config.verify)
        elif (path / "pose_clip.csv").is_file():
            raw = _read_folder(path / "pose_clip.csv")
        else:
            raise ValueError(f"load_cmu_mocap: {path} holds neither {COMPACT_FILE} nor pose_clip.csv")
    elif path.suffix == ".csv":
        raw = _read_folder(path)
    elif path.name == COMPACT_FILE:
        raw = _read_compact(path.parent, config.verify)
    else:
        raw = _read_original(path)
    return _checked(raw, config)


# ----------------------------------------------------------------------------------------------------
# the compact copy


def encode_positions(clips: Sequence[np.ndarray], quantum: float = QUANTUM) -> np.ndarray:
    """Clips ``(T_i, J, 3)`` (metres) as one int16 array ``(sum T_i, J, 3)``: each clip's first frame in
    steps of ``quantum``, then the differences from frame to frame (small numbers that compress well).

    Raises:
        ValueError: a coordinate or a frame-to-frame step does not fit in int16 at this ``quantum``.
    """
    steps = [np.round(np.asarray(c, dtype=np.float64) / quantum).astype(np.int64) for c in clips]
    delta = np.concatenate([np.diff(s, axis=0, prepend=np.zeros_like(s[:1])) for s in steps])
    limit = np.iinfo(np.int16).max
    if np.abs(delta).max(initial=0) > limit:
        raise ValueError(
            f"encode_positions: values exceed int16 at quantum {quantum} m; use a larger quantum"
        )
    return delta.astype(np.int16)


def write_compact(source: Path, out: Path, quantum: float = QUANTUM) -> dict[str, object]:
    """Write the compact copy of the original archive ``source`` into folder ``out``
    (:data:`COMPACT_FILE` and :data:`CHECKSUM_FILE`); returns the checksum record.

    Deterministic: the same source gives the same arrays and checksums on every machine (rounding of
    float64 products and quotients is exact IEEE arithmetic).
    """
    raw = _read_original(source)
    arrays = {
        "positions_delta": encode_positions(raw.positions, quantum),
        "quantum": np.array(quantum),
        "clip_length": np.array([len(p) for p in raw.positions], dtype=np.int64),
        "clip_id": np.array(raw.clip_id),
        "action": np.array(raw.action, dtype=np.int64),
        "action_names": np.array(raw.action_names),
        "kinematic_chain": np.array([str(list(chain)) for chain in KINEMATIC_CHAIN]),
    }
    decoded = _decode_positions(arrays, "write_compact")
    error = max(float(np.abs(a - b).max()) for a, b in zip(decoded, raw.positions))
    record = {
        "source": {"file": source.name, "sha256": hashlib.sha256(source.read_bytes()).hexdigest()},
        "quantum_m": quantum,
        "max_abs_error_m": error,
        "sha256": {key: _sha256(value) for key, value in arrays.items()},
    }
    out.mkdir(parents=True, exist_ok=True)
    temporary = out / f".{COMPACT_FILE}.{os.getpid()}.tmp"
    try:
        with open(temporary, "wb") as handle:
            np.savez_compressed(handle, **arrays)
        os.replace(temporary, out / COMPACT_FILE)
    finally:
        temporary.unlink(missing_ok=True)
    (out / CHECKSUM_FILE).write_text(json.dumps(record, indent=2, sort_keys=True) + "\n")
    return record


def main(argv: list[str] | None = None) -> int:
    """``python -m motionlab.data.cmu_mocap --source ORIGINAL.npz --out data_real``: regenerate the compact
    copy; returns the exit status."""
    prog = "python -m motionlab.data.cmu_mocap"
    parser = argparse.ArgumentParser(prog=prog, description="Write the compact copy of the CMU MoCap data.")
    parser.add_argument("--source", required=True, type=Path, help="the original archive cmu_mocap_a2m.npz")
    parser.add_argument("--out", type=Path, default=DATA_DIR, help="output folder (default data_real/)")
    args = parser.parse_args(argv)

    def run() -> int:
        record = write_compact(args.source, args.out)
        size = (args.out / COMPACT_FILE).stat().st_size / 1e6
        print(
            f"wrote {args.out / COMPACT_FILE} ({size:.1f} MB, "
            f"largest error {record['max_abs_error_m']:.2e} m)"
        )
        return 0

    return arguments.run(prog, run)


if __name__ == "__main__":
    sys.exit(main())
