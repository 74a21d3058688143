"""Read and write BVH (Biovision Hierarchy) motion-capture files.

A BVH file has two parts. ``HIERARCHY`` describes the skeleton: a ``ROOT`` joint and nested ``JOINT``
blocks, each with an ``OFFSET`` (rest translation from its parent) and ``CHANNELS`` (which values each
frame carries for it), and ``End Site`` blocks that only mark where a leaf bone ends. ``MOTION`` gives
``Frames:``, ``Frame Time:`` (seconds) and then one line per frame with every joint's channel values
in hierarchy order.

Conventions this module follows (and how it maps them to motionlab's):

- **Rotation channels** are applied in the order listed, as intrinsic rotations, angles in degrees:
  ``Zrotation Xrotation Yrotation`` with values ``a b c`` is ``R = Rz(a) · Rx(b) · Ry(c)``, which is
  ``scipy.spatial.transform.Rotation.from_euler("ZXY", [a, b, c], degrees=True)``. Each joint may use
  its own order, and any subset of the three axes.
- **Position channels** replace the matching component of the joint's ``OFFSET`` for that frame (the
  convention of the Biovision/MotionBuilder exports; usually only the root has them).
- **Local transform** of a joint: translate by its (offset or channel) translation, then rotate, so
  ``p_j = p_parent + R_parent · t_j`` and ``R_j = R_parent · R_local_j``.
- **Axes**: BVH files are y up and their characters face +z (left is +x). motionlab is z up and faces
  +x (left is +y). The loader applies the fixed proper rotation :data:`FILE_TO_WORLD`, 120° about
  ``(1, 1, 1)/√3``, i.e. ``(x, y, z)_file ↦ (z, x, y)_world``: file x → world y (left stays left),
  file y → world z (up stays up), file z → world x (forward becomes +x). It equals +90° about x
  (y up becomes z up) followed by +90° about z. Because it only permutes axes, the conversion is
  exact. Offsets, translations and local rotations are all conjugated by it, so the whole animation is
  rotated rigidly. The writer applies the inverse, so files it writes are y up and face +z, which is
  what Blender's and MotionBuilder's BVH importers expect.
- **Units** stay those of the file unless ``scale`` is given. :data:`CMU_SCALE` converts the CMU
  database (and its common BVH conversion) to metres.

The CMU sample ``cmu_12_01_walk.bvh`` (31 joints, 524 frames at 120 fps) walks along file +z, which is
world +x after loading; its first frame is the T-pose that the BVH conversion adds in front of the take.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from decimal import Decimal
from pathlib import Path

import numpy as np
import torch

from motionlab.data.motion import (
    CHANNEL_NAMES,
    POSITION_CHANNELS,
    ROTATION_CHANNELS,
    Motion,
)
from motionlab.geometry import quat_mul, quat_to_euler

#: Metres per CMU length unit: the CMU ASF files use ``length 0.45`` with inch data, so one unit is
#: (1 / 0.45) inches = 0.0254 / 0.45 m ≈ 0.056444 m (the factor given in the CMU database FAQ).
CMU_SCALE = 0.0254 / 0.45

#: The y-up → z-up rotation as a quaternion (w first): 120° about (1, 1, 1)/√3, (x, y, z) ↦ (z, x, y).
FILE_TO_WORLD = (0.5, 0.5, 0.5, 0.5)
_FILE_TO_WORLD_AXES = [2, 0, 1]  # world[..., i] = file[..., _FILE_TO_WORLD_AXES[i]]
_WORLD_TO_FILE_AXES = [1, 2, 0]  # file[..., i] = world[..., _WORLD_TO_FILE_AXES[i]]
_QUAT_FILE_TO_WORLD = [0, 3, 1, 2]  # the same permutation on a quaternion's vector part (w first)
_QUAT_WORLD_TO_FILE = [0, 2, 3, 1]

_NUMBER_RE = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_COUNT_RE = re.compile(r"[0-9]+")
_FRAMES_RE = re.compile(r"frames\s*:?\s*(\S+)", re.IGNORECASE)
_FRAME_TIME_RE = re.compile(r"frame\s*time\s*:?\s*(\S+)", re.IGNORECASE)
_CHANNEL_BY_LOWER = {name.lower(): name for name in CHANNEL_NAMES}
_AXIS_INDEX = {"X": 0, "Y": 1, "Z": 2}


class BVHError(ValueError):
    """A malformed BVH file; the message names the file, the line number and what is wrong."""

    def __init__(self, message: str, line: int | None = None, source: str | None = None) -> None:
        self.line = line
        where = ", ".join(part for part in (source, None if line is None else f"line {line}") if part)
        super().__init__(f"{where}: {message}" if where else message)


def _shorten(token: str, limit: int = 40) -> str:
    return repr(token if len(token) <= limit else token[:limit] + "...")


def _end_of_file(lines: list[str], expected: str, source: str) -> BVHError:
    """The error for a file that stops early, at its last non-blank line."""
    last = next((i for i in range(len(lines) - 1, -1, -1) if lines[i].strip()), 0)
    return BVHError(f"unexpected end of file, expected {expected}", last + 1, source)


# ----------------------------------------------------------------------------------------- reading


@dataclass
class _Hierarchy:
    """The parsed HIERARCHY section, in file units and file axes."""

    names: list[str] = field(default_factory=list)
    parents: list[int] = field(default_factory=list)
    offsets: list[tuple[float, float, float]] = field(default_factory=list)
    channels: list[tuple[str, ...]] = field(default_factory=list)
    end_sites: list[tuple[int, tuple[float, float, float]]] = field(default_factory=list)


class _TokenReader:
    """Whitespace-separated tokens of the lines of a file, with their 1-based line numbers."""

    def __init__(self, lines: list[str], source: str) -> None:
        self.lines = lines
        self.source = source
        self.line_index = 0  # the line of the current tokens (0-based)
        self.tokens: list[str] = lines[0].split()
        self.position = 0

    def error(self, message: str, line: int | None = None) -> BVHError:
        return BVHError(message, self.line_index + 1 if line is None else line, self.source)

    def _fill(self) -> bool:
        while self.position >= len(self.tokens):
            if self.line_index + 1 >= len(self.lines):
                return False
            self.line_index += 1
            self.tokens, self.position = self.lines[self.line_index].split(), 0
        return True

    def peek(self) -> str | None:
        return self.tokens[self.position] if self._fill() else None

    def next(self, what: str) -> str:
        if not self._fill():
            raise _end_of_file(self.lines, what, self.source)
        token = self.tokens[self.position]
        self.position += 1
        return token

    def expect(self, keyword: str) -> None:
        token = self.next(repr(keyword))
        if token.lower() != keyword.lower():
            raise self.error(f"expected {keyword!r}, found {_shorten(token)}")

    def number(self, what: str, line: int) -> float:
        """The next token as a finite number; errors name ``line`` (where the statement began)."""
        token = self.next(what)
        if not _NUMBER_RE.fullmatch(token):
            raise self.error(f"expected a number for {what}, found {_shorten(token)}", line)
        value = float(token)
        if not np.isfinite(value):
            raise self.error(f"{what} {_shorten(token)} is out of range", line)
        return value

    def rest_of_line(self) -> list[str]:
        """The remaining tokens on the current line (the reader then moves past them)."""
        rest = self.tokens[self.position :]
        self.position = len(self.tokens)
        return rest


def _read_joint_header(reader: _TokenReader, keyword: str) -> str:
    """The name after ROOT/JOINT: the rest of the line, spaces joined by '_' (as Blender does)."""
    line = reader.line_index + 1
    words = reader.rest_of_line()
    if words and words[-1] == "{":
        words.pop()
        reader.position -= 1  # leave the brace for the caller
    if not words or any(c in "{}" for w in words for c in w):
        raise reader.error(f"{keyword} needs a joint name, found {_shorten(' '.join(words))}", line)
    return "_".join(words)


def _read_channels(reader: _TokenReader) -> tuple[str, ...]:
    line = reader.line_index + 1
    count_token = reader.next("a channel count")
    if not _COUNT_RE.fullmatch(count_token) or len(count_token) > 2 or int(count_token) > len(CHANNEL_NAMES):
        raise reader.error(
            f"CHANNELS count must be an integer from 0 to {len(CHANNEL_NAMES)}, "
            f"found {_shorten(count_token)}",
            line,
        )
    names = []
    for k in range(int(count_token)):
        token = reader.next(f"channel {k + 1} of {count_token}")
        name = _CHANNEL_BY_LOWER.get(token.lower())
        if name is None:
            if token.upper() in ("JOINT", "END", "}", "{", "OFFSET", "CHANNELS", "MOTION"):
                raise reader.error(f"CHANNELS declares {count_token} channels but names only {k}", line)
            raise reader.error(f"unknown channel {_shorten(token)} (known: {', '.join(CHANNEL_NAMES)})")
        if name in names:
            raise reader.error(f"channel {name} listed twice")
        names.append(name)
    return tuple(names)


def _read_offset(reader: _TokenReader) -> tuple[float, float, float]:
    """The three numbers after an OFFSET keyword just read."""
    line = reader.line_index + 1
    return (reader.number("OFFSET x", line), reader.number("OFFSET y", line), reader.number("OFFSET z", line))


def _parse_hierarchy(reader: _TokenReader) -> _Hierarchy:
    """Parse from ``HIERARCHY`` to the root's closing brace (iteratively: deep nesting cannot overflow)."""
    tree = _Hierarchy()
    reader.expect("HIERARCHY")
    reader.expect("ROOT")
    stack: list[int] = []
    seen_names: set[str] = set()
    keyword = "ROOT"
    while True:
        # A joint block: name, '{', OFFSET and CHANNELS (either order), then children and '}'.
        name_line = reader.line_index + 1
        name = _read_joint_header(reader, keyword)
        if name in seen_names:
            raise reader.error(f"joint name {name!r} is used twice", name_line)
        reader.expect("{")
        offset = channels = None
        while reader.peek() is not None and reader.peek().upper() in ("OFFSET", "CHANNELS"):
            token = reader.next("OFFSET or CHANNELS").upper()
            if (offset if token == "OFFSET" else channels) is not None:
                raise reader.error(f"joint {name!r} has two {token} lines")
            if token == "OFFSET":
                offset = _read_offset(reader)
            else:
                channels = _read_channels(reader)
        if offset is None:
            raise reader.error(f"joint {name!r} has no OFFSET", name_line)
        if channels is None:
            raise reader.error(f"joint {name!r} has no CHANNELS", name_line)
        tree.names.append(name)
        seen_names.add(name)
        tree.parents.append(stack[-1] if stack else -1)
        tree.offsets.append(offset)
        tree.channels.append(channels)
        stack.append(len(tree.names) - 1)

        # Children until this joint's block closes; a new JOINT restarts the outer loop.
        while True:
            token = reader.next(f"JOINT, End Site or '}}' inside joint {tree.names[stack[-1]]!r}")
            upper = token.upper()
            if upper == "JOINT":
                keyword = "JOINT"
                break
            if upper == "END":
                reader.expect("Site")
                reader.expect("{")
                reader.expect("OFFSET")
                tree.end_sites.append((stack[-1], _read_offset(reader)))
                reader.expect("}")
            elif token == "}":
                stack.pop()
                if not stack:
                    return tree
            else:
                raise reader.error(
                    f"expected JOINT, End Site or '}}' inside joint "
                    f"{tree.names[stack[-1]]!r}, found {_shorten(token)}"
                )


def _parse_frame_time(token: str, line: int, source: str) -> float:
    """Frames per second from the Frame Time token.

    fps snaps to an integer when the frame time is that rate's period rounded to the digits the file
    prints (``.0083333`` → 120 fps, ``0.0333`` → 30 fps); otherwise it is ``1 / frame_time``.
    """
    if not _NUMBER_RE.fullmatch(token):
        raise BVHError(f"Frame Time must be a number, found {_shorten(token)}", line, source)
    frame_time = float(token)
    if not np.isfinite(frame_time) or frame_time <= 0:
        raise BVHError(f"Frame Time must be a positive number of seconds, found {token}", line, source)
    fps = 1.0 / frame_time
    if not np.isfinite(fps):
        raise BVHError(f"Frame Time {token} is too small", line, source)
    half_last_digit = 0.5 * 10.0 ** Decimal(token).as_tuple().exponent
    nearest = round(fps)
    if nearest >= 1 and abs(frame_time - 1.0 / nearest) <= half_last_digit * (1 + 1e-9):
        fps = float(nearest)
    return fps


def _header_line(
    lines: list[str], index: int, pattern: re.Pattern[str], what: str, source: str
) -> tuple[int, str]:
    """Skip blank lines from ``index``; the next line must match ``pattern``. Returns (line index, value)."""
    while index < len(lines) and not lines[index].strip():
        index += 1
    if index >= len(lines):
        raise _end_of_file(lines, f"the {what!r} line", source)
    match = pattern.fullmatch(lines[index].strip())
    if match is None:
        raise BVHError(
            f"expected the {what!r} line, found {_shorten(lines[index].strip())}", index + 1, source
        )
    return index, match.group(1)


def _parse_motion(lines: list[str], start: int, num_channels: int, source: str) -> tuple[np.ndarray, float]:
    """Parse from the line after ``MOTION``: ``(values (T, C), fps)``."""
    frames_index, frames_token = _header_line(lines, start, _FRAMES_RE, "Frames:", source)
    if not _COUNT_RE.fullmatch(frames_token) or not frames_token.strip("0"):
        raise BVHError(
            f"Frames must be a positive integer, found {_shorten(frames_token)}", frames_index + 1, source
        )
    if len(frames_token.lstrip("0")) > 18:
        raise BVHError(
            f"Frames count {_shorten(frames_token)} is implausibly large", frames_index + 1, source
        )
    num_frames = int(frames_token)
    time_index, time_token = _header_line(lines, frames_index + 1, _FRAME_TIME_RE, "Frame Time:", source)
    fps = _parse_frame_time(time_token, time_index + 1, source)

    frame_lines = [i for i in range(time_index + 1, len(lines)) if lines[i].strip()]
    if len(frame_lines) < num_frames:
        raise BVHError(
            f"truncated motion: 'Frames: {num_frames}' but only {len(frame_lines)} frame lines follow",
            frames_index + 1,
            source,
        )
    if len(frame_lines) > num_frames:
        raise BVHError(
            f"more frame lines than 'Frames: {num_frames}' declares (frame {num_frames + 1} starts here)",
            frame_lines[num_frames] + 1,
            source,
        )
    if num_channels == 0:
        raise BVHError(
            "the hierarchy declares no channels, but frame lines follow", frame_lines[0] + 1, source
        )

    values = np.empty((num_frames, num_channels), dtype=np.float64)
    for frame, i in enumerate(frame_lines):
        tokens = lines[i].split()
        if len(tokens) != num_channels:
            raise BVHError(
                f"frame {frame + 1} has {len(tokens)} values, the hierarchy declares {num_channels} channels",
                i + 1,
                source,
            )
        if not all(map(_NUMBER_RE.fullmatch, tokens)):
            bad = next(k for k, t in enumerate(tokens) if not _NUMBER_RE.fullmatch(t))
            raise BVHError(
                f"frame {frame + 1}, value {bad + 1} is not a number: {_shorten(tokens[bad])}", i + 1, source
            )
        values[frame] = [float(t) for t in tokens]
        if not np.isfinite(values[frame]).all():
            bad = int(np.flatnonzero(~np.isfinite(values[frame]))[0])
            raise BVHError(
                f"frame {frame + 1}, value {bad + 1} is out of range: {_shorten(tokens[bad])}", i + 1, source
            )
    return values, fps


def _split_lines(data: bytes, source: str) -> list[str]:
    """Text lines of a BVH file (any mix of LF, CRLF and CR endings), decoded as UTF-8 or, failing that,
    Latin-1; data with NUL bytes is rejected as binary."""
    if not data.strip():
        raise BVHError("the file is empty", 1, source)
    if b"\x00" in data:
        line = data.count(b"\n", 0, data.index(b"\x00")) + 1
        raise BVHError("binary data (NUL byte), not a BVH text file", line, source)
    try:
        text = data.decode("utf-8-sig")  # drops a byte-order mark, as Windows tools write
    except UnicodeDecodeError:
        text = data.decode("latin-1")
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _elementary_quaternions(axis: int, degrees: np.ndarray) -> torch.Tensor:
    """``(T, 4)`` quaternions of rotations by ``degrees`` about coordinate axis ``axis`` (0 = x)."""
    half = torch.from_numpy(np.deg2rad(degrees) / 2)
    q = torch.zeros(len(degrees), 4, dtype=torch.float64)
    q[:, 0] = torch.cos(half)
    q[:, 1 + axis] = torch.sin(half)
    return q


def parse_bvh(data: bytes, source: str = "<bvh>") -> Motion:
    """Parse the bytes of a BVH file into a :class:`Motion` (file units, world axes, float64).

    See :func:`load_bvh`; ``source`` names the data in error messages.
    """
    lines = _split_lines(data, source)
    reader = _TokenReader(lines, source)
    tree = _parse_hierarchy(reader)
    token = reader.next("MOTION")
    if token.upper() == "ROOT":
        raise reader.error("a second ROOT: files with several skeletons are not supported")
    if token.upper() != "MOTION":
        raise reader.error(f"expected 'MOTION' after the hierarchy, found {_shorten(token)}")
    if reader.rest_of_line():
        raise reader.error("unexpected text after 'MOTION'")
    num_channels = sum(len(c) for c in tree.channels)
    values, fps = _parse_motion(lines, reader.line_index + 1, num_channels, source)

    num_frames, num_joints = values.shape[0], len(tree.names)
    offsets = np.array(tree.offsets, dtype=np.float64)
    translations = np.broadcast_to(offsets, (num_frames, num_joints, 3)).copy()
    rotations = torch.zeros(num_frames, num_joints, 4, dtype=torch.float64)
    rotations[..., 0] = 1.0
    column = 0
    for j, channels in enumerate(tree.channels):
        for name in channels:
            axis = _AXIS_INDEX[name[0]]
            if name in POSITION_CHANNELS:
                translations[:, j, axis] = values[:, column]
            else:
                rotations[:, j] = quat_mul(rotations[:, j], _elementary_quaternions(axis, values[:, column]))
            column += 1
    moving_joints = any(name in POSITION_CHANNELS for c in tree.channels[1:] for name in c)

    world_translations = torch.from_numpy(translations[..., _FILE_TO_WORLD_AXES])
    return Motion(
        joint_names=tuple(tree.names),
        parents=tuple(tree.parents),
        offsets=torch.from_numpy(offsets[:, _FILE_TO_WORLD_AXES]),
        rotations=rotations[..., _QUAT_FILE_TO_WORLD],
        root_positions=world_translations[:, 0],
        fps=fps,
        channels=tuple(tree.channels),
        end_sites=tuple((j, tuple(off[i] for i in _FILE_TO_WORLD_AXES)) for j, off in tree.end_sites),
        joint_translations=world_translations if moving_joints else None,
    )


def load_bvh(path: str | Path, scale: float | None = None) -> Motion:
    """Load a BVH file as a :class:`Motion` in motionlab's world frame (z up, facing +x).

    Args:
        path: the ``.bvh`` file.
        scale: multiply every length by this (for example :data:`CMU_SCALE` for metres); ``None`` keeps
            the file's units.

    Returns:
        A ``Motion`` (float64) with ``joint_names`` in file order (End Sites excluded; names with spaces
        get ``_`` as in Blender), ``parents``, ``offsets``, ``rotations`` ``(T, J, 4)``,
        ``root_positions`` ``(T, 3)``, ``fps``, the per-joint ``channels``, the ``end_sites`` and, when
        non-root joints have position channels, ``joint_translations``. ``motion.global_positions()``
        gives ``(T, J, 3)`` world positions. Axis conversion: see the module docstring.

    Raises:
        BVHError: (a ``ValueError``) for any malformed content, naming the line and the problem.
        OSError: when the file cannot be read.
    """
    path = Path(path)
    motion = parse_bvh(path.read_bytes(), source=str(path))
    return motion if scale is None else motion.scaled(scale)


# ----------------------------------------------------------------------------------------- writing


def _default_channels(motion: Motion, rotation_order: str) -> tuple[tuple[str, ...], ...]:
    """Positions and rotations on the root (and on every joint of a motion with joint translations),
    rotations only elsewhere."""
    rotation = tuple(f"{axis}rotation" for axis in rotation_order)
    moving = POSITION_CHANNELS + rotation
    return tuple(
        moving if j == 0 or motion.joint_translations is not None else rotation
        for j in range(motion.num_joints)
    )


def _default_end_sites(motion: Motion) -> tuple[tuple[int, tuple[float, float, float]], ...]:
    """One End Site per leaf joint, continuing its bone by half its length (so tools draw a leaf bone);
    a leaf with a zero offset (or a lone root) gets one pointing up, half the median bone long."""
    lengths = motion.offsets[1:].norm(dim=-1)
    up = 0.5 * float(lengths[lengths > 0].median()) if (lengths > 0).any() else 1.0
    has_child = set(motion.parents[1:])
    sites = []
    for j in range(motion.num_joints):
        if j in has_child:
            continue
        offset = motion.offsets[j]
        if j == 0 or float(offset.norm()) == 0.0:
            sites.append((j, (0.0, 0.0, up)))
        else:
            sites.append((j, tuple(0.5 * float(v) for v in offset)))
    return tuple(sites)


def _depth_first(parents: tuple[int, ...]) -> list[int]:
    """Joint indices in depth-first order from the root, children in index order."""
    children: dict[int, list[int]] = {j: [] for j in range(len(parents))}
    for j, p in enumerate(parents[1:], start=1):
        children[p].append(j)
    order, stack = [], [0]
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(reversed(children[j]))
    return order


def _euler_order(rotation_axes: str) -> str:
    """A full three-axis order containing ``rotation_axes`` (a joint's rotation channels) in order.

    A joint with two rotation channels puts the missing axis in the middle: the middle angle of a
    Tait-Bryan decomposition is confined to [-90°, 90°], so a rotation the two channels can express
    decomposes with that angle exactly 0 and the other two free.
    """
    missing = "".join(a for a in "XYZ" if a not in rotation_axes)
    if len(rotation_axes) == 2:
        return rotation_axes[0] + missing + rotation_axes[1]
    return rotation_axes + missing


def _joint_columns(
    name: str,
    channels: tuple[str, ...],
    translation: np.ndarray,
    offset: np.ndarray,
    rotation: torch.Tensor,
) -> list[np.ndarray]:
    """Frame values ``(T,)`` of one joint's channels, from its file-axes ``translation`` ``(T, 3)``,
    ``offset`` ``(3,)`` and ``rotation`` ``(T, 4)``; rotations in degrees."""
    tolerance = 1e-6 * max(1.0, float(np.abs(translation).max()))
    for axis in range(3):
        if (
            POSITION_CHANNELS[axis] not in channels
            and np.abs(translation[:, axis] - offset[axis]).max() > tolerance
        ):
            raise ValueError(
                f"save_bvh: joint {name!r} moves along file axis {'XYZ'[axis]} but its channels "
                f"{channels} have no {POSITION_CHANNELS[axis]}"
            )
    rotation_axes = "".join(c[0] for c in channels if c in ROTATION_CHANNELS)
    order = _euler_order(rotation_axes)
    angles = np.rad2deg(quat_to_euler(rotation, order).numpy())  # (T, 3), one column per letter of order
    unused = [k for k, axis in enumerate(order) if axis not in rotation_axes]
    if unused and np.abs(angles[:, unused]).max() > 1e-4:
        raise ValueError(
            f"save_bvh: joint {name!r} rotates about axes its channels {channels} cannot express"
        )
    angles = np.unwrap(angles, period=360.0, axis=0)  # continuous curves for animation tools

    return [
        translation[:, _AXIS_INDEX[c[0]]] if c in POSITION_CHANNELS else angles[:, order.index(c[0])]
        for c in channels
    ]


def _end_site_lines(sites: list[tuple[float, ...]], depth: int) -> list[str]:
    indent = "\t" * depth
    out = []
    for offset in sites:
        out += [f"{indent}End Site", f"{indent}{{", f"{indent}\tOFFSET {_format_row(offset)}", f"{indent}}}"]
    return out


def _format_row(values: tuple[float, ...] | list[float]) -> str:
    return " ".join(f"{v:.6f}" for v in values)


def save_bvh(motion: Motion, path: str | Path, rotation_order: str = "ZYX") -> None:
    """Write ``motion`` as a BVH file (y up, facing +z, the motion's length units, angles in degrees).

    Joints are written depth-first (BVH nests children inside parents), children in index order, so
    a skeleton whose order is not depth-first (SMPL's) loads back depth-first under the same names;
    ``Motion.reorder`` restores the order. Joints keep their recorded ``channels``; a motion without
    them (synthetic data) gets ``Xposition Yposition Zposition`` plus rotations in ``rotation_order``
    on the root and rotations only on the other joints. Leaf joints get their recorded End Sites, or,
    when none are recorded, one that continues the bone by half its length. Values are written with
    6 decimals; Euler angles are unwrapped over time so that animation curves stay continuous.

    Raises:
        TypeError: ``rotation_order`` is not a string.
        ValueError: for a bad ``rotation_order``, or a motion its channels cannot express (a joint that
            moves or rotates about an axis it has no channel for, or no channels at all).
    """
    if not isinstance(rotation_order, str):
        raise TypeError(f"save_bvh: rotation_order must be a string, got {type(rotation_order).__name__}")
    if sorted(rotation_order) != ["X", "Y", "Z"]:
        raise ValueError(f"save_bvh: rotation_order must be a permutation of 'XYZ', got {rotation_order!r}")
    channels = motion.channels if motion.channels is not None else _default_channels(motion, rotation_order)
    if not any(channels):
        raise ValueError("save_bvh: no joint has channels, so the file could hold no motion")
    end_sites = motion.end_sites if motion.end_sites is not None else _default_end_sites(motion)
    sites_of: dict[int, list[tuple[float, ...]]] = {}
    for j, offset in end_sites:
        sites_of.setdefault(j, []).append(tuple(offset[i] for i in _WORLD_TO_FILE_AXES))

    offsets = motion.offsets[:, _WORLD_TO_FILE_AXES].to(torch.float64).numpy()
    translations = motion.local_translations()[..., _WORLD_TO_FILE_AXES].to(torch.float64).numpy()
    rotations = motion.rotations[..., _QUAT_WORLD_TO_FILE].to(torch.float64)

    order = _depth_first(motion.parents)
    lines = ["HIERARCHY"]
    open_blocks: list[int] = []

    def close_block() -> None:
        joint = open_blocks.pop()
        lines.extend(_end_site_lines(sites_of.get(joint, []), len(open_blocks) + 1))
        lines.append("\t" * len(open_blocks) + "}")

    for j in order:
        while open_blocks and open_blocks[-1] != motion.parents[j]:
            close_block()
        indent = "\t" * len(open_blocks)
        lines += [
            f"{indent}{'ROOT' if j == 0 else 'JOINT'} {motion.joint_names[j]}",
            f"{indent}{{",
            f"{indent}\tOFFSET {_format_row(offsets[j].tolist())}",
            f"{indent}\tCHANNELS {' '.join((str(len(channels[j])),) + channels[j])}",
        ]
        open_blocks.append(j)
    while open_blocks:
        close_block()

    columns = [
        column
        for j in order
        for column in _joint_columns(
            motion.joint_names[j], channels[j], translations[:, j], offsets[j], rotations[:, j]
        )
    ]
    lines += ["MOTION", f"Frames: {motion.num_frames}", f"Frame Time: {1.0 / motion.fps:.10g}"]
    lines += [_format_row(row) for row in np.stack(columns, axis=1).tolist()]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8", newline="\n")
