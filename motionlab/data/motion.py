"""The :class:`Motion` container: one clip of skeletal motion as local rotations plus a moving root.

A ``Motion`` holds everything needed to pose a skeleton frame by frame and to write it back to a
BVH file (:mod:`motionlab.data.bvh`):

- ``joint_names`` (J names) and ``parents`` (J ints, ``-1`` for the root, which is joint 0, and
  ``parents[j] < j`` for every other joint, so a single pass in index order visits parents first);
- ``offsets`` ``(J, 3)``: each joint's rest translation relative to its parent;
- ``rotations`` ``(T, J, 4)``: local rotations as unit quaternions, w first, each relative to the
  parent's frame;
- ``root_positions`` ``(T, 3)``: the root's translation per frame;
- ``fps``: frames per second;
- optional BVH details kept for writing back: ``channels`` (per joint, the BVH channel names in file
  order), ``end_sites`` (``(joint index, offset)`` pairs of the BVH ``End Site`` leaves) and
  ``joint_translations`` ``(T, J, 3)`` for files whose non-root joints carry position channels.

Everything is in the motionlab world frame (z up, right-handed, a character facing +x) and in one
length unit (metres for synthetic data; BVH files load in file units unless a scale is given).
All tensors share one floating dtype: the dtype of ``rotations`` (the BVH loader uses float64).
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import torch

from motionlab.skeleton import forward_kinematics
from motionlab.validation import Checked, check_finite, check_scalar, real

#: BVH channel names (canonical spelling); a joint lists a subset of them, each at most once.
POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
ROTATION_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")
CHANNEL_NAMES = POSITION_CHANNELS + ROTATION_CHANNELS

#: How far a quaternion's norm may be from 1 before it is rejected as not a rotation.
UNIT_NORM_TOLERANCE = 1e-3

EndSite = tuple[int, tuple[float, float, float]]


def _as_tensor(value: Any, name: str, dtype: torch.dtype | None = None) -> torch.Tensor:
    """``value`` as a floating tensor (``dtype``, or its own float dtype, or float32), rejecting NaN/inf."""
    if isinstance(value, torch.Tensor):
        tensor = value.detach()
    else:
        try:
            array = np.asarray(value)
        except ValueError as exc:
            raise ValueError(f"Motion.{name}: not a rectangular numeric array ({exc})") from exc
        if array.dtype.kind not in "fiub":
            raise TypeError(f"Motion.{name}: not a numeric array (dtype {array.dtype})")
        tensor = torch.tensor(array)  # a copy (NumPy arrays may be read-only, torch wants writable memory)
    if dtype is not None:
        tensor = tensor.to(dtype)
    elif not tensor.is_floating_point():
        tensor = tensor.to(torch.float32)
    return check_finite(tensor, name, "Motion")


def _check_shape(tensor: torch.Tensor, name: str, shape: tuple[int | None, ...], meaning: str) -> None:
    ok = tensor.dim() == len(shape) and all(s is None or s == d for s, d in zip(shape, tensor.shape))
    if not ok:
        raise ValueError(f"Motion.{name}: expected shape {meaning}, got {tuple(tensor.shape)}")


def _check_names(joint_names: Sequence[str]) -> tuple[str, ...]:
    names = tuple(joint_names)
    if not names:
        raise ValueError("Motion.joint_names: a motion needs at least one joint")
    for j, name in enumerate(names):
        if not isinstance(name, str):
            raise TypeError(f"Motion.joint_names[{j}]: {name!r} is not a string")
        if not name or any(c.isspace() or c in "{}" for c in name):
            raise ValueError(
                f"Motion.joint_names[{j}]: {name!r} is not a valid joint name "
                "(non-empty, no whitespace, no braces)"
            )
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise ValueError(f"Motion.joint_names: joint name {dup!r} appears more than once")
    return names


def _check_parents(parents: Sequence[int] | torch.Tensor | np.ndarray, num_joints: int) -> tuple[int, ...]:
    values = parents.tolist() if isinstance(parents, (torch.Tensor, np.ndarray)) else list(parents)
    if len(values) != num_joints:
        raise ValueError(f"Motion.parents: expected {num_joints} entries (one per joint), got {len(values)}")
    out = []
    for j, p in enumerate(values):
        out.append(int(check_scalar(p, f"parents[{j}]", "Motion", kind=numbers.Integral)))
    if out[0] != -1:
        raise ValueError(f"Motion.parents[0]: joint 0 must be the root (parent -1), got {out[0]}")
    for j, p in enumerate(out[1:], start=1):
        if not 0 <= p < j:
            raise ValueError(
                f"Motion.parents[{j}]: must be the index of an earlier joint (0..{j - 1}), got {p}"
            )
    return tuple(out)


def _check_channels(channels: Sequence[Sequence[str]], num_joints: int) -> tuple[tuple[str, ...], ...]:
    out = tuple(tuple(c) for c in channels)
    if len(out) != num_joints:
        raise ValueError(f"Motion.channels: expected {num_joints} entries (one per joint), got {len(out)}")
    for j, names in enumerate(out):
        unknown = [c for c in names if c not in CHANNEL_NAMES]
        if unknown:
            raise ValueError(f"Motion.channels[{j}]: unknown channel {unknown[0]!r} (known: {CHANNEL_NAMES})")
        if len(set(names)) != len(names):
            raise ValueError(f"Motion.channels[{j}]: a channel is listed twice in {names}")
    return out


def _check_end_sites(end_sites: Sequence[EndSite], num_joints: int) -> tuple[EndSite, ...]:
    out = []
    for k, site in enumerate(end_sites):
        try:
            joint, offset = site
            joint = int(joint)
            offset = tuple(float(v) for v in offset)
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"Motion.end_sites[{k}]: expected (joint index, (x, y, z)), got {site!r}"
            ) from exc
        if not 0 <= joint < num_joints or len(offset) != 3 or not all(np.isfinite(offset)):
            raise ValueError(
                f"Motion.end_sites[{k}]: joint index must be in 0..{num_joints - 1} and the "
                f"offset three finite numbers, got {site!r}"
            )
        out.append((joint, offset))
    return tuple(out)


@dataclass(frozen=True, eq=False, repr=False)
class Motion(Checked):
    """One motion clip: local joint rotations, root translation and the skeleton they pose.

    Args:
        joint_names: J unique names (no whitespace or braces, so that they survive a BVH file).
        parents: J parent indices; ``parents[0] == -1`` and ``0 <= parents[j] < j`` otherwise.
        offsets: ``(J, 3)`` rest translation of each joint relative to its parent (the root's entry is
            its rest position, used only by joints without position data).
        rotations: ``(T, J, 4)`` local rotations, unit quaternions with w first (T >= 1). Norms within
            :data:`UNIT_NORM_TOLERANCE` of 1 are renormalised, others rejected.
        root_positions: ``(T, 3)`` root translation per frame.
        fps: frames per second (> 0).
        channels: optional per-joint BVH channel names in file order (see :data:`CHANNEL_NAMES`).
        end_sites: optional ``(joint index, (x, y, z))`` BVH End Site offsets, relative to that joint.
        joint_translations: optional ``(T, J, 3)`` per-frame translation of every joint relative to its
            parent, for skeletons whose non-root joints move (BVH position channels). Row 0 must equal
            ``root_positions``. ``None`` means each non-root joint stays at its offset.

    Raises:
        TypeError: a field of the wrong type (a non-numeric array, a non-integer parent, a bool fps...).
        ValueError: naming the field and what is wrong (shape, NaN, non-unit quaternion, bad tree...).
    """

    joint_names: tuple[str, ...]
    parents: tuple[int, ...]
    offsets: torch.Tensor
    rotations: torch.Tensor
    root_positions: torch.Tensor
    fps: float = real(above=0)
    channels: tuple[tuple[str, ...], ...] | None = None
    end_sites: tuple[EndSite, ...] | None = None
    joint_translations: torch.Tensor | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        names = _check_names(self.joint_names)
        num_joints = len(names)
        set_field = object.__setattr__
        set_field(self, "joint_names", names)
        set_field(self, "parents", _check_parents(self.parents, num_joints))

        rotations = _as_tensor(self.rotations, "rotations")
        _check_shape(rotations, "rotations", (None, num_joints, 4), f"(T, {num_joints}, 4)")
        if rotations.shape[0] < 1:
            raise ValueError("Motion.rotations: a motion needs at least one frame, got T = 0")
        norms = rotations.norm(dim=-1)
        if ((norms - 1).abs() > UNIT_NORM_TOLERANCE).any():
            frame, joint = torch.nonzero((norms - 1).abs() > UNIT_NORM_TOLERANCE)[0].tolist()
            raise ValueError(
                f"Motion.rotations: frame {frame}, joint {joint} ({names[joint]}) is not a unit "
                f"quaternion (norm {norms[frame, joint].item():.6g})"
            )
        set_field(self, "rotations", rotations / norms.unsqueeze(-1))
        dtype = rotations.dtype
        num_frames = rotations.shape[0]

        offsets = _as_tensor(self.offsets, "offsets", dtype)
        _check_shape(offsets, "offsets", (num_joints, 3), f"({num_joints}, 3)")
        set_field(self, "offsets", offsets)
        root = _as_tensor(self.root_positions, "root_positions", dtype)
        _check_shape(root, "root_positions", (num_frames, 3), f"({num_frames}, 3) (T from rotations)")
        set_field(self, "root_positions", root)

        set_field(self, "fps", float(self.fps))

        if self.channels is not None:
            set_field(self, "channels", _check_channels(self.channels, num_joints))
        if self.end_sites is not None:
            set_field(self, "end_sites", _check_end_sites(self.end_sites, num_joints))
        if self.joint_translations is not None:
            moving = _as_tensor(self.joint_translations, "joint_translations", dtype)
            _check_shape(
                moving, "joint_translations", (num_frames, num_joints, 3), f"({num_frames}, {num_joints}, 3)"
            )
            if not torch.equal(moving[:, 0], root):
                raise ValueError("Motion.joint_translations: row 0 (the root) must equal root_positions")
            set_field(self, "joint_translations", moving)

    def __repr__(self) -> str:
        seconds = (self.num_frames - 1) / self.fps
        return (
            f"Motion({self.num_joints} joints, {self.num_frames} frames at {self.fps:g} fps = "
            f"{seconds:.2f} s, "
            f"root {self.joint_names[0]!r}, {self.rotations.dtype})"
        )

    @property
    def num_frames(self) -> int:
        """T, the number of frames."""
        return self.rotations.shape[0]

    @property
    def num_joints(self) -> int:
        """J, the number of joints."""
        return len(self.joint_names)

    def local_translations(self) -> torch.Tensor:
        """``(T, J, 3)`` translation of each joint relative to its parent (the root: its world position)."""
        if self.joint_translations is not None:
            return self.joint_translations
        out = self.offsets.expand(self.num_frames, -1, -1).clone()
        out[:, 0] = self.root_positions
        return out

    def global_positions(self) -> torch.Tensor:
        """``(T, J, 3)`` world positions of the joints by forward kinematics.

        ``p_j = p_parent + R_parent · t_j`` and ``R_j = R_parent · R_local_j`` with the per-frame
        translations of :meth:`local_translations` (:func:`motionlab.skeleton.forward_kinematics`).
        """
        return forward_kinematics(
            self.rotations, self.root_positions, self.local_translations(), self.parents
        )[0]

    def scaled(self, factor: float) -> Motion:
        """The same motion with every length (offsets, translations, end sites) multiplied by ``factor``."""
        factor = float(check_scalar(factor, "factor", "Motion.scaled", minimum=0, include_minimum=False))
        return replace(
            self,
            offsets=self.offsets * factor,
            root_positions=self.root_positions * factor,
            end_sites=None
            if self.end_sites is None
            else tuple((j, tuple(v * factor for v in off)) for j, off in self.end_sites),
            joint_translations=None if self.joint_translations is None else self.joint_translations * factor,
        )

    def __getitem__(self, frames: slice) -> Motion:
        """Frames ``frames`` (a slice with a positive step) as a new ``Motion``; the step divides fps."""
        if not isinstance(frames, slice):
            raise TypeError(
                f"Motion can only be sliced by frames (motion[a:b:step]), got {type(frames).__name__}"
            )
        step = 1 if frames.step is None else frames.step
        if step < 1:
            raise ValueError(f"Motion slice step must be a positive integer, got {frames.step!r}")
        index = torch.arange(self.num_frames)[frames]
        if index.numel() == 0:
            raise ValueError(f"Motion slice {frames} selects no frames of {self.num_frames}")
        return replace(
            self,
            rotations=self.rotations[index],
            root_positions=self.root_positions[index],
            fps=self.fps / step,
            joint_translations=None if self.joint_translations is None else self.joint_translations[index],
        )

    def resample(self, fps: float) -> Motion:
        """The motion at another frame rate, by linear interpolation between the two nearest frames.

        Translations are interpolated linearly; rotations by normalised linear interpolation of the
        quaternions (nlerp: the second quaternion's sign is flipped onto the first one's hemisphere,
        the blend is renormalised). Between frames that differ by a few degrees, as at mocap rates,
        nlerp and slerp agree to well below a degree. The new clip starts at the first frame and keeps
        every sample time ``k / fps`` that lies within the original duration ``(T - 1) / self.fps``.
        """
        fps = float(check_scalar(fps, "fps", "Motion.resample", minimum=0, include_minimum=False))
        ratio = self.fps / fps
        count = int(np.floor((self.num_frames - 1) / ratio + 1e-9)) + 1
        times = torch.arange(count, dtype=torch.float64) * ratio
        lower = times.floor().long().clamp(max=self.num_frames - 1)
        upper = (lower + 1).clamp(max=self.num_frames - 1)
        weight = (times - lower).to(self.rotations.dtype)

        def lerp(x: torch.Tensor) -> torch.Tensor:
            w = weight.view(-1, *([1] * (x.dim() - 1)))
            return x[lower] * (1 - w) + x[upper] * w

        q0, q1 = self.rotations[lower], self.rotations[upper]
        q1 = torch.where((q0 * q1).sum(-1, keepdim=True) < 0, -q1, q1)
        w = weight.view(-1, 1, 1)
        blend = q0 * (1 - w) + q1 * w
        return replace(
            self,
            rotations=blend / blend.norm(dim=-1, keepdim=True),
            root_positions=lerp(self.root_positions),
            fps=fps,
            joint_translations=None if self.joint_translations is None else lerp(self.joint_translations),
        )

    def reorder(self, joint_names: Sequence[str]) -> Motion:
        """The same motion with its joints in the order ``joint_names`` (a permutation of the current names).

        Useful after a BVH round trip: BVH stores joints depth-first, so a skeleton in another order
        (like SMPL's) comes back depth-first; ``motion.reorder(original_names)`` restores the order.
        The new order must still list every parent before its children, with the root first.
        """
        names = tuple(joint_names)
        if sorted(names) != sorted(self.joint_names) or len(set(names)) != len(names):
            raise ValueError(
                f"Motion.reorder: joint_names must be a permutation of {self.joint_names}, got {names}"
            )
        old_index = [self.joint_names.index(n) for n in names]
        new_index = {old: new for new, old in enumerate(old_index)}
        parents = [-1 if self.parents[o] < 0 else new_index[self.parents[o]] for o in old_index]
        return replace(
            self,
            joint_names=names,
            parents=parents,
            offsets=self.offsets[old_index],
            rotations=self.rotations[:, old_index],
            channels=None if self.channels is None else [self.channels[o] for o in old_index],
            end_sites=None if self.end_sites is None else [(new_index[j], off) for j, off in self.end_sites],
            joint_translations=None
            if self.joint_translations is None
            else self.joint_translations[:, old_index],
        )
