"""The synthetic motion-capture generator: labelled clips of six actions in twelve style modes.

Python::

    from motionlab.data.synthetic import generate, load_or_generate
    data = generate(seed=0, n_per_mode=10)           # a MotionSet of 12 * 10 clips of 4 s at 30 fps
    data = load_or_generate(seed=0, n_per_mode=100)  # cached under build/data/ (notebooks use this)

Command line (writes the ``.npz`` format of :mod:`motionlab.data.store`)::

    python -m motionlab.data.synthetic --out FILE.npz --seed S [--n-per-mode N] [--seconds S]

**Layout and seeding.** Clips come mode by mode (mode 0 first), ``n_per_mode`` each, and body types
alternate inside a mode (clip ``k`` of a mode has body ``k % 2``), so bodies are balanced. Clip ``k`` of
mode ``m`` draws its parameters from its own stream ``SeedSequence(seed, spawn_key=(split, m, k))``:
the same seed gives bitwise-identical arrays, and a smaller ``n_per_mode`` gives a subset of a larger one.

**Splits.** Each split is generated from its own streams (``split="train" | "val" | "test"``), so splits
never share a clip for any seed; :func:`load_splits` returns all three. (To split one set into windows
instead, use :func:`motionlab.data.datasets.split_clips`, which stratifies by mode.)

How each action is made: :mod:`~motionlab.data.gait` (walk, jog), :mod:`~motionlab.data.events` (jump,
lift), :mod:`~motionlab.data.gestures` (wave, kick), all posed by :mod:`~motionlab.data.body`.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import numbers
import sys
import time
from pathlib import Path

import numpy as np

from motionlab import arguments, config, skeleton
from motionlab.data import actions, body, curves, events, gait, gestures, rig, store, styles
from motionlab.data.actions import ACTION_NAMES, CATALOGUE, MODE_ACTION, MODE_NAMES, MODE_STYLE
from motionlab.data.body import BodyBatch, pose
from motionlab.data.store import MotionSet
from motionlab.data.styles import DRAWS_PER_CLIP, Draws
from motionlab.skeleton import BODY_MEASUREMENTS, BODY_TYPES, PARENTS
from motionlab.validation import check_choice, check_scalar

SPLITS = ("train", "val", "test")

#: Shortest clip the generator makes; one-off events are played faster to fit short clips.
MIN_SECONDS = 1.0

#: Lowest frame rate: below it a jog's swing lasts a frame or two.
MIN_FPS = 10

#: Clips posed at once (bounds memory: about 0.4 MB per clip of 4 s).
CHUNK = 128

#: The version of what the generator produces, by which trained runs are keyed (MoGlow's data identity, and
#: with it the shipped reference models in ``reference/``): it changes when, and only when, the generator's
#: output changes, and then `make reference` retrains them. ``tests/test_synthetic_version.py`` keeps it
#: honest: it compares a small generated sample with the one stored in ``tests/data/synthetic_sample.npz``
#: under this version, so a changed output fails there, while an edited docstring keeps the version. (It
#: was a hash of the generator's source files until 2026-12; this is that hash's last value.)
GENERATOR_VERSION = "be4a8edf80cb"

_SOURCES = (rig, curves, body, styles, gait, events, gestures, actions, store)


def generator_fingerprint() -> str:
    """The version of the generator's output that trained runs are keyed by: :data:`GENERATOR_VERSION`."""
    return GENERATOR_VERSION


def source_digest() -> str:
    """A short hash of the generator's source files: cached data sets are keyed by it, so any edit of the
    generator (an exercise's, say) makes its data afresh."""
    digest = hashlib.sha256()
    for module in (*_SOURCES, skeleton, sys.modules[__name__]):
        digest.update(Path(module.__file__).read_bytes())
    return digest.hexdigest()[:12]


def _check_arguments(seed: int, n_per_mode: int, seconds: float, fps: int, split: str) -> None:
    """The arguments :func:`generate` and :func:`load_or_generate` share, checked."""
    check_scalar(seed, "seed", "generate", kind=numbers.Integral, minimum=0)
    check_scalar(n_per_mode, "n_per_mode", "generate", kind=numbers.Integral, minimum=1)
    check_scalar(fps, "fps", "generate", kind=numbers.Integral, minimum=MIN_FPS)
    check_scalar(seconds, "seconds", "generate", minimum=MIN_SECONDS)
    check_choice(split, "split", "generate", SPLITS)


def generate(
    seed: int, n_per_mode: int, seconds: float = 4.0, fps: int = 30, split: str = "train"
) -> MotionSet:
    """Generate ``12 * n_per_mode`` labelled clips of ``round(seconds * fps)`` frames.

    Args:
        seed: non-negative integer; the same seed (and arguments) gives bitwise-identical arrays.
        n_per_mode: clips per style mode (bodies alternate inside a mode).
        seconds: clip length, at least :data:`MIN_SECONDS`.
        fps: frames per second, at least :data:`MIN_FPS`.
        split: ``"train"``, ``"val"`` or ``"test"``: which family of random streams to draw from.
    Raises:
        TypeError: an argument of the wrong type (a float seed, a bool count...).
        ValueError: an argument out of range, or an unknown split.
    """
    _check_arguments(seed, n_per_mode, seconds, fps, split)
    n_frames = int(round(seconds * fps))
    mode = np.repeat(np.arange(len(MODE_NAMES)), n_per_mode)
    replicate = np.tile(np.arange(n_per_mode), len(MODE_NAMES))
    body_type = replicate % len(BODY_TYPES)
    split_id = SPLITS.index(split)
    streams = (
        np.random.SeedSequence(int(seed), spawn_key=(split_id, int(m), int(k)))
        for m, k in zip(mode, replicate)
    )
    uniforms = np.stack([np.random.default_rng(stream).random(DRAWS_PER_CLIP) for stream in streams])

    n_clips, n_joints = mode.size, len(PARENTS)
    positions = np.empty((n_clips, n_frames, n_joints, 3), np.float32)
    rotations = np.empty((n_clips, n_frames, n_joints, 4), np.float32)
    contacts = np.empty((n_clips, n_frames, 4), bool)
    for action_id, action in enumerate(CATALOGUE):
        clips = np.flatnonzero(MODE_ACTION[mode] == action_id)
        for chunk in np.array_split(clips, math.ceil(clips.size / CHUNK)):
            bodies = BodyBatch.of(body_type[chunk])
            drive = action.make(Draws(uniforms[chunk], MODE_STYLE[mode[chunk]]), bodies, n_frames, fps)
            rotations[chunk], positions[chunk] = pose(drive, bodies, fps)
            contacts[chunk] = drive.contacts
    return MotionSet(
        positions=positions,
        rotations=rotations,
        action=MODE_ACTION[mode],
        mode=mode.astype(np.int64),
        body=body_type.astype(np.int64),
        contacts=contacts,
        action_names=np.array(ACTION_NAMES),
        mode_names=np.array(MODE_NAMES),
        mode_action=MODE_ACTION.copy(),
        parents=np.array(PARENTS, dtype=np.int64),
        offsets=np.stack([m.offsets() for m in BODY_MEASUREMENTS]).astype(np.float32),
        fps=np.array(fps, dtype=np.int64),
    )


def cache_path(seed: int, n_per_mode: int, seconds: float = 4.0, fps: int = 30, split: str = "train") -> Path:
    """Where :func:`load_or_generate` keeps a data set (under ``config.build_dir() / "data"``)."""
    name = f"synthetic_{split}_seed{seed}_n{n_per_mode}_{seconds:g}s_{fps}fps_{source_digest()}.npz"
    return config.build_dir() / "data" / name


def _stale_caches(path: Path) -> list[Path]:
    """Cache files of the same arguments made by an older generator (another fingerprint)."""
    prefix = path.name.rsplit("_", 1)[0]
    return [other for other in path.parent.glob(f"{prefix}_*.npz") if other != path]


def load_or_generate(
    seed: int, n_per_mode: int, seconds: float = 4.0, fps: int = 30, split: str = "train"
) -> MotionSet:
    """:func:`generate`, cached on disk; a cache file that does not load cleanly is regenerated.

    Files are keyed by the arguments and :func:`source_digest`, so an edited generator makes new data;
    writing it removes the copies an older generator made for the same arguments.
    """
    _check_arguments(seed, n_per_mode, seconds, fps, split)
    path = cache_path(seed, n_per_mode, seconds, fps, split)
    if path.is_file():
        try:
            return MotionSet.load(path)
        except ValueError:
            path.unlink()
    data = generate(seed, n_per_mode, seconds, fps, split)
    data.save(path)
    for stale in _stale_caches(path):
        stale.unlink(missing_ok=True)
    return data


def load_splits(
    seed: int, n_per_mode: tuple[int, int, int], seconds: float = 4.0, fps: int = 30
) -> tuple[MotionSet, MotionSet, MotionSet]:
    """Train, validation and test sets, each from its own streams, with ``n_per_mode[i]`` clips per mode."""
    if len(n_per_mode) != len(SPLITS):
        raise ValueError(f"load_splits: n_per_mode needs one count per split {SPLITS}, got {n_per_mode!r}")
    train, val, test = (
        load_or_generate(seed, n, seconds, fps, split) for n, split in zip(n_per_mode, SPLITS)
    )
    return train, val, test


def _write(args: argparse.Namespace) -> int:
    """Generate the data set the parsed command line describes, write it (and its checksums); returns 0."""
    start = time.perf_counter()
    data = generate(args.seed, args.n_per_mode, args.seconds, args.fps, args.split)
    data.save(args.out, compress=args.compress)
    if args.checksums is not None:
        record = {
            "seed": args.seed,
            "n_per_mode": args.n_per_mode,
            "seconds": args.seconds,
            "fps": args.fps,
            "split": args.split,
            "sha256": data.checksums(),
        }
        args.checksums.write_text(json.dumps(record, indent=2, sort_keys=True) + "\n")
    print(
        f"wrote {data.n_clips} clips x {data.n_frames} frames ({len(MODE_NAMES)} modes x {args.n_per_mode}) "
        f"to {args.out} in {time.perf_counter() - start:.2f} s"
    )
    return 0


def main(argv: list[str] | None = None) -> int:
    """The command line; returns the exit status (2, with a one-line message, for a bad argument)."""
    prog = "python -m motionlab.data.synthetic"
    parser = argparse.ArgumentParser(
        prog=prog, description="Write a synthetic motion-capture data set (.npz)."
    )
    parser.add_argument(
        "--out",
        required=True,
        type=arguments.output_file,
        help="output file (.npz); its directory must exist",
    )
    parser.add_argument(
        "--seed", required=True, type=arguments.non_negative_int, help="non-negative integer seed"
    )
    parser.add_argument(
        "--n-per-mode",
        type=arguments.positive_int,
        default=10,
        help="clips per style mode (12 modes; default 10)",
    )
    parser.add_argument(
        "--seconds",
        type=arguments.float_at_least(MIN_SECONDS),
        default=4.0,
        help=f"clip length in seconds, at least {MIN_SECONDS:g} (default 4)",
    )
    parser.add_argument(
        "--fps",
        type=arguments.int_at_least(MIN_FPS),
        default=30,
        help=f"frames per second, at least {MIN_FPS} (default 30)",
    )
    parser.add_argument(
        "--split", choices=SPLITS, default="train", help="family of random streams (default train)"
    )
    parser.add_argument(
        "--compress", action="store_true", help="write a compressed archive (slower, ~10%% smaller)"
    )
    parser.add_argument(
        "--checksums",
        type=arguments.output_file,
        help="also write the SHA-256 of every array to this JSON file",
    )
    args = parser.parse_args(argv)
    return arguments.run(prog, lambda: _write(args))


if __name__ == "__main__":
    sys.exit(main())
