"""From codes to motions: a trained ODMO model, its modes and the way back to 30 fps joint positions.

:class:`ODMOSampler` is what the evaluation, the customisation functions, the widgets and the benchmark
use: it draws codes from a :class:`~motionlab.models.odmo.modes.ModeSet` (mode-preserving, conventional
or prior), picks their end points, runs the generators and decodes the features to global joint
positions at the data's frame rate.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import torch
from torch import Tensor

from motionlab.models.odmo.data import ODMOData, to_positions
from motionlab.models.odmo.model import ODMO
from motionlab.models.odmo.modes import ModeSet, discover_modes, prior_modes, single_gaussian_modes

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


def build_modes(kind: str, codes: np.ndarray, data: ODMOData, n_classes: int, seed: int = 0) -> ModeSet:
    """The :class:`ModeSet` of sampler ``kind`` (one of :data:`SAMPLERS`) over training codes ``(N, D)``."""
    action, ends = data.action.numpy(), data.end_point.numpy()
    if kind == "modes":
        return discover_modes(codes, action, ends, n_classes, seed=seed)
    if kind == "conventional":
        return single_gaussian_modes(codes, action, ends, n_classes)
    if kind == "prior":
        return prior_modes(codes, action, ends, n_classes)
    raise ValueError(f"build_modes: kind must be one of {SAMPLERS}, got {kind!r}")


@dataclass(frozen=True, eq=False)
class ODMOSampler:
    """A trained model with its modes and the decoding settings of its data (frame stride, floor
    clearance)."""

    model: ODMO
    modes: ModeSet
    frame_stride: int
    floor_clearance: float

    @classmethod
    def from_data(cls, model: ODMO, data: ODMOData, kind: str = "modes", seed: int = 0) -> ODMOSampler:
        """Encode ``data`` (the training clips), build the modes of ``kind`` and wrap everything."""
        return cls.from_codes(model, encode_clips(model, data), data, kind, seed)

    @classmethod
    def from_codes(
        cls, model: ODMO, codes: np.ndarray, data: ODMOData, kind: str = "modes", seed: int = 0
    ) -> ODMOSampler:
        """:meth:`from_data` with the training clips' codes ``(N, D)`` (:func:`encode_clips`) already
        computed."""
        return cls(
            model,
            build_modes(kind, codes, data, model.cfg.n_classes, seed),
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
        codes, modes = self.modes.sample(action, n, rng, probabilities, mode)
        ends = self.modes.nearest_end_points(action, codes)
        actions = np.full(n, action, dtype=np.int64)
        return Samples(*self.generate(codes, actions, ends), codes, actions, modes, ends)

    def sample_classes(self, n_per_class: int, rng: np.random.Generator) -> Samples:
        """``n_per_class`` clips of every class (mode-preserving within each), generated in one batch."""
        return self._batch(
            [(c, self.modes.sample(c, n_per_class, rng)) for c in range(len(self.modes.classes))]
        )

    def sample_modes(self, n_per_mode: int, rng: np.random.Generator) -> Samples:
        """``n_per_mode`` clips of every discovered mode of every class, generated in one batch."""
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
