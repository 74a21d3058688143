"""Chapter 04's exercise: how far each joint's rotation reaches, the ``L_k`` behind the Motion Cell's joint
weights (eq. 23), checked against :func:`motionlab.skeleton.subtree_reach`."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from motionlab.exercises.checking import CheckResult, Diagnosis, run_checks
from motionlab.skeleton import average_skeleton, subtree_reach

SubtreeReach = Callable[[Sequence[int], np.ndarray], np.ndarray]


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
            raise Diagnosis(f"for {name} return one L_k per joint, shape {want.shape}, got {got.shape}")
        if np.allclose(got, want):
            continue
        if np.allclose(got, _subtree_sum(parents, bones)):
            raise Diagnosis(
                f"for {name} you added up every bone below joint k; L_k is the longest single path to an end "
                "effector (a max over the children, not a sum)"
            )
        if np.allclose(got, want + bones):
            raise Diagnosis(f"for {name} each L_k includes the joint's own bone; start from its children")
        leaves = [j for j in range(len(parents)) if j not in parents]
        if not np.allclose(got[leaves], 0):
            raise Diagnosis(f"for {name} the end effectors {leaves} should have L_k = 0: they move no joint")
        first = int(np.flatnonzero(~np.isclose(got, want))[0])
        raise Diagnosis(
            f"for {name} joint {first} has L = {got[first]:.3f}, not {want[first]:.3f}: visit children "
            "before their parents (from the last joint back), so a child's reach is known when its parent "
            "needs it"
        )


def check_subtree_reach(fn: SubtreeReach) -> CheckResult:
    """Check ``fn(parents (J,), bone_lengths (J,)) -> L (J,)``, the longest path from each joint to an end
    effector (``bone_lengths[j]``: the length of the bone from joint ``j``'s parent to ``j``)."""
    return run_checks(
        "subtree_reach",
        fn,
        [_reach_values],
        "matches motionlab.skeleton.subtree_reach on the skeleton, a chain and a random tree",
    )
