"""Chapter 02's exercise: forward kinematics of one chain, checked against
:func:`motionlab.skeleton.forward_kinematics`."""

from __future__ import annotations

from collections.abc import Callable

import torch

from motionlab import geometry as geo
from motionlab.exercises.checking import (
    CheckResult,
    Diagnosis,
    as_result,
    checker,
    close,
    random_unit_quaternions,
)
from motionlab.skeleton import forward_kinematics

ChainFK = Callable[[torch.Tensor, torch.Tensor, torch.Tensor], torch.Tensor]


def _chain_inputs(frames: int, joints: int, seed: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    generator = torch.Generator().manual_seed(seed)
    rotations = random_unit_quaternions((frames, joints), seed)
    root = torch.randn(frames, 3, generator=generator, dtype=torch.float64)
    offsets = torch.randn(joints, 3, generator=generator, dtype=torch.float64) * 0.3
    return rotations, root, offsets


def _reference(rotations: torch.Tensor, root: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
    parents = list(range(-1, offsets.shape[0] - 1))
    return forward_kinematics(rotations, root, offsets, parents)[0]


def _own_rotation_variant(rotations: torch.Tensor, root: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
    """The common mistake: each joint's offset turned by its *own* global rotation."""
    positions, frame = [root], rotations[..., 0, :]
    for j in range(1, offsets.shape[0]):
        frame = geo.quat_mul(frame, rotations[..., j, :])
        positions.append(positions[-1] + geo.quat_apply(frame, offsets[j].expand_as(root)))
    return torch.stack(positions, dim=-2)


def _reversed_composition(rotations: torch.Tensor, root: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
    """The other common mistake: ``G_j = q_j ⊗ G_{j-1}``."""
    positions, frame = [root], rotations[..., 0, :]
    for j in range(1, offsets.shape[0]):
        positions.append(positions[-1] + geo.quat_apply(frame, offsets[j].expand_as(root)))
        frame = geo.quat_mul(rotations[..., j, :], frame)
    return torch.stack(positions, dim=-2)


def _chain_values(fn: ChainFK) -> None:
    rotations, root, offsets = _chain_inputs(5, 4, 1)
    got = as_result(fn(rotations, root, offsets), "chain_positions")
    if got.shape != (5, 4, 3):
        raise Diagnosis(
            f"rotations (5, 4, 4), root (5, 3) and offsets (4, 3) should give positions (5, 4, 3), "
            f"got {tuple(got.shape)}"
        )
    want = _reference(rotations, root, offsets)
    if close(got, want):
        return
    if not close(got[:, 0], root):
        raise Diagnosis("joint 0 (the root) should sit at the root position")
    if close(got, _own_rotation_variant(rotations, root, offsets)):
        raise Diagnosis(
            "each offset is turned by its own joint's global rotation; joint j's offset o_j is turned by its "
            "parent's, G_{j-1}: a joint's own rotation moves its children, not itself"
        )
    if close(got, _reversed_composition(rotations, root, offsets)):
        raise Diagnosis("the global rotations compose in the wrong order: G_j = G_{j-1} ⊗ q_j (parent first)")
    first = next(j for j in range(4) if not close(got[:, j], want[:, j]))
    raise Diagnosis(f"joint {first} is the first one in the wrong place (joints before it are right)")


def _chain_batches_and_gradient(fn: ChainFK) -> None:
    rotations, root, offsets = _chain_inputs(6, 3, 2)
    rotations = rotations.reshape(2, 3, 3, 4).requires_grad_(True)
    root = root.reshape(2, 3, 3)
    got = as_result(fn(rotations, root, offsets), "chain_positions")
    if got.shape != (2, 3, 3, 3) or not close(got, _reference(rotations.detach(), root, offsets)):
        raise Diagnosis(
            "with two leading dimensions (clips, frames) the result is wrong or mis-shaped: use q[..., j, :] "
            "so any leading dimensions work"
        )
    if not got.requires_grad:
        raise Diagnosis("no gradient flows to the rotations: compute with torch operations only")


@checker(
    [_chain_values, _chain_batches_and_gradient],
    "matches motionlab.skeleton.forward_kinematics on a chain, batched, with gradients",
)
def check_chain_positions(fn: ChainFK) -> CheckResult:
    """Check ``fn(rotations (..., K, 4), root (..., 3), offsets (K, 3)) -> positions (..., K, 3)`` for a chain
    in which joint ``j``'s parent is ``j - 1``."""
