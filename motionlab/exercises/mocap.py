"""Chapter 10's exercises: the left/right mirror image of a recorded pose, checked against
:func:`motionlab.data.augment.mirror_positions` with :data:`motionlab.data.cmu_mocap.MIRROR`; and the
bone-length variation of a clip, checked against :func:`motionlab.metrics.realism.bone_length_variation`."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch

from motionlab.data.augment import mirror_positions
from motionlab.data.cmu_mocap import MIRROR, PARENTS
from motionlab.exercises.checking import CheckResult, Diagnosis, checker, close
from motionlab.metrics.physical import bone_lengths
from motionlab.metrics.realism import bone_length_variation

BoneLengthVariation = Callable[[np.ndarray, tuple[int, ...]], np.ndarray]
Mirror = Callable[[np.ndarray, tuple[int, ...]], np.ndarray]


def _as_array(value: object, name: str = "my_bone_length_variation") -> np.ndarray:
    if isinstance(value, torch.Tensor):
        value = value.detach().numpy()
    if not isinstance(value, np.ndarray):
        raise Diagnosis(f"{name} should return a NumPy array, got {type(value).__name__}")
    return value.astype(np.float64)


def _clip(seed: int, n_frames: int = 30) -> np.ndarray:
    """A random clip ``(T, 20, 3)``: a standing skeleton plus marker-like noise of a few centimetres."""
    generator = np.random.default_rng(seed)
    rest = np.cumsum(generator.normal(scale=0.2, size=(len(PARENTS), 3)), axis=0)
    return rest + generator.normal(scale=0.03, size=(n_frames, len(PARENTS), 3))


def _variation_values(fn: BoneLengthVariation) -> None:
    clip = _clip(0)
    got = _as_array(fn(clip.copy(), PARENTS))
    want = bone_length_variation(clip, PARENTS)
    n_bones = len(PARENTS) - 1
    if got.shape != want.shape:
        if got.size == 1:
            raise Diagnosis(f"return one number per bone, shape ({n_bones},), not their mean")
        if got.shape == (len(PARENTS),):
            raise Diagnosis(f"the root has no bone: return ({n_bones},), the non-root joints in order")
        raise Diagnosis(
            f"a clip of {len(PARENTS)} joints has {n_bones} bones: expected ({n_bones},), got {got.shape}"
        )
    if close(torch.from_numpy(got), torch.from_numpy(want), 1e-8):
        return
    lengths = bone_lengths(clip, PARENTS)
    for wrong, text in (
        (
            lengths.std(axis=0, ddof=1) / lengths.mean(axis=0),
            "use the population std (ddof=0), NumPy's default",
        ),
        (lengths.std(axis=0), "divide the standard deviation by the mean length"),
        (
            lengths.std(axis=1) / lengths.mean(axis=1),
            "take the statistics over the frames (axis 0), per bone",
        ),
        (lengths.var(axis=0) / lengths.mean(axis=0), "the standard deviation, not the variance"),
    ):
        if wrong.shape == got.shape and np.allclose(got, wrong, rtol=1e-8, atol=1e-10):
            raise Diagnosis(text)
    raise Diagnosis(
        "the values are wrong: bone b joins joint b + 1 to its parent; take its length in every frame, "
        "then std / mean over the frames"
    )


def _rigid_is_zero(fn: BoneLengthVariation) -> None:
    pose = _clip(1, n_frames=1)[0]
    turning = (
        np.stack(
            [
                pose @ np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]]).T
                for a in np.linspace(0, 1, 12)
            ]
        )
        + np.linspace(0, 2, 12)[:, None, None]
    )
    got = _as_array(fn(turning, PARENTS))
    if not np.allclose(got, 0.0, atol=1e-9):
        raise Diagnosis("a rigid body that turns and moves keeps its bone lengths: the variation should be 0")


@checker(
    [_variation_values, _rigid_is_zero],
    "matches the package's bone-length variation, and a rigid moving body gives 0",
)
def check_bone_length_variation(fn: BoneLengthVariation) -> CheckResult:
    """Check ``fn(positions (T, J, 3), parents) -> (J - 1,)``: each bone's length std over mean."""


def _mirror_values(fn: Mirror) -> None:
    clip = _clip(2, n_frames=5)
    got = _as_array(fn(clip.copy(), tuple(MIRROR)), "my_mirror")
    want = mirror_positions(torch.from_numpy(clip), torch.tensor(MIRROR)).numpy()
    if got.shape != want.shape:
        raise Diagnosis(f"return positions of the input's shape {want.shape}, got {got.shape}")
    if np.allclose(got, want, atol=1e-12):
        return
    reflect = {axis: clip * np.where(np.arange(3) == axis, -1.0, 1.0) for axis in range(3)}
    for wrong, text in (
        (reflect[1], "swap left and right too: joint j of the mirror image is joint MIRROR[j] reflected"),
        (clip[:, list(MIRROR)], "reflect the positions too (y -> -y), not only swap left and right"),
        (reflect[0][:, list(MIRROR)], "reflect across the x-z plane (y -> -y): the character faces +x"),
        (reflect[2][:, list(MIRROR)], "reflect y (sideways), not z: a mirror image keeps the floor below"),
    ):
        if wrong.shape == got.shape and np.allclose(got, wrong, atol=1e-12):
            raise Diagnosis(text)
    raise Diagnosis("the values are wrong: reflect y -> -y, then take joint MIRROR[j] as the new joint j")


def _mirror_twice_is_identity(fn: Mirror) -> None:
    clip = _clip(3, n_frames=4)
    twice = _as_array(fn(_as_array(fn(clip.copy(), tuple(MIRROR)), "my_mirror"), tuple(MIRROR)), "my_mirror")
    if not np.allclose(twice, clip, atol=1e-12):
        raise Diagnosis("mirroring twice must give the clip back")


@checker(
    [_mirror_values, _mirror_twice_is_identity],
    "matches the package's mirror image, and mirroring twice gives the clip back",
)
def check_mirror(fn: Mirror) -> CheckResult:
    """Check ``fn(positions (T, J, 3), mirror (J,)) -> (T, J, 3)``: the left/right mirror image."""
