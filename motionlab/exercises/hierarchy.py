"""Appendix 04a's exercises: how far each joint's rotation reaches, the ``L_j`` behind the Motion Cell's joint
weights ``λ_j`` (eq. 23), and the weights themselves, checked against
:func:`motionlab.skeleton.subtree_reach` and :func:`motionlab.skeleton.joint_impact_weights`."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from motionlab.exercises.checking import CheckResult, Diagnosis, checker
from motionlab.skeleton import Skeleton, average_skeleton, joint_impact_weights, subtree_reach

SubtreeReach = Callable[[Sequence[int], np.ndarray], np.ndarray]
ImpactWeights = Callable[[np.ndarray, float], np.ndarray]


def _trees() -> list[tuple[str, list[int], np.ndarray]]:
    skeleton = average_skeleton()
    rng = np.random.default_rng(0)
    random_parents = [-1] + [int(rng.integers(0, j)) for j in range(1, 12)]
    return [
        ("the 22-joint skeleton", list(skeleton.parents), skeleton.bone_lengths()),
        ("a chain of 5 joints", [-1, 0, 1, 2, 3], np.array([0.0, 0.5, 0.4, 0.3, 0.2])),
        ("a random tree of 12 joints", random_parents, np.concatenate([[0.0], rng.uniform(0.1, 1.0, 11)])),
    ]


def _subtree_sum(parents: Sequence[int], bones: np.ndarray) -> np.ndarray:
    total = np.zeros(len(parents))
    for j in range(len(parents) - 1, 0, -1):
        total[parents[j]] += total[j] + bones[j]
    return total


def _reach_values(fn: SubtreeReach) -> None:
    for name, parents, bones in _trees():
        got = np.asarray(fn(parents, bones), dtype=float)
        want = subtree_reach(parents, bones)
        if got.shape != want.shape:
            raise Diagnosis(f"for {name} return one L_j per joint, shape {want.shape}, got {got.shape}")
        if np.allclose(got, want):
            continue
        if np.allclose(got, _subtree_sum(parents, bones)):
            raise Diagnosis(
                f"for {name} you added up every bone below joint j; L_j is the longest single path to an end "
                "effector (a max over the children, not a sum)"
            )
        if np.allclose(got, want + bones):
            raise Diagnosis(f"for {name} each L_j includes the joint's own bone; start from its children")
        leaves = [j for j in range(len(parents)) if j not in parents]
        if not np.allclose(got[leaves], 0):
            raise Diagnosis(f"for {name} the end effectors {leaves} should have L_j = 0: they move no joint")
        first = int(np.flatnonzero(~np.isclose(got, want))[0])
        raise Diagnosis(
            f"for {name} joint {first} has L = {got[first]:.3f}, not {want[first]:.3f}: visit children "
            "before their parents (from the last joint back), so a child's reach is known when its parent "
            "needs it"
        )


@checker(
    [_reach_values],
    "matches motionlab.skeleton.subtree_reach on the skeleton, a chain and a random tree",
)
def check_subtree_reach(fn: SubtreeReach) -> CheckResult:
    """Check ``fn(parents (J,), bone_lengths (J,)) -> L (J,)``, the longest path from each joint to an end
    effector (``bone_lengths[j]``: the length of the bone from joint ``j``'s parent to ``j``)."""


def _as_skeleton(parents: list[int], bones: np.ndarray, seed: int) -> Skeleton:
    """A skeleton with these parents and bone lengths (random bone directions)."""
    directions = np.random.default_rng(seed).normal(size=(len(parents), 3))
    offsets = directions / np.linalg.norm(directions, axis=1, keepdims=True) * bones[:, None]
    return Skeleton(tuple(f"joint{j}" for j in range(len(parents))), tuple(parents), offsets)


def _weight_cases() -> list[tuple[str, np.ndarray, float, np.ndarray]]:
    """(what, L, leaf_floor, the package's weights) for the skeleton, a chain and a random tree."""
    cases = []
    for seed, (name, parents, bones) in enumerate(_trees()):
        skeleton = _as_skeleton(parents, bones, seed)
        reach = subtree_reach(skeleton.parents, skeleton.bone_lengths())
        for floor in (0.1, 0.3, 0.0, 1.0):
            cases.append(
                (f"{name} with leaf_floor = {floor:g}", reach, floor, joint_impact_weights(skeleton, floor))
            )
    return cases


def _weights_values(fn: ImpactWeights) -> None:
    for name, reach, floor, want in _weight_cases():
        got = np.asarray(fn(reach.copy(), floor), dtype=float)
        if got.shape != want.shape:
            raise Diagnosis(f"for {name} return one λ_j per joint, shape {want.shape}, got {got.shape}")
        if np.allclose(got, want):
            continue
        floored = np.maximum(reach, floor * reach.max())
        if np.allclose(got, floored / floored.sum()):
            raise Diagnosis(f"for {name} the weights sum to 1; divide by the mean so that they average 1")
        if np.allclose(got, floored / floored.max()):
            raise Diagnosis(f"for {name} the largest weight is 1; divide by the mean so that they average 1")
        if np.allclose(got, reach / reach.mean()):
            raise Diagnosis(
                f"for {name} the end effectors get λ = 0; raise every L_j to at least leaf_floor * "
                "max(L) first, so that their orientation still counts in the loss"
            )
        absolute = np.maximum(reach, floor)
        if np.allclose(got, absolute / absolute.mean()):
            raise Diagnosis(f"for {name} the floor is a fraction of the largest L_j: leaf_floor * max(L)")
        if not np.isclose(got.mean(), 1.0):
            raise Diagnosis(
                f"for {name} the weights average {got.mean():.3f}: floor first, then divide by the mean"
            )
        raise Diagnosis(f"for {name} the weights are wrong: λ = max(L, leaf_floor * max(L)), over its mean")


@checker(
    [_weights_values],
    "matches motionlab.skeleton.joint_impact_weights on the skeleton, a chain and a random tree",
)
def check_impact_weights(fn: ImpactWeights) -> CheckResult:
    """Check ``fn(reach (J,), leaf_floor) -> λ (J,)``: each ``L_j`` raised to at least ``leaf_floor *
    max(L)``, then divided by the mean (eq. 23's joint impact weights, mean 1)."""
