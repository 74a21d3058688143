"""Input checks for the plotting functions: positions and parent lists, as NumPy, with clear errors.

Every plotting function accepts NumPy arrays or torch tensors (any device, with or without grad). The
conversion and the finiteness check are :func:`motionlab.validation.as_float_array`; the checks here add
the layouts of positions and parents. Following :mod:`motionlab.validation`, a wrong type or dtype raises
``TypeError`` and a wrong shape or value ``ValueError``, naming the function, the argument and what it got,
for example ``animate: motion 1 must have shape (T, 22, 3), got (30, 21, 3)``.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np
import torch

from motionlab.validation import as_float_array, check_scalar

ArrayLike = np.ndarray | torch.Tensor
"""Joint positions as a NumPy array or a torch tensor."""


def as_sequence(positions: ArrayLike, name: str, func: str) -> np.ndarray:
    """Positions ``(T, J, 3)`` or one pose ``(J, 3)`` as a ``(T, J, 3)`` array (T >= 1, J >= 1)."""
    array = as_float_array(positions, name, func, allow_empty=True)
    if array.ndim == 2:
        array = array[None]
    if array.ndim != 3 or array.shape[-1] != 3 or array.shape[0] == 0 or array.shape[1] == 0:
        raise ValueError(
            f"{func}: {name} must have shape (T, J, 3) or (J, 3), got {tuple(np.shape(positions))}"
        )
    return array


def as_pose(pose: ArrayLike, name: str, func: str) -> np.ndarray:
    """One pose ``(J, 3)`` (J >= 1)."""
    array = as_float_array(pose, name, func, allow_empty=True)
    if array.ndim != 2 or array.shape[-1] != 3 or array.shape[0] == 0:
        raise ValueError(
            f"{func}: {name} must have shape (J, 3) (one pose; use filmstrip or animate for "
            f"a sequence), got {tuple(array.shape)}"
        )
    return array


def as_sequence_list(motions: ArrayLike | Sequence[ArrayLike], func: str) -> list[np.ndarray]:
    """Several motions: a list of ``(T_i, J, 3)``, one ``(N, T, J, 3)`` array, or one ``(T, J, 3)`` motion.

    All motions must have the same joint count J; their lengths may differ.
    """
    if isinstance(motions, (np.ndarray, torch.Tensor)):
        ndim = motions.ndim
        if ndim == 4:
            items = list(motions)
        elif ndim in (2, 3):
            items = [motions]
        else:
            raise ValueError(
                f"{func}: expected positions (T, J, 3), (N, T, J, 3) or a list of (T, J, 3), "
                f"got shape {tuple(motions.shape)}"
            )
    else:
        items = list(motions)
    if not items:
        raise ValueError(f"{func}: no motions given")
    out = [as_sequence(m, f"motion {i}", func) for i, m in enumerate(items)]
    joints = out[0].shape[1]
    for i, m in enumerate(out):
        if m.shape[1] != joints:
            raise ValueError(
                f"{func}: motion {i} must have shape (T, {joints}, 3) like motion 0, got {m.shape}"
            )
    return out


def as_parents(parents: Sequence[int] | ArrayLike, num_joints: int, func: str) -> np.ndarray:
    """Parent indices ``(J,)``: ``-1`` for roots, otherwise another joint's index."""
    values = parents.tolist() if isinstance(parents, (np.ndarray, torch.Tensor)) else list(parents)
    if len(values) != num_joints:
        raise ValueError(
            f"{func}: parents has {len(values)} entries but the positions have {num_joints} joints"
        )
    for j, p in enumerate(values):
        check_scalar(p, f"parents[{j}]", func, kind=numbers.Integral)
        if not -1 <= p < num_joints or p == j:
            raise ValueError(f"{func}: parents[{j}] must be -1 or the index of another joint, got {p!r}")
    return np.asarray(values, dtype=np.int64)


def series_colors(
    colors: Sequence[str] | None, labels: Sequence[str] | None, count: int, func: str
) -> list[str]:
    """One colour per motion (default ``C0, C1, ...``), after checking that ``colors`` and ``labels`` (when
    given) have one entry per motion."""
    colors = [f"C{i % 10}" for i in range(count)] if colors is None else list(colors)
    if len(colors) != count:
        raise ValueError(f"{func}: got {len(colors)} colors for {count} motions")
    if labels is not None and len(labels) != count:
        raise ValueError(f"{func}: got {len(labels)} labels for {count} motions")
    return colors
