r"""Evaluating trajectory completion: DLow's metrics against the number of given trajectories, and more.

All functions take windows in the TrajeVAE representation ``(N, T, J * 3)`` (frame 0 the initial pose) and a
completion model with the common sampling interface
``model.sample(initial_pose (B, J*3), trajectories (B, F, J*3), n_samples, temperature, generator)`` →
``(B, K, F, J*3)`` (TrajeVAE and both baselines).

**DLow metrics** of one window with ``K`` samples (:mod:`motionlab.metrics`): APD (diversity of the samples),
ADE and FDE (best of ``K`` against the true frames), MMADE and MMFDE (the same against every test window whose
initial pose lies within ``threshold`` of this one, the multimodal ground truth). All distances are the L2
norm over the whole ``J * 3`` pose of a frame, in metres, on the completed frames ``1 .. T - 1``. A table
entry is the mean over the test windows with the half-width of its 95% Student-t interval (each window is
one sample set of fixed size ``K``).

**Number of trajectories** ``k`` (the chapters' :math:`J_g`, the number of given trajectories; TrajeVAE's
:math:`k`): the first ``k`` joints of
:data:`~motionlab.models.trajevae.masks.FULL_ORDER` are given (k = 1..4: right foot, left foot, right hand,
left hand, the paper's Table 1 and Figure 6; up to all 22 joints).

**Other sequences' trajectories** (the paper's Table 5): the initial pose of window ``i`` with the ``k``
trajectories of another window ``j`` (the one whose given joints start closest), each trajectory moved so that
it starts where that joint is in ``i``'s initial pose. We measure how far the completions' given joints stay
from the requested trajectories, their APD, and which action the evaluation classifier recognises.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np
import torch
from torch import Tensor

from motionlab.metrics import apd, mean_ci, min_ade, min_fde, mmade, mmfde, multimodal_ground_truth
from motionlab.models.trajevae.data import completion_task
from motionlab.models.trajevae.masks import (
    FULL_ORDER,
    channel_mask,
    check_mask,
    first_joints,
    given_trajectories,
    hidden_poses,
)
from motionlab.models.trajevae.model import Completer
from motionlab.validation import check_scalar, check_tensor

#: Samples per input window, as in DLow and the paper.
N_SAMPLES = 50

#: The paper's Table 1: no trajectory, then right foot, left foot, right hand, left hand.
PAPER_KS: tuple[int, ...] = (0, 1, 2, 3, 4)

#: Figure 6: from no trajectory to all 22 joints.
FIGURE6_KS: tuple[int, ...] = (0, 1, 2, 3, 4, 6, 8, 11, 16, 22)

#: Windows whose initial poses are closer than this (metres, L2 over the whole pose) share their futures in
#: MMADE / MMFDE (DLow's multimodal ground truth; the paper's code uses 0.5).
MULTIMODAL_THRESHOLD = 0.5

#: Windows completed at once (bounds the memory of ``K`` samples per window).
CHUNK = 16

DLOW_METRICS = ("apd", "ade", "fde", "mmade", "mmfde")

#: One model's k sweep: ``{k: {metric: (mean, 95% CI half-width)}}`` (:func:`sweep_given_joints`).
Sweep = dict[int, dict[str, tuple[float, float]]]


def complete(
    model: Completer,
    initial_pose: Tensor,
    trajectories: Tensor,
    n_samples: int,
    generator: torch.Generator,
    temperature: float = 1.0,
) -> Tensor:
    """Completed windows ``(N, K, T, J * 3)`` (frame 0 the initial pose), sampled in chunks of :data:`CHUNK`.

    Args:
        initial_pose: ``(N, J * 3)``; trajectories: ``(N, F, J * 3)`` with zeros for joints to complete.
    """
    where = "complete"
    check_tensor(initial_pose, "initial_pose", where, ndim=2)
    check_tensor(trajectories, "trajectories", where, ndim=3)
    check_scalar(n_samples, "n_samples", where, kind=numbers.Integral, minimum=1)
    parts = []
    for begin in range(0, initial_pose.shape[0], CHUNK):
        start, given = initial_pose[begin : begin + CHUNK], trajectories[begin : begin + CHUNK]
        future = model.sample(start, given, n_samples, temperature, generator)
        parts.append(torch.cat([start[:, None, None, :].expand(-1, n_samples, 1, -1), future], dim=2))
    return torch.cat(parts)


def multimodal_futures(windows: Tensor, threshold: float = MULTIMODAL_THRESHOLD) -> list[np.ndarray]:
    """DLow's multimodal ground truth of each window: the futures ``(M_i, F, J * 3)`` of windows starting
    alike."""
    check_tensor(windows, "windows", "multimodal_futures", ndim=3)
    check_scalar(threshold, "threshold", "multimodal_futures", minimum=0)
    return multimodal_ground_truth(windows[:, 0].numpy(), windows[:, 1:].numpy(), threshold)


def dlow_metrics(samples: Tensor, windows: Tensor, multimodal: Sequence[np.ndarray]) -> dict[str, np.ndarray]:
    """Per-window APD, ADE, FDE, MMADE, MMFDE: ``{name: (N,)}``.

    Args:
        samples: completed windows ``(N, K, T, J * 3)`` (frame 0 is skipped); windows: the truth ``(N, T, J *
        3)``; multimodal: :func:`multimodal_futures` of the windows.
    """
    where = "dlow_metrics"
    check_tensor(windows, "windows", where, ndim=3)
    check_tensor(samples, "samples", where, trailing=tuple(windows.shape[1:]), ndim=4)
    if samples.shape[0] != windows.shape[0] or len(multimodal) != windows.shape[0]:
        raise ValueError(
            f"{where}: samples {tuple(samples.shape)} and {len(multimodal)} multimodal sets must match the "
            f"{windows.shape[0]} windows"
        )
    future = samples[:, :, 1:].detach().float().numpy()
    truth = windows[:, 1:].float().numpy()
    rows = {name: [] for name in DLOW_METRICS}
    for i in range(truth.shape[0]):
        rows["apd"].append(apd(future[i]) if future.shape[1] > 1 else 0.0)
        rows["ade"].append(min_ade(future[i], truth[i]))
        rows["fde"].append(min_fde(future[i], truth[i]))
        rows["mmade"].append(mmade(future[i], multimodal[i]))
        rows["mmfde"].append(mmfde(future[i], multimodal[i]))
    return {name: np.asarray(values) for name, values in rows.items()}


def summarise(values: dict[str, np.ndarray]) -> dict[str, tuple[float, float]]:
    """``{name: (mean, 95% CI half-width)}`` over windows of per-window metric values ``{name: (N,)}``."""
    return {name: mean_ci(v) if v.shape[0] > 1 else (float(v.mean()), 0.0) for name, v in values.items()}


def sweep_given_joints(
    model: Completer,
    windows: Tensor,
    ks: Sequence[int] = PAPER_KS,
    n_samples: int = N_SAMPLES,
    seed: int = 0,
    multimodal: Sequence[np.ndarray] | None = None,
    order: Sequence[str] = FULL_ORDER,
) -> Sweep:
    """DLow metrics with ``k`` given trajectories for each ``k`` in ``ks``: ``{k: {metric: (mean, ci95)}}``.

    The samples of ``k`` come from a generator seeded with ``(seed, k)``, so a row does not depend on the
    others.
    """
    check_tensor(windows, "windows", "sweep_given_joints", ndim=3)
    multimodal = multimodal_futures(windows) if multimodal is None else multimodal
    return {
        k: summarise(given_joints_metrics(model, windows, k, n_samples, seed, multimodal, order)) for k in ks
    }


def given_joints_metrics(
    model: Completer,
    windows: Tensor,
    k: int,
    n_samples: int = N_SAMPLES,
    seed: int = 0,
    multimodal: Sequence[np.ndarray] | None = None,
    order: Sequence[str] = FULL_ORDER,
) -> dict[str, np.ndarray]:
    """Per-window DLow metrics ``{metric: (N,)}`` with the first ``k`` joints of ``order`` given: the values
    that :func:`sweep_given_joints` (same ``seed``) summarises in its row ``k``, e.g. for a paired comparison
    of two ``k`` on the same windows."""
    check_tensor(windows, "windows", "given_joints_metrics", ndim=3)
    multimodal = multimodal_futures(windows) if multimodal is None else multimodal
    initial_pose, trajectories = completion_task(windows, first_joints(k, order))
    generator = torch.Generator().manual_seed(int(np.random.SeedSequence([seed, k]).generate_state(1)[0]))
    samples = complete(model, initial_pose, trajectories, n_samples, generator)
    return dlow_metrics(samples, windows, multimodal)


def ratio_and_worst_step(values: Sequence[float]) -> tuple[float, float]:
    """For a metric listed against k = 0, 1, ...: ``values[-1] / values[0]`` and the largest ``values[k+1] /
    values[k]``."""
    values = [float(v) for v in values]
    if len(values) < 2 or any(v <= 0 for v in values):
        raise ValueError(f"ratio_and_worst_step: needs at least two positive values, got {values}")
    return values[-1] / values[0], max(b / a for a, b in zip(values[:-1], values[1:]))


# ----------------------------------------------------------------------------------------------------
# Table 5: the same initial pose, other sequences' trajectories


def borrowed_trajectories(windows: Tensor, mask: Tensor) -> tuple[Tensor, Tensor, Tensor]:
    """Give each window another window's trajectories, each joint's moved to start at this window's joint.

    Args:
        windows: ``(N, T, J * 3)``, ``N >= 2``; mask: ``(J,)`` bool, the given joints (at least one).

    Returns:
        ``trajectories`` ``(N, F, J * 3)`` (zeros outside ``mask``), ``donor`` ``(N,)`` (the window each
        came from: the other window whose given joints start closest) and ``start_gap`` ``(N,)``, the
        distance (metres, over the given joints) that was removed by moving them.
    """
    where = "borrowed_trajectories"
    check_tensor(windows, "windows", where, ndim=3)
    if windows.shape[0] < 2:
        raise ValueError(f"{where}: needs at least 2 windows to borrow from, got {windows.shape[0]}")
    check_mask(mask, "mask", where, shape=(windows.shape[-1] // 3,))
    if not bool(mask.any()):
        raise ValueError(f"{where}: mask must give at least one joint")
    channels = channel_mask(mask)
    starts = windows[:, 0, channels]
    distance = torch.cdist(starts.double(), starts.double())
    distance.fill_diagonal_(float("inf"))
    start_gap, donor = distance.min(dim=1)
    moved = windows[donor, 1:] - windows[donor, :1] + windows[:, :1]
    return moved * channels.to(moved.dtype), donor, start_gap.float()


def follow_error(samples: Tensor, trajectories: Tensor, mask: Tensor) -> np.ndarray:
    """Mean distance (metres) between the completions' given joints and the requested trajectories, per
    window.

    Args:
        samples: ``(N, K, T, J * 3)`` (frame 0 skipped); trajectories: ``(N, F, J * 3)``; mask: ``(J,)`` bool.
    """
    where = "follow_error"
    check_tensor(samples, "samples", where, ndim=4)
    check_tensor(trajectories, "trajectories", where, ndim=3)
    check_mask(mask, "mask", where, shape=(samples.shape[-1] // 3,))
    joints = torch.nonzero(mask).flatten()
    generated = samples[:, :, 1:].unflatten(-1, (-1, 3))[..., joints, :]
    requested = trajectories.unflatten(-1, (-1, 3))[:, None, :, joints, :]
    return (generated - requested).norm(dim=-1).mean(dim=(1, 2, 3)).numpy()


def decoded_means_error(model: torch.nn.Module, windows: Tensor, k: int) -> dict[str, float]:
    """How far TrajeVAE's learned prior is from its posterior, seen through the decoder, with the first ``k``
    joints given.

    Returns:
        ``posterior mean`` and ``prior mean``: the mean squared error (m², per number) of decoding the
        posterior's mean (what training sees) and the prior's mean (what generation sees) on ``windows``
        ``(N, T, J * 3)``; ``sigma_p`` and ``sigma_q``: the two distributions' mean standard deviations.
    """
    check_tensor(windows, "windows", "decoded_means_error", ndim=3)
    mask = first_joints(k).expand(windows.shape[0], -1)
    start, future = windows[:, 0], windows[:, 1:]
    with torch.no_grad():
        embedding = model.initial_pose_encoder(start)
        prior = model.prior(given_trajectories(future, mask), embedding)
        posterior = model.posterior(hidden_poses(future, mask), embedding)
        errors = {
            name: ((model.decoder(mu, start, embedding) - future) ** 2).mean().item()
            for name, mu in (("posterior mean", posterior.mu), ("prior mean", prior.mu))
        }
        return {
            **errors,
            "sigma_p": prior.logvar.mul(0.5).exp().mean().item(),
            "sigma_q": posterior.logvar.mul(0.5).exp().mean().item(),
        }


def upsample_frames(windows: Tensor, factor: int) -> Tensor:
    """Linear interpolation to ``factor`` times the frame rate: ``(..., T, C) -> (..., factor * T, C)``.

    Frame ``factor * t + s`` lies ``s / factor`` of the way from frame ``t`` to ``t + 1``; after the last
    frame the motion continues with its last velocity (so a window keeps its duration).
    """
    check_scalar(factor, "factor", "upsample_frames", kind=numbers.Integral, minimum=1)
    check_tensor(windows, "windows", "upsample_frames", min_leading=2)
    if windows.shape[-2] < 2:
        raise ValueError(
            f"upsample_frames: windows need a frame axis of at least 2 frames, got {tuple(windows.shape)}"
        )
    following = torch.cat([windows[..., 1:, :], 2 * windows[..., -1:, :] - windows[..., -2:-1, :]], dim=-2)
    weights = torch.arange(factor, dtype=windows.dtype) / factor
    frames = windows[..., None, :] + weights[:, None] * (following - windows)[..., None, :]
    return frames.flatten(-3, -2)
