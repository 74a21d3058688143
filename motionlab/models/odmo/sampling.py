"""Generation: from codes to 30 fps joint positions, by mode, and on demand.

:class:`ODMOSampler` is what the evaluation, the widgets and the benchmark use: a trained ODMO model with a
:class:`~motionlab.models.odmo.modes.ModeSet` (mode-preserving, conventional or prior). It draws codes from
the modes, picks their end points, runs the generators and decodes the features to global joint positions
at the data's frame rate.

**On-demand customisation** (:func:`mode_interpolation`, :func:`to_end_point`, :func:`styles_to_end_point`):
walk between two modes, send a motion to a chosen end point, several styles to one end point. All three
only choose codes and end points; the trained generators do the rest (through :meth:`ODMOSampler.generate`).
The code space is what makes them work: the codes of a discovered mode share a style, the straight line
between two mode centres stays inside the class's region (the contrastive springs keep classes apart), and
the end point is an input of the trajectory generator, separate from the code.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import torch
from torch import Tensor

from motionlab.models.odmo.data import ODMOData, to_positions
from motionlab.models.odmo.model import ODMO
from motionlab.models.odmo.modes import (
    K_VALUES,
    ModeSet,
    discover_modes,
    prior_modes,
    single_gaussian_modes,
)
from motionlab.validation import check_choice, check_scalar

SAMPLERS = ("modes", "conventional", "prior")
"""Kinds of code samplers: mode-preserving (ODMO), one Gaussian per class (ODMO_conv), ``N(0, I)`` (VAE)."""


class Samples(NamedTuple):
    """Generated clips: ``positions (N, T, J, 3)`` at the data's frame rate, ``features (N, T_model, F)``
    (metres), the trajectory generator's ``trajectory (N, T_model, 3)`` (metres; the motion's own root path is
    in ``features``), ``codes (N, D)``, ``action (N,)``, ``mode (N,)`` (the mode each code was drawn from,
    within its class), ``end_points (N, 3)``."""

    positions: Tensor
    features: Tensor
    trajectory: Tensor
    codes: np.ndarray
    action: np.ndarray
    mode: np.ndarray
    end_points: np.ndarray


@torch.no_grad()
def encode_clips(model: ODMO, data: ODMOData) -> np.ndarray:
    """The code means ``μ`` ``(N, D)`` of prepared clips (the model in evaluation mode)."""
    was_training = model.training
    model.eval()
    try:
        mu, _ = model.encode(data.features)
    finally:
        model.train(was_training)
    return mu.numpy().astype(np.float64)


def build_modes(
    kind: str,
    codes: np.ndarray,
    data: ODMOData,
    n_classes: int,
    seed: int = 0,
    mode_counts: Sequence[int] = K_VALUES,
) -> ModeSet:
    """The :class:`ModeSet` of sampler ``kind`` (one of :data:`SAMPLERS`) over training codes ``(N, D)``;
    ``mode_counts``: the component counts mode discovery tries (``kind="modes"``)."""
    check_choice(kind, "kind", "build_modes", SAMPLERS)
    action, ends = data.action.numpy(), data.end_point.numpy()
    if kind == "modes":
        return discover_modes(codes, action, ends, n_classes, mode_counts, seed=seed)
    if kind == "conventional":
        return single_gaussian_modes(codes, action, ends, n_classes)
    return prior_modes(codes, action, ends, n_classes)


@dataclass(frozen=True, eq=False)
class ODMOSampler:
    """A trained model with its modes and the decoding settings of its data (frame stride, floor
    clearance)."""

    model: ODMO
    modes: ModeSet
    frame_stride: int
    floor_clearance: float

    @classmethod
    def from_data(
        cls,
        model: ODMO,
        data: ODMOData,
        kind: str = "modes",
        seed: int = 0,
        mode_counts: Sequence[int] = K_VALUES,
    ) -> ODMOSampler:
        """Encode ``data`` (the training clips), build the modes of ``kind`` and wrap everything
        (``mode_counts``: as for :func:`build_modes`)."""
        return cls.from_codes(model, encode_clips(model, data), data, kind, seed, mode_counts)

    @classmethod
    def from_codes(
        cls,
        model: ODMO,
        codes: np.ndarray,
        data: ODMOData,
        kind: str = "modes",
        seed: int = 0,
        mode_counts: Sequence[int] = K_VALUES,
    ) -> ODMOSampler:
        """:meth:`from_data` with the training clips' codes ``(N, D)`` (:func:`encode_clips`) already
        computed (``mode_counts``: as for :func:`build_modes`)."""
        return cls(
            model,
            build_modes(kind, codes, data, model.cfg.n_classes, seed, mode_counts),
            data.frame_stride,
            data.floor_clearance,
        )

    def generate(
        self, codes: np.ndarray | Tensor, action: np.ndarray | Tensor, end_points: np.ndarray | Tensor
    ) -> tuple[Tensor, Tensor, Tensor]:
        """Positions ``(N, T, J, 3)``, features ``(N, T_model, F)`` and the trajectory generator's trajectory
        ``(N, T_model, 3)`` for codes ``(N, D)``, actions ``(N,)`` and end points ``(N, 3)``."""
        code = torch.as_tensor(np.asarray(codes), dtype=torch.float32)
        act = torch.as_tensor(np.asarray(action), dtype=torch.int64)
        end = torch.as_tensor(np.asarray(end_points), dtype=torch.float32)
        if code.dim() != 2 or act.shape != code.shape[:1] or end.shape != (code.shape[0], 3):
            raise ValueError(
                f"ODMOSampler.generate: need codes (N, D), action (N,) and end_points (N, 3), got "
                f"{tuple(code.shape)}, {tuple(act.shape)} and {tuple(end.shape)}"
            )
        was_training = self.model.training
        self.model.eval()
        try:
            features, trajectory = self.model.generate(code, act, end)
        finally:
            self.model.train(was_training)
        return to_positions(features, self.frame_stride, self.floor_clearance), features, trajectory

    def sample(
        self,
        action: int,
        n: int,
        rng: np.random.Generator,
        probabilities: Sequence[float] | None = None,
        mode: int | None = None,
    ) -> Samples:
        """``n`` clips of ``action`` drawn mode by mode (see :meth:`ModeSet.sample`), end points from the
        nearest codes."""
        check_scalar(n, "n", "ODMOSampler.sample", kind=numbers.Integral, minimum=1)
        codes, modes = self.modes.sample(action, n, rng, probabilities, mode)
        ends = self.modes.nearest_end_points(action, codes)
        actions = np.full(n, action, dtype=np.int64)
        return Samples(*self.generate(codes, actions, ends), codes, actions, modes, ends)

    def sample_classes(self, n_per_class: int, rng: np.random.Generator) -> Samples:
        """``n_per_class`` clips of every class (mode-preserving within each), generated in one batch."""
        check_scalar(
            n_per_class, "n_per_class", "ODMOSampler.sample_classes", kind=numbers.Integral, minimum=1
        )
        return self._batch(
            [(c, self.modes.sample(c, n_per_class, rng)) for c in range(len(self.modes.classes))]
        )

    def sample_modes(self, n_per_mode: int, rng: np.random.Generator) -> Samples:
        """``n_per_mode`` clips of every discovered mode of every class, generated in one batch."""
        check_scalar(n_per_mode, "n_per_mode", "ODMOSampler.sample_modes", kind=numbers.Integral, minimum=1)
        return self._batch(
            [
                (c, self.modes.sample(c, n_per_mode, rng, mode=k))
                for c, modes in enumerate(self.modes.classes)
                for k in range(modes.n_modes)
            ]
        )

    def _batch(self, drawn: list[tuple[int, tuple[np.ndarray, np.ndarray]]]) -> Samples:
        codes = np.concatenate([d[1][0] for d in drawn])
        modes = np.concatenate([d[1][1] for d in drawn])
        actions = np.concatenate([np.full(len(d[1][0]), d[0], dtype=np.int64) for d in drawn])
        ends = np.concatenate([self.modes.nearest_end_points(c, d[0]) for c, d in drawn])
        return Samples(*self.generate(codes, actions, ends), codes, actions, modes, ends)


def interpolate(a: np.ndarray, b: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``(1 - w) a + w b`` for each weight: vectors (codes, end points) ``(D,)``, ``(D,)``, weights ``(n,)``
    -> ``(n, D)``."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    if a.ndim != 1 or a.shape != b.shape or w.ndim != 1:
        raise ValueError(
            f"interpolate: need two vectors (D,) and weights (n,), got {a.shape}, {b.shape}, {w.shape}"
        )
    return (1.0 - w)[:, None] * a[None] + w[:, None] * b[None]


def _samples(
    sampler: ODMOSampler, action: int, codes: np.ndarray, ends: np.ndarray, modes: np.ndarray
) -> Samples:
    actions = np.full(len(codes), action, dtype=np.int64)
    return Samples(*sampler.generate(codes, actions, ends), codes, actions, modes, ends)


def _mode_mean(sampler: ODMOSampler, action: int, mode: int, name: str) -> np.ndarray:
    modes = sampler.modes.classes[sampler.modes.check_action(action)]
    check_scalar(mode, name, "mode_interpolation", kind=numbers.Integral)
    if not 0 <= mode < modes.n_modes:
        raise ValueError(
            f"mode_interpolation: {name} must be one of action {action}'s modes 0..{modes.n_modes - 1}, "
            f"got {mode!r}"
        )
    return modes.means[mode]


def mode_interpolation(
    sampler: ODMOSampler, action: int, mode_a: int, mode_b: int, weights: np.ndarray
) -> Samples:
    """Clips whose codes slide from the centre of ``mode_a`` to that of ``mode_b`` of ``action`` (``weights``
    ``(n,)`` in [0, 1]); each takes the end point of its nearest training code. ``mode`` holds the nearer end
    (a or b)."""
    start, stop = _mode_mean(sampler, action, mode_a, "mode_a"), _mode_mean(sampler, action, mode_b, "mode_b")
    codes = interpolate(start, stop, weights)
    ends = sampler.modes.nearest_end_points(action, codes)
    return _samples(sampler, action, codes, ends, np.where(np.asarray(weights) < 0.5, mode_a, mode_b))


def to_end_point(sampler: ODMOSampler, action: int, codes: np.ndarray, end_points: np.ndarray) -> Samples:
    """Clips of ``action`` from given codes ``(n, D)``, each sent to its end point ``(n, 3)`` (metres,
    relative to the start; the character starts facing +x)."""
    codes = np.asarray(codes, dtype=np.float64)
    ends = np.asarray(end_points, dtype=np.float64)
    if ends.shape != (len(codes), 3):
        raise ValueError(f"to_end_point: end_points must be ({len(codes)}, 3), got {ends.shape}")
    modes = sampler.modes.classes[sampler.modes.check_action(action)].assign(codes)
    return _samples(sampler, action, codes, ends, modes)


def end_point_sweep(start: np.ndarray, stop: np.ndarray, n: int) -> np.ndarray:
    """``n`` end points evenly spaced on the segment from ``start`` ``(3,)`` to ``stop`` ``(3,)``, both
    included."""
    check_scalar(n, "n", "end_point_sweep", kind=numbers.Integral, minimum=1)
    return interpolate(np.asarray(start, float), np.asarray(stop, float), np.linspace(0.0, 1.0, n))


def styles_to_end_point(
    sampler: ODMOSampler, action: int, end_point: np.ndarray, rng: np.random.Generator, per_mode: int = 1
) -> Samples:
    """``per_mode`` codes from every discovered mode of ``action``, all sent to one ``end_point`` ``(3,)``."""
    check_scalar(per_mode, "per_mode", "styles_to_end_point", kind=numbers.Integral, minimum=1)
    modes = sampler.modes.classes[sampler.modes.check_action(action)]
    codes, picked = sampler.modes.sample(
        action, per_mode * modes.n_modes, rng, probabilities=np.ones(modes.n_modes)
    )
    ends = np.repeat(np.asarray(end_point, dtype=np.float64)[None], len(codes), axis=0)
    return _samples(sampler, action, codes, ends, picked)
