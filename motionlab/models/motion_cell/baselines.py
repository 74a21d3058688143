"""The paper's deterministic baselines: ERD and a QuaterNet-style quaternion RNN.

Both are frame-level recurrent networks conditioned on the same control embedding as the Motion Cell.
They are deterministic: their only randomness is the initial recurrent state, drawn from a learned
Gaussian per (action, body) combination, as in the paper's comparison. Each is trained teacher-forced on
the same windows as the Motion Cell, predicting frame ``t`` from frames ``< t`` (frame 0 from a learned
start pose), with its own remedy for the gap between teacher forcing and free running:

* **ERD** (Fragkiadaki et al. 2015): MLP encoder, 2-layer LSTM, MLP decoder of absolute poses; a *noise
  curriculum* adds Gaussian noise of growing size to the inputs (schedule ``"input_noise"``).
* **QuaterNet-style** (Pavllo et al. 2018): 2-layer GRU with unit-quaternion outputs, trained on joint
  positions through forward kinematics (every second frame, to halve its cost) and with *scheduled
  sampling* (schedule ``"sampling"``: each input frame is replaced by the model's own prediction with that
  probability; the predictions come from a first, teacher-forced pass).
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import torch
from torch import Tensor, nn

from motionlab.models.motion_cell.data import PoseCodec, WindowBatch, pose_dim
from motionlab.models.motion_cell.heads import (
    PoseNetwork,
    PosePrediction,
    assemble_pose,
    split_raw_pose,
)
from motionlab.models.motion_cell.losses import (
    LossConfig,
    LossFn,
    joint_weights,
    norm_loss,
    root_loss,
    rotation_loss,
)
from motionlab.models.motion_cell.model import ControlEmbedding, InitialState, mlp
from motionlab.validation import Checked, check_scalar, check_tensor, choice, integer

RecurrentState = Tensor | tuple[Tensor, Tensor]


@dataclass(frozen=True)
class BaselineConfig(Checked):
    """A frame-level deterministic recurrent baseline: ERD or the QuaterNet-style quaternion RNN.

    Attributes:
        kind: ``"erd"`` (MLP encoder, 2-layer LSTM, MLP decoder; Fragkiadaki et al. 2015) or
            ``"quaternet"`` (2-layer GRU, quaternion outputs as rotations of the previous pose, trained
            through forward kinematics; Pavllo et al. 2018).
        n_joints, n_actions, n_bodies, control_dim: as in :class:`MotionCellConfig`.
        hidden_dim: recurrent width; encoder_dim: ERD's encoder / decoder width (unused by QuaterNet).
    """

    kind: str = choice(("erd", "quaternet"), "erd")
    n_joints: int = integer(22, minimum=2)
    hidden_dim: int = integer(128, minimum=1)
    encoder_dim: int = integer(128, minimum=1)
    control_dim: int = integer(32, minimum=1)
    n_actions: int = integer(6, minimum=1)
    n_bodies: int = integer(2, minimum=1)

    @property
    def pose_dim(self) -> int:
        """Channels of one pose vector (:func:`~.data.pose_dim`)."""
        return pose_dim(self.n_joints)


class FrameBaseline(PoseNetwork[BaselineConfig]):
    """ERD or the QuaterNet-style RNN (``cfg.kind``), predicting one pose per recurrent step."""

    def __init__(self, cfg: BaselineConfig, codec: PoseCodec) -> None:
        super().__init__(cfg, codec, "quaternion")
        raw_dim = self.head.raw_dim(cfg.n_joints)
        inputs = cfg.pose_dim + cfg.control_dim
        self.control = ControlEmbedding(cfg.n_actions, cfg.n_bodies, cfg.control_dim)
        if cfg.kind == "erd":
            self.encoder: nn.Module = mlp([inputs, cfg.encoder_dim, cfg.encoder_dim])
            self.rnn: nn.LSTM | nn.GRU = nn.LSTM(
                cfg.encoder_dim, cfg.hidden_dim, num_layers=2, batch_first=True
            )
            self.decoder = mlp([cfg.hidden_dim, cfg.encoder_dim, raw_dim])
        else:
            self.encoder = nn.Identity()
            self.rnn = nn.GRU(inputs, cfg.hidden_dim, num_layers=2, batch_first=True)
            self.decoder = nn.Sequential(nn.Linear(cfg.hidden_dim, raw_dim))
        nn.init.zeros_(self.decoder[-1].weight)
        nn.init.zeros_(self.decoder[-1].bias)
        states = 2 * cfg.hidden_dim * (2 if cfg.kind == "erd" else 1)
        self.initial = InitialState(cfg.n_actions, cfg.n_bodies, states)
        rest = assemble_pose(torch.tensor([1.0, 0.0, 0.0, 0.0]).expand(cfg.n_joints - 1, 4), torch.zeros(6))
        self.start_pose = nn.Parameter(rest.clone())

    def initial_state(
        self, action: Tensor, body: Tensor, generator: torch.Generator | None = None
    ) -> RecurrentState:
        """The sampled initial state: ``(2, B, hidden)`` for the GRU, ``(h, c)`` of that shape for the
        LSTM."""
        flat = self.initial(action, body, generator)
        layers = flat.unflatten(-1, (-1, 2, self.cfg.hidden_dim)).permute(1, 2, 0, 3).contiguous()
        return (layers[0], layers[1]) if self.cfg.kind == "erd" else layers[0]

    def _step(
        self, inputs: Tensor, control: Tensor, state: RecurrentState
    ) -> tuple[Tensor, Tensor, RecurrentState]:
        """Run the network over input poses ``(B, T, 90)``: poses, raw quaternions and the new state."""
        controls = control[:, None].expand(-1, inputs.shape[1], -1)
        hidden, state = self.rnn(self.encoder(torch.cat([inputs, controls], dim=-1)), state)
        params, root = split_raw_pose(self.decoder(hidden), self.head, self.cfg.n_joints)
        return assemble_pose(self.head.quaternions(params), root), params, state

    def forward(
        self,
        poses: Tensor,
        action: Tensor,
        body: Tensor,
        input_noise: float = 0.0,
        sampling: float = 0.0,
        generator: torch.Generator | None = None,
    ) -> PosePrediction:
        """Predict every frame of ``poses`` ``(B, T, 90)`` from the frames before it (teacher-forced).

        Args:
            input_noise: standard deviation of Gaussian noise added to the inputs (ERD's curriculum).
            sampling: probability of feeding the model's own prediction instead of the data (QuaterNet).
        """
        check_tensor(poses, "poses", "FrameBaseline", ndim=3, trailing=(self.cfg.pose_dim,))
        check_scalar(input_noise, "input_noise", "FrameBaseline", minimum=0.0)
        check_scalar(sampling, "sampling", "FrameBaseline", minimum=0.0, maximum=1.0)
        control = self.control(action, body)
        state = self.initial_state(action, body, generator)
        start = self.start_pose.expand(poses.shape[0], 1, -1)
        inputs = torch.cat([start, poses[:, :-1]], dim=1)
        if sampling > 0:
            with torch.no_grad():
                first_pass, _, _ = self._step(inputs, control, state)
            own = torch.rand(poses.shape[0], poses.shape[1] - 1, 1, generator=generator) < sampling
            inputs = torch.cat([start, torch.where(own, first_pass[:, :-1], poses[:, :-1])], dim=1)
        if input_noise > 0:
            inputs = inputs + input_noise * torch.randn(inputs.shape, generator=generator)
        predicted, params, _ = self._step(inputs, control, state)
        return PosePrediction(predicted, params)

    @torch.no_grad()
    def generate(
        self, action: Tensor, body: Tensor, n_frames: int, generator: torch.Generator | None = None
    ) -> Tensor:
        """Roll out ``n_frames`` pose vectors ``(B, n_frames, 90)`` from a sampled initial state."""
        check_scalar(n_frames, "n_frames", "FrameBaseline.generate", kind=numbers.Integral, minimum=1)
        control = self.control(action, body)
        state = self.initial_state(action, body, generator)
        pose = self.start_pose.expand(control.shape[0], 1, -1)
        frames = []
        for _ in range(n_frames):
            pose, _, state = self._step(pose, control, state)
            frames.append(pose)
        return torch.cat(frames, dim=1)


def baseline_loss(cfg: LossConfig) -> LossFn:
    """The baselines' loss: ERD on rotations (eq. 22, like the Motion Cell), QuaterNet on joint positions.

    ERD reads the schedule ``input_noise``, QuaterNet ``sampling``. QuaterNet's position term is the mean
    distance (metres) between predicted and true joints, both posed by forward kinematics from the local
    rotations with the root fixed at the origin (its root motion is in the root channels' term), summed over
    joints and averaged over every second frame.
    """
    weights = joint_weights(cfg.joint_weights)

    def loss_fn(
        model: nn.Module, batch: WindowBatch, step: int, coeffs: dict[str, float]
    ) -> dict[str, Tensor]:
        out = model(
            batch.poses,
            batch.action,
            batch.body,
            input_noise=coeffs.get("input_noise", 0.0),
            sampling=coeffs.get("sampling", 0.0),
        )
        codec = model.codec
        predicted_q, predicted_root = codec.split(out.poses)
        target_q, target_root = codec.split(batch.poses)
        if model.cfg.kind == "quaternet":
            predicted = codec.local_positions(out.poses[:, ::2], batch.body)
            with torch.no_grad():
                target = codec.local_positions(batch.poses[:, ::2], batch.body)
            pose = (predicted - target).norm(dim=-1).sum(-1).mean()
        else:
            pose = rotation_loss(predicted_q, target_q, weights)
        root = root_loss(predicted_root, target_root)
        norm = norm_loss(out.rotation_params, model.head)
        total = pose + cfg.root_weight * root + cfg.norm_weight * norm
        return {"loss": total, "pose": pose, "root": root, "norm": norm}

    return loss_fn
