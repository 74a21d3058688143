r"""Accuracy of sampled futures and trajectories: best-of-K ADE/FDE, their multimodal versions, end-point
error.

Following DLow (Yuan & Kitani 2020), with ``K`` sampled futures :math:`\hat x^{(k)}` ``(K, T, D)`` and the
true future :math:`x` ``(T, D)``:

.. math::
    \mathrm{ADE} = \min_k \frac{1}{T} \sum_t \lVert \hat x^{(k)}_t - x_t \rVert_2, \qquad
    \mathrm{FDE} = \min_k \lVert \hat x^{(k)}_T - x_T \rVert_2 .

The per-frame distance is the L2 norm over *all* coordinates of the frame (the whole pose vector, e.g.
``D = J·3`` joint coordinates), not a mean of per-joint distances. Trailing axes are flattened, so a
``(K, T, J, 3)`` input gives the same number as its ``(K, T, J·3)`` reshape.

**Multimodal ground truth** (DLow): the test windows whose start poses (last observed frame) lie within a
distance threshold of this window's start pose are all plausible futures. MMADE (MMFDE) is the mean, over
those futures, of the best-of-K ADE (FDE) against each.

**End-point error** ``dist_e`` (ODMO): the distance between the root position a trajectory was asked to
reach and the one it reached at its last frame.
"""

from __future__ import annotations

import numpy as np

from motionlab.validation import ArrayLike, as_float_array, check_scalar


def _samples_and_targets(
    samples: ArrayLike, targets: ArrayLike, func: str, targets_name: str, batched: bool
) -> tuple[np.ndarray, np.ndarray]:
    """``samples`` as ``(K, T, F)`` and targets as ``(M, T, F)`` (``M = 1`` when not batched), both
    flattened."""
    x = as_float_array(samples, "samples", func, min_ndim=3, layout="(K, T, D)")
    y = as_float_array(
        targets, targets_name, func, min_ndim=3 if batched else 2, layout="(M, T, D)" if batched else "(T, D)"
    )
    if not batched:
        y = y[None]
    if x.shape[1:] != y.shape[1:]:
        raise ValueError(
            f"{func}: each sample and {targets_name} must have the same (T, D) shape, "
            f"got {x.shape[1:]} and {y.shape[1:]}"
        )
    return x.reshape(x.shape[0], x.shape[1], -1), y.reshape(y.shape[0], y.shape[1], -1)


def _frame_distances(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Per-frame L2 distances ``(M, K, T)`` between samples ``(K, T, F)`` and targets ``(M, T, F)``."""
    return np.linalg.norm(x[None] - y[:, None], axis=-1)


def min_ade(samples: ArrayLike, target: ArrayLike) -> float:
    """Best-of-K average displacement error.

    Args:
        samples: ``K`` sampled futures ``(K, T, D)`` (or ``(K, T, J, 3)``).
        target: the true future ``(T, D)`` (or ``(T, J, 3)``).

    Returns:
        ``min_k mean_t ||samples[k, t] - target[t]||`` with the norm over the whole frame.
    """
    x, y = _samples_and_targets(samples, target, "min_ade", "target", batched=False)
    return float(_frame_distances(x, y).mean(axis=-1).min())


def min_fde(samples: ArrayLike, target: ArrayLike) -> float:
    """Best-of-K final displacement error: ``min_k ||samples[k, -1] - target[-1]||`` (shapes as
    :func:`min_ade`)."""
    x, y = _samples_and_targets(samples, target, "min_fde", "target", batched=False)
    return float(_frame_distances(x[:, -1:], y[:, -1:])[..., 0].min())


def multimodal_ground_truth(start_poses: ArrayLike, futures: ArrayLike, threshold: float) -> list[np.ndarray]:
    """DLow's multimodal ground truth: for each window, the futures of all windows that start alike.

    Args:
        start_poses: the last observed pose of each of ``N`` test windows ``(N, P)`` (or ``(N, J, 3)``).
        futures: the true future of each window ``(N, T, D)``.
        threshold: windows ``j`` with ``||start_j - start_i|| < threshold`` (strictly, L2 over the whole
            pose) form window ``i``'s set; it always contains ``i`` itself.

    Returns:
        ``N`` float64 arrays; entry ``i`` has shape ``(M_i, T, D)``, its rows in window order.
    """
    func = "multimodal_ground_truth"
    starts = as_float_array(start_poses, "start_poses", func, min_ndim=2, layout="(N, P)")
    ahead = as_float_array(futures, "futures", func, min_ndim=3, layout="(N, T, D)")
    if starts.shape[0] != ahead.shape[0]:
        raise ValueError(
            f"{func}: start_poses and futures must have the same N, got {starts.shape[0]} and "
            f"{ahead.shape[0]}"
        )
    radius = float(check_scalar(threshold, "threshold", func, minimum=0, include_minimum=False))
    from scipy.spatial.distance import cdist  # scipy.spatial costs 0.2 s to import: on first use

    distances = cdist(starts.reshape(starts.shape[0], -1), starts.reshape(starts.shape[0], -1))
    return [ahead[np.flatnonzero(row < radius)] for row in distances]


def mmade(samples: ArrayLike, gt_futures: ArrayLike) -> float:
    """Multimodal ADE of one window: mean over its ``M`` ground-truth futures of the best-of-K ADE.

    Args:
        samples: ``K`` sampled futures ``(K, T, D)``.
        gt_futures: the window's multimodal ground truth ``(M, T, D)`` (an entry of
            :func:`multimodal_ground_truth`).
    """
    x, y = _samples_and_targets(samples, gt_futures, "mmade", "gt_futures", batched=True)
    return float(_frame_distances(x, y).mean(axis=-1).min(axis=1).mean())


def mmfde(samples: ArrayLike, gt_futures: ArrayLike) -> float:
    """Multimodal FDE of one window: mean over ground-truth futures of the best-of-K FDE (shapes as
    :func:`mmade`)."""
    x, y = _samples_and_targets(samples, gt_futures, "mmfde", "gt_futures", batched=True)
    return float(_frame_distances(x[:, -1:], y[:, -1:])[..., 0].min(axis=1).mean())


def _end_point_offsets(trajectories: ArrayLike, targets: ArrayLike, func: str) -> np.ndarray:
    paths = as_float_array(trajectories, "trajectories", func, ndim=3, layout="(N, T, C)")
    ends = as_float_array(targets, "targets", func, ndim=2, layout="(N, C)")
    expected = (paths.shape[0], paths.shape[2])
    if ends.shape != expected:
        raise ValueError(f"{func}: targets must be {expected} to match trajectories, got {ends.shape}")
    return paths[:, -1] - ends


def end_point_error(trajectories: ArrayLike, targets: ArrayLike) -> float:
    """Mean distance between each trajectory's last position and its requested end point (in the units of
    the positions; ODMO's ``dist_e`` is the mean *squared* distance, :func:`end_point_mse`).

    Args:
        trajectories: root trajectories ``(N, T, C)`` with ``C`` coordinates (2 for the ground plane, 3 for
        space). targets: requested end positions ``(N, C)``.
    """
    offsets = _end_point_offsets(trajectories, targets, "end_point_error")
    return float(np.linalg.norm(offsets, axis=-1).mean())


def end_point_mse(trajectories: ArrayLike, targets: ArrayLike) -> float:
    """ODMO's ``dist_e`` (§4.4, Table 4): the mean squared distance between each trajectory's last position
    and its requested end point (squared units of the positions). Arguments as :func:`end_point_error`."""
    offsets = _end_point_offsets(trajectories, targets, "end_point_mse")
    return float((offsets**2).sum(axis=-1).mean())
