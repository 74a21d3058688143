"""The trajectory generator: per-frame root velocities from the code, the class and the end point,
accumulated.

The condition of every ODMO generator is the outer product of the class one-hot and the code, flattened
(:func:`class_code_condition`): a ``C · D`` vector that holds the code in the block of its class and zeros
elsewhere, so each class reads the code space with its own weights. The trajectory generator feeds that
condition, the end point ``r_e`` (zeros in the ``-r_e`` ablation) and the frame's time ``t / (T - 1)`` to
an LSTM at every frame, maps each output to a velocity and adds the velocities up from the origin
(:func:`accumulate`). :class:`~motionlab.models.odmo.model.ODMO` feeds it a standardised end point and reads
its velocities in units of each trajectory channel's standard deviation.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from motionlab.models.odmo.config import ODMOConfig


def class_code_condition(code: Tensor, action: Tensor, n_classes: int) -> Tensor:
    """The flattened outer product ``one_hot(action) ⊗ code``: ``(B, D)``, ``(B,)`` -> ``(B, C · D)``."""
    if code.dim() != 2 or action.shape != code.shape[:1] or action.is_floating_point():
        raise ValueError(
            f"class_code_condition: code must be (B, D) and action (B,) integers, got "
            f"{tuple(code.shape)} and {action.dtype} {tuple(action.shape)}"
        )
    if action.numel() and (int(action.min()) < 0 or int(action.max()) >= n_classes):
        raise ValueError(
            f"class_code_condition: actions must lie in [0, {n_classes}), got "
            f"[{int(action.min())}, {int(action.max())}]"
        )
    one_hot = F.one_hot(action, n_classes).to(code.dtype)
    return (one_hot[:, :, None] * code[:, None, :]).flatten(1)


def accumulate(velocity: Tensor) -> Tensor:
    """Positions ``(B, T, 3)`` from the velocities of frames 1..T-1 ``(B, T - 1, 3)``: frame 0 at the origin,
    frame ``t`` the sum of the first ``t`` velocities."""
    if velocity.dim() != 3:
        raise ValueError(f"accumulate: velocity must be (B, T - 1, C), got {tuple(velocity.shape)}")
    return torch.cat([torch.zeros_like(velocity[:, :1]), torch.cumsum(velocity, dim=1)], dim=1)


class TrajectoryGenerator(nn.Module):
    """``code (B, D)``, ``action (B,)``, ``end_point (B, 3)`` -> root trajectory ``(B, T, 3)`` from the
    origin.

    With ``use_end_point=False`` (the ``-r_e`` ablation) the end point is replaced by zeros.
    """

    def __init__(self, cfg: ODMOConfig) -> None:
        super().__init__()
        self.cfg = cfg
        hidden = cfg.trajectory_hidden
        self.embed = nn.Sequential(nn.Linear(cfg.condition_dim + 3 + 1, hidden), nn.PReLU())
        self.lstm = nn.LSTM(hidden, hidden, batch_first=True)
        self.velocity = nn.Sequential(nn.Linear(hidden, hidden), nn.PReLU(), nn.Linear(hidden, 3))

    def forward(self, code: Tensor, action: Tensor, end_point: Tensor) -> Tensor:
        if end_point.shape != (code.shape[0], 3):
            raise ValueError(
                f"TrajectoryGenerator: end_point must be ({code.shape[0]}, 3), got {tuple(end_point.shape)}"
            )
        if not self.cfg.use_end_point:
            end_point = torch.zeros_like(end_point)
        steps = self.cfg.n_frames - 1
        per_clip = torch.cat([class_code_condition(code, action, self.cfg.n_classes), end_point], dim=-1)
        time = torch.linspace(1.0 / steps, 1.0, steps, dtype=code.dtype)
        inputs = torch.cat(
            [per_clip[:, None, :].expand(-1, steps, -1), time[None, :, None].expand(code.shape[0], -1, 1)],
            dim=-1,
        )
        out, _ = self.lstm(self.embed(inputs))
        return accumulate(self.velocity(out))
