"""The motion generator: a trajectory encoder whose final state starts an autoregressive LSTM decoder.

The trajectory encoder reads the root trajectory ``(B, T, 3)`` (the trajectory generator's, during
training and sampling alike) with an LSTM; its last hidden and cell states become the decoder's initial
state, which is how the trajectory steers the motion. The decoder then writes the full motion frame by
frame, local movement profile and root trajectory together (``3 (J - 1) + 3`` channels): at frame ``t``
its input is the previous frame, the class-code condition and the time ``t / T``.

**Teacher forcing.** In training the previous frame is the real one with probability ``teacher_forcing``
(drawn independently for each clip and frame), the decoder's own output otherwise. The chapter decays the
probability from 1 to 0.3 (``LinearRamp(0, steps, 1.0, 0.3)``), so the decoder learns to continue its own
output, which is all it has when sampling (probability 0). Frame 0 starts from a zero frame.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

from motionlab.data.representations import check_tensor
from motionlab.models.odmo.config import ODMOConfig
from motionlab.models.odmo.trajectory import class_code_condition


class MotionGenerator(nn.Module):
    """``trajectory (B, T, 3)``, ``code (B, D)``, ``action (B,)`` -> motion features ``(B, T, 3 (J - 1) +
    3)``."""

    def __init__(self, cfg: ODMOConfig) -> None:
        super().__init__()
        self.cfg = cfg
        hidden = cfg.motion_hidden
        self.trajectory_embed = nn.Sequential(nn.Linear(3, hidden), nn.PReLU())
        self.trajectory_encoder = nn.LSTM(hidden, hidden, batch_first=True)
        # the decoder's input embedding PReLU(W [previous frame; condition; time] + b), split in two linear
        # maps so that the part that does not change from frame to frame is computed once per clip
        self.previous_embed = nn.Linear(cfg.feature_dim, hidden, bias=False)
        self.condition_embed = nn.Linear(cfg.condition_dim + 1, hidden)
        self.embed_activation = nn.PReLU()
        self.decoder = nn.LSTMCell(hidden, hidden)
        self.out = nn.Linear(hidden, cfg.feature_dim)

    def forward(
        self,
        trajectory: Tensor,
        code: Tensor,
        action: Tensor,
        target: Tensor | None = None,
        teacher_forcing: float = 0.0,
        generator: torch.Generator | None = None,
    ) -> Tensor:
        """Decode a motion; ``target`` ``(B, T, F)`` is needed when ``teacher_forcing > 0``."""
        cfg = self.cfg
        batch = code.shape[0]
        check_tensor(trajectory, "trajectory", "MotionGenerator", (cfg.n_frames, 3), min_leading=1)
        if trajectory.shape[0] != batch:
            raise ValueError(f"MotionGenerator: trajectory has {trajectory.shape[0]} clips, code has {batch}")
        if not 0.0 <= teacher_forcing <= 1.0:
            raise ValueError(f"MotionGenerator: teacher_forcing must be a probability, got {teacher_forcing}")
        if teacher_forcing > 0:
            if target is None or target.shape != (batch, cfg.n_frames, cfg.feature_dim):
                raise ValueError(
                    f"MotionGenerator: teacher forcing needs target ({batch}, {cfg.n_frames}, "
                    f"{cfg.feature_dim}), got {None if target is None else tuple(target.shape)}"
                )
            forced = torch.rand(batch, cfg.n_frames, 1, generator=generator) < teacher_forcing
        _, (h, c) = self.trajectory_encoder(self.trajectory_embed(trajectory))
        h, c = h[0], c[0]
        condition = class_code_condition(code, action, cfg.n_classes)
        time = torch.arange(cfg.n_frames, dtype=code.dtype) / cfg.n_frames
        per_frame = self.condition_embed(
            torch.cat(
                [
                    condition[:, None, :].expand(-1, cfg.n_frames, -1),
                    time[None, :, None].expand(batch, -1, 1),
                ],
                dim=-1,
            )
        )
        previous = code.new_zeros(batch, cfg.feature_dim)
        frames = []
        for t in range(cfg.n_frames):
            embedded = self.embed_activation(self.previous_embed(previous) + per_frame[:, t])
            h, c = self.decoder(embedded, (h, c))
            frame = self.out(h)
            frames.append(frame)
            previous = torch.where(forced[:, t], target[:, t], frame) if teacher_forcing > 0 else frame
        return torch.stack(frames, dim=1)
