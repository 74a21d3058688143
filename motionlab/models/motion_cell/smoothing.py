"""Smoothing the boundaries between generated motion words (ours; the paper has no such step).

Each motion word is decoded from its own latent on its own. Where neighbouring words do not join up, the
pose *steps* at the word boundary: a clip becomes a staircase with one step every ``l`` frames, its joint
speed ripples at ``fps / l`` (10 Hz for the paper's ``l = 3`` at 30 fps) and its jerk rises. Chapter 04
measures this on the samples of its Motion Cell as decoded, and on its reconstructions of
real clips; the paper reports no such artefact.

:func:`smooth_word_boundaries` takes generated pose vectors ``(B, T, 90)`` and

1. makes the quaternions continuous in time (:func:`continuous_poses`: ``q`` and ``-q`` are the same
   rotation; differences are taken between neighbours on the same hemisphere);
2. finds the excess step at every boundary frame ``s``, a multiple of ``l``: the step ``x_s - x_{s-1}``
   minus the mean of the steps on either side, ``Δ_s - (Δ_{s-1} + Δ_{s+1}) / 2`` with ``Δ_t = x_t - x_{t-1}``;
3. spreads that excess over the ``2 l - 1`` steps around the boundary with the triangular weights of two
   ``l``-frame boxes (``[1, 2, 3, 2, 1] / 9`` for ``l = 3``), keeping the total displacement, and integrates
   the steps back into poses (what the words do between boundaries is kept);
4. averages every ``l`` consecutive frames (a centred moving average: its frequency response is zero at
   ``fps / l`` and its multiples, where the boundary steps repeat);
5. renormalises the quaternions (:func:`unit_poses`).

Everything is in pose-vector space (unit quaternions and standardised root channels); the same input
gives bitwise the same output.
"""

from __future__ import annotations

import numbers

import torch
import torch.nn.functional as F
from torch import Tensor

from motionlab.data.rig import continuous_quaternions
from motionlab.geometry import quat_normalize
from motionlab.models.motion_cell.data import ROOT_DIM
from motionlab.models.motion_cell.heads import assemble_pose
from motionlab.validation import check_scalar, check_tensor


def _split(poses: Tensor) -> tuple[Tensor, Tensor]:
    """Quaternions ``(B, T, J - 1, 4)`` and root channels ``(B, T, 6)`` of pose vectors ``(B, T, 90)``."""
    return poses[..., :-ROOT_DIM].unflatten(-1, (-1, 4)), poses[..., -ROOT_DIM:]


def continuous_poses(poses: Tensor) -> Tensor:
    """Pose vectors ``(B, T, 90)`` whose quaternions have their signs flipped along ``T`` so that neighbours
    have a dot product ``>= 0`` (the same rotations; :func:`~motionlab.data.rig.continuous_quaternions`, so
    no gradient flows)."""
    quaternions, root = _split(poses)
    flipped = continuous_quaternions(quaternions.detach().cpu().numpy(), time_axis=1)
    return assemble_pose(torch.as_tensor(flipped, dtype=poses.dtype, device=poses.device), root)


def unit_poses(x: Tensor) -> Tensor:
    """Pose vectors ``(B, T, 90)`` with every quaternion normalised to unit length."""
    quaternions, root = _split(x)
    return assemble_pose(quat_normalize(quaternions), root)


def triangle_weights(length: int) -> Tensor:
    """The ``2 length - 1`` weights of two ``length``-frame boxes convolved (sum 1), ``(2 length - 1,)``."""
    box = torch.full((1, 1, length), 1.0 / length)
    return F.conv1d(box, box, padding=length - 1).flatten()


def spread_boundary_steps(x: Tensor, word_length: int) -> Tensor:
    """Signals ``(B, T, D)`` whose excess step at each word boundary is spread over its neighbours.

    Boundaries closer than ``word_length`` frames to either end are left as they are.
    """
    steps = x[:, 1:] - x[:, :-1]  # steps[:, k - 1] = x_k - x_{k-1}
    n_steps, reach = steps.shape[1], word_length - 1
    boundary = torch.arange(word_length - 1, n_steps, word_length)  # the steps x_s - x_{s-1}, s = n l
    boundary = boundary[(boundary >= reach) & (boundary + reach <= n_steps - 1)]
    excess = torch.zeros_like(steps)
    excess[:, boundary] = steps[:, boundary] - 0.5 * (steps[:, boundary - 1] + steps[:, boundary + 1])
    batch, _, channels = x.shape
    flat = excess.transpose(1, 2).reshape(batch * channels, 1, n_steps)
    spread = F.conv1d(flat, triangle_weights(word_length).view(1, 1, -1), padding=reach)
    spread = spread.reshape(batch, channels, n_steps).transpose(1, 2)
    return torch.cat([x[:, :1], x[:, :1] + (steps - excess + spread).cumsum(dim=1)], dim=1)


def moving_average(x: Tensor, width: int) -> Tensor:
    """The mean of ``width`` consecutive frames ``(B, T, D)`` (centred; the end frames are repeated)."""
    before, after = (width - 1) // 2, width // 2
    padded = torch.cat([x[:, :1].expand(-1, before, -1), x, x[:, -1:].expand(-1, after, -1)], dim=1)
    return padded.unfold(1, width, 1).mean(dim=-1)


def smooth_word_boundaries(poses: Tensor, word_length: int) -> Tensor:
    """Generated pose vectors ``(B, T, (J - 1) * 4 + 6)`` with the word-boundary steps smoothed away.

    See the module notes for the five steps. ``word_length`` 1 (no words) returns ``poses`` unchanged, as
    does a clip shorter than three words.
    """
    check_tensor(poses, "poses", "smooth_word_boundaries", ndim=3)
    check_scalar(word_length, "word_length", "smooth_word_boundaries", kind=numbers.Integral, minimum=1)
    if (poses.shape[-1] - ROOT_DIM) % 4 or poses.shape[-1] <= ROOT_DIM:
        raise ValueError(
            f"smooth_word_boundaries: poses must be (B, T, (J - 1) * 4 + {ROOT_DIM}), "
            f"got {tuple(poses.shape)}"
        )
    if word_length == 1 or poses.shape[1] < 3 * word_length:
        return poses
    spread = spread_boundary_steps(continuous_poses(poses), word_length)
    return unit_poses(moving_average(spread, word_length))
