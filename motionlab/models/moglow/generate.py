"""Generating motion in physical units: control programmes, seeds, and decoding to joint positions.

The models work in standard units (:mod:`.data`). Here controls are given in metres and radians per
frame, the generated poses are turned back into metres, and the root path is integrated from the
control (:func:`motionlab.data.representations.from_moglow`): MoGlow never predicts where the root goes,
the control says it, and the model's job is a body that moves accordingly.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple, Protocol

import torch
from torch import Tensor

from motionlab.data.representations import from_moglow
from motionlab.models.moglow.data import CONTROL_DIM, MoGlowFeatures, Scalers


class AutoregressiveModel(Protocol):
    """MoGlow or the Gaussian baseline: ``cfg.history`` and ``sample(control, seed_pose, temperature,
    generator)``."""

    cfg: object

    def sample(
        self,
        control: Tensor,
        seed_pose: Tensor,
        temperature: float = 1.0,
        generator: torch.Generator | None = None,
    ) -> Tensor: ...


@dataclass(frozen=True)
class Segment:
    """A stretch of constant command: ``seconds`` long, ``speed`` forward (m/s), ``turn`` (rad/s, positive
    to the left), ``sideways`` (m/s, positive to the left)."""

    seconds: float
    speed: float
    turn: float = 0.0
    sideways: float = 0.0

    def __post_init__(self) -> None:
        for name in ("seconds", "speed", "turn", "sideways"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"Segment.{name} must be finite, got {getattr(self, name)!r}")
        if self.seconds <= 0:
            raise ValueError(f"Segment.seconds must be > 0, got {self.seconds}")


def control_programme(segments: Sequence[Segment], fps: float = 30.0, ramp: float = 0.5) -> Tensor:
    """Per-frame control ``(T, 3)`` (forward and sideways m/frame, yaw rad/frame) following ``segments``.

    Changes between segments are smoothed by a moving average over ``ramp`` seconds (0: abrupt), as a
    joystick moved by a hand would be.
    """
    if not segments:
        raise ValueError("control_programme: needs at least one segment")
    rows = [
        torch.tensor([[s.speed, s.sideways, s.turn]], dtype=torch.float64).expand(round(s.seconds * fps), 3)
        for s in segments
    ]
    control = torch.cat(rows) / fps
    width = round(ramp * fps)
    if width > 1:
        padded = torch.cat(
            [control[:1].expand(width // 2, 3), control, control[-1:].expand(width - 1 - width // 2, 3)]
        )
        control = padded.unfold(0, width, 1).mean(dim=-1)
    return control.float()


def splice_controls(pieces: Sequence[Tensor], blend: int = 15) -> Tensor:
    """Join control sequences ``(T_i, 3)`` end to end, cross-fading linearly over ``blend`` frames at each
    joint.

    Recorded controls carry the gait's own rhythm (the pelvis sways and turns a little with every step),
    which a constant command lacks; splicing pieces of recorded control gives realistic commands that
    still change abruptly, such as walk, then stand still, then jog. Each junction takes ``blend`` frames
    from the end of one piece and the start of the next, so the result has ``sum(T_i) - blend * (n - 1)``
    frames.
    """
    if not pieces:
        raise ValueError("splice_controls: needs at least one piece")
    if any(p.dim() != 2 or p.shape[1] != CONTROL_DIM or p.shape[0] <= 2 * blend for p in pieces):
        raise ValueError(
            f"splice_controls: pieces must be (T, {CONTROL_DIM}) with T > 2 * blend = {2 * blend}, got "
            f"{[tuple(p.shape) for p in pieces]}"
        )
    out = pieces[0]
    weight = torch.linspace(0.0, 1.0, blend + 2, dtype=out.dtype)[1:-1, None]
    for piece in pieces[1:]:
        mixed = (1 - weight) * out[-blend:] + weight * piece[:blend] if blend else out[:0]
        out = torch.cat([out[: out.shape[0] - blend], mixed, piece[blend:]])
    return out


def seed_features(
    clips: MoGlowFeatures, indices: Sequence[int], history: int, start: int = 1
) -> MoGlowFeatures:
    """Frames ``start .. start + history - 1`` of the chosen clips ``(B, history, ·)``: a generation seed.

    ``start = 1`` skips frame 0, whose control is undefined.
    """
    index = torch.as_tensor(list(indices), dtype=torch.long)
    return MoGlowFeatures(
        clips.pose[index, start : start + history], clips.control[index, start : start + history]
    )


class GeneratedMotion(NamedTuple):
    """Generated clips: ``pose`` ``(B, T, 64)`` and ``control`` ``(B, T, 3)`` in physical units, and world
    ``positions`` ``(B, T, 22, 3)``. The first ``history`` frames are the seed."""

    pose: Tensor
    control: Tensor
    positions: Tensor


def generate_motion(
    model: AutoregressiveModel,
    scalers: Scalers,
    control: Tensor,
    seed: MoGlowFeatures,
    temperature: float = 1.0,
    generator: torch.Generator | None = None,
) -> GeneratedMotion:
    """Generate ``N`` frames after ``seed`` following ``control``.

    Args:
        model: a trained MoGlow or Gaussian baseline.
        scalers: the standardisers the model was trained with.
        control: ``(B, N, 3)`` in m/frame and rad/frame (for example rows of :func:`control_programme`).
        seed: raw features ``(B, tau, ·)`` of the frames that start the history (:func:`seed_features`).
        temperature, generator: as for the model's ``sample``.
    """
    if control.dim() != 3 or control.shape[-1] != CONTROL_DIM or seed.pose.shape[0] != control.shape[0]:
        raise ValueError(
            f"generate_motion: control must be (B, N, {CONTROL_DIM}) with the seed's batch "
            f"{seed.pose.shape[0]}, got {tuple(control.shape)}"
        )
    all_control = torch.cat([seed.control, control.to(seed.control)], dim=1)
    generated = model.sample(
        scalers.control.transform(all_control), scalers.pose.transform(seed.pose), temperature, generator
    )
    pose = torch.cat([seed.pose, scalers.pose.inverse(generated)], dim=1)
    return GeneratedMotion(pose, all_control, from_moglow(torch.cat([pose, all_control], dim=-1)))
