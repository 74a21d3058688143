"""Configurations of MoGlow and of its Gaussian autoregressive baseline (frozen, hashed into the cache
key)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from motionlab.models.moglow.data import CONTROL_DIM, POSE_DIM


def _check_positive(owner: str, name: str, value: object) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ValueError(f"{owner}.{name} must be a positive int, got {value!r}")


def _check_dropout(owner: str, value: object) -> None:
    if not isinstance(value, (int, float)) or not math.isfinite(value) or not 0.0 <= value < 1.0:
        raise ValueError(f"{owner}.dropout must be a probability in [0, 1), got {value!r}")


@dataclass(frozen=True)
class MoGlowConfig:
    """MoGlow (§4 of the paper): a next-frame Glow whose couplings are LSTMs over time.

    Attributes:
        pose_dim: output features per frame (64: root height and 21 joints' xyz).
        control_dim: control features per frame (3: forward, sideways, yaw velocity).
        history: ``tau``, the previous poses fed to every coupling (and ``tau + 1`` control frames, the
            current one included: zero-latency control).
        steps: Glow steps ``K`` (ActNorm, 1x1 convolution, LSTM affine coupling).
        hidden: LSTM units in each coupling network.
        cond_features: size of the shared linear projection of the conditioning that every coupling reads
            (our deviation from the paper, where each coupling reads the raw conditioning: on a CPU the
            first LSTM layer's input weights dominate both training and generation time; sharing one
            projection makes them ``K`` times cheaper).
        dropout: probability of zeroing each previous pose in the conditioning during training.
    """

    pose_dim: int = POSE_DIM
    control_dim: int = CONTROL_DIM
    history: int = 5
    steps: int = 8
    hidden: int = 64
    cond_features: int = 64
    dropout: float = 0.95

    def __post_init__(self) -> None:
        for name in ("pose_dim", "control_dim", "history", "steps", "hidden", "cond_features"):
            _check_positive("MoGlowConfig", name, getattr(self, name))
        if self.pose_dim < 2:
            raise ValueError(
                f"MoGlowConfig.pose_dim must be >= 2 for a coupling to split it, got {self.pose_dim}"
            )
        _check_dropout("MoGlowConfig", self.dropout)

    @property
    def cond_dim(self) -> int:
        """Conditioning features per frame: ``tau`` poses and ``tau + 1`` controls."""
        return self.history * self.pose_dim + (self.history + 1) * self.control_dim


@dataclass(frozen=True)
class GaussianARConfig:
    """The baseline: an LSTM over the same conditioning that outputs a diagonal Gaussian for the next pose.

    Attributes: as :class:`MoGlowConfig`; ``hidden`` is the LSTM width, ``layers`` its depth.
    """

    pose_dim: int = POSE_DIM
    control_dim: int = CONTROL_DIM
    history: int = 5
    hidden: int = 256
    layers: int = 1
    dropout: float = 0.0

    def __post_init__(self) -> None:
        for name in ("pose_dim", "control_dim", "history", "hidden", "layers"):
            _check_positive("GaussianARConfig", name, getattr(self, name))
        _check_dropout("GaussianARConfig", self.dropout)

    @property
    def cond_dim(self) -> int:
        """Conditioning features per frame: ``tau`` poses and ``tau + 1`` controls."""
        return self.history * self.pose_dim + (self.history + 1) * self.control_dim
