"""The paper's first step: a 1D-convolutional denoising autoencoder that cleans motion capture before
training.

Real capture is noisy (jitter on every frame, spikes where markers were lost). Our synthetic clips are
clean, so the chapter plays the whole story: the training split is "captured" through the noise model
of :mod:`motionlab.data.noise`, a denoiser is trained on *other* clips whose clean version we know (the
validation split, with fresh noise), and the denoised training split is what every model learns from
(:func:`~.experiment.prepare_training_data`); the validation split, captured with its own noise and denoised
alike, is what the models validate on.

The autoencoder reads pose vectors ``(B, T, 90)`` as 90 channels over time: two conv layers down to a
bottleneck and two back up, every layer keeping the frame count (kernel ``k``, padding ``k // 2``). Its
output is a *correction* added to the noisy input (a skip connection around the autoencoder; the last
layer starts at zero, so training starts from "change nothing"), and the corrected quaternions are
normalised. It is trained with the same pose loss as the models (eq. 22 plus the root term) and the
quaternion-norm constraint.

What is ours: the paper's denoiser (§3.1, §4.2, Table 1) is a plain convolutional autoencoder (two
``Conv1D + ReLU`` down, ``ConvTranspose1D`` layers up, no skip connection), trained for 300 epochs on the
rest of AMASS with 10 % of the input dimensions corrupted by Gaussian noise N(0, 0.5). Ours uses ELU and
stride-1 convolutions throughout, adds the skip connection, and is trained on the capture noise of
:mod:`motionlab.data.noise` (jitter and spikes) on the benchmark's validation split, for the chapter's
``denoiser_steps`` with the Motion Cell's learning-rate decay (:func:`.experiment.learning_rate_decay`).
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import torch
from torch import Tensor, nn

from motionlab.data.noise import ROTATION_NOISE, NoiseConfig, add_position_noise, add_rotation_noise
from motionlab.geometry import quat_normalize
from motionlab.models.motion_cell.data import (
    PoseCodec,
    WindowBatches,
    motion_cell_features,
    pose_dim,
)
from motionlab.models.motion_cell.heads import PoseNetwork, PosePrediction, assemble_pose
from motionlab.models.motion_cell.losses import LossConfig, LossFn, joint_weights, norm_loss, pose_loss
from motionlab.train import TrainResult
from motionlab.validation import Checked, check_scalar, check_tensor, integer

#: Noise on the root position: 0.5 mm jitter, no spikes. The pelvis is tracked by a rigid cluster of markers,
#: far better than single joints, and the root channels are velocities (frame differences), which magnify
#: jitter: 5 mm would already swamp the sideways velocity (its standard deviation in the data is 4 mm per
#: frame).
ROOT_NOISE = NoiseConfig(jitter=0.0005, spike_rate=0.0)

#: Clips denoised at a time.
CHUNK = 256

#: Threads of the denoiser's training. It runs in this process while two workers train the benchmark's
#: evaluators, so a second thread competes with them for the cores: on an idle machine two threads took 17 s
#: against 24 s for one, but with the cores busy two spinning OpenMP threads slowed it about fifteenfold
#: (8 s per step against 0.5 s). The denoised clips have the same fingerprint on one and on two threads.
DENOISER_THREADS = 1

#: Seeds of the capture noise on the training split, of the denoiser's noisy copies of the validation
#: split, and of the capture of the validation split the models validate on (its own noise, as if captured
#: like the training split).
CAPTURE_SEED, DENOISER_DATA_SEED, VAL_CAPTURE_SEED = 1, 2, 3


@dataclass(frozen=True)
class DenoiserConfig(Checked):
    """The 1D-convolutional denoising autoencoder (after the paper's Table 1: two layers down, two up; with
    a skip connection and ELU, ours).

    Attributes:
        n_joints: skeleton joints; channels: width of the outer conv layers; bottleneck: width of the code;
        kernel_size: temporal kernel (odd); every layer keeps the frame count.
    """

    n_joints: int = integer(22, minimum=2)
    channels: int = integer(128, minimum=1)
    bottleneck: int = integer(64, minimum=1)
    kernel_size: int = integer(5, minimum=1)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.kernel_size % 2 != 1:
            raise ValueError(f"DenoiserConfig: kernel_size must be odd, got {self.kernel_size!r}")

    @property
    def pose_dim(self) -> int:
        """Channels of one pose vector (:func:`~.data.pose_dim`)."""
        return pose_dim(self.n_joints)


def noisy_features(rotations: np.ndarray, positions: np.ndarray, rng: np.random.Generator | int) -> Tensor:
    """Motion Cell features ``(N, T, 90)`` of clips "captured" with noise.

    The non-root joints' rotations get :data:`~motionlab.data.noise.ROTATION_NOISE` (jitter and spikes), the
    root position :data:`ROOT_NOISE`; the root orientation stays clean (see :data:`ROOT_NOISE`).

    Args:
        rotations: clean local quaternions ``(N, T, 22, 4)``; positions: clean positions ``(N, T, 22, 3)``.
        rng: a NumPy generator or seed; draws the rotation noise, then the root noise.
    """
    if not isinstance(rng, np.random.Generator):
        check_scalar(
            rng, "rng (a numpy Generator or a seed)", "noisy_features", kind=numbers.Integral, minimum=0
        )
        rng = np.random.default_rng(int(rng))
    noisy_rotations = np.asarray(rotations, dtype=np.float32).copy()
    noisy_rotations[:, :, 1:], _ = add_rotation_noise(noisy_rotations[:, :, 1:], rng, ROTATION_NOISE)
    noisy_root, _ = add_position_noise(np.asarray(positions, dtype=np.float32)[:, :, :1], rng, ROOT_NOISE)
    noisy_positions = np.asarray(positions, dtype=np.float32).copy()
    noisy_positions[:, :, :1] = noisy_root
    return motion_cell_features(noisy_rotations, noisy_positions)


class DenoisingAutoencoder(PoseNetwork[DenoiserConfig]):
    """Conv1d encoder-decoder over time: noisy pose vectors ``(B, T, 90)`` -> clean ones."""

    def __init__(self, cfg: DenoiserConfig, codec: PoseCodec) -> None:
        super().__init__(cfg, codec, "quaternion")
        k, pad = cfg.kernel_size, cfg.kernel_size // 2
        self.encoder = nn.Sequential(
            nn.Conv1d(cfg.pose_dim, cfg.channels, k, padding=pad),
            nn.ELU(),
            nn.Conv1d(cfg.channels, cfg.bottleneck, k, padding=pad),
            nn.ELU(),
        )
        self.decoder = nn.Sequential(
            nn.Conv1d(cfg.bottleneck, cfg.channels, k, padding=pad),
            nn.ELU(),
            nn.Conv1d(cfg.channels, cfg.pose_dim, k, padding=pad),
        )
        with torch.no_grad():  # start close to "change nothing"
            self.decoder[-1].weight.mul_(0.01)
            self.decoder[-1].bias.zero_()

    def forward(self, noisy: Tensor) -> PosePrediction:
        """Denoised pose vectors ``(B, T, 90)`` and the corrected quaternions before normalisation ``(B, T, J
        - 1, 4)``."""
        check_tensor(noisy, "noisy", "DenoisingAutoencoder", ndim=3, trailing=(self.cfg.pose_dim,))
        corrected = noisy + self.decoder(self.encoder(noisy.transpose(1, 2))).transpose(1, 2)
        quaternions, root = self.codec.split(corrected)
        return PosePrediction(assemble_pose(quat_normalize(quaternions), root), quaternions)

    @torch.no_grad()
    def denoise(self, noisy: Tensor) -> Tensor:
        """Denoised pose vectors ``(N, T, 90)``, in chunks of :data:`CHUNK` clips."""
        self.eval()
        return torch.cat([self(noisy[i : i + CHUNK]).poses for i in range(0, noisy.shape[0], CHUNK)])


def denoiser_loss(cfg: LossConfig) -> LossFn:
    """Pose loss of the denoised clips against the clean ones, plus the norm constraint; batches ``(noisy,
    clean)``."""
    weights = joint_weights(cfg.joint_weights)

    def loss_fn(
        model: nn.Module, batch: tuple[Tensor, Tensor], step: int, coeffs: dict[str, float]
    ) -> dict[str, Tensor]:
        noisy, clean = batch
        out = model(noisy)
        pose = pose_loss(model.codec, out.poses, clean, weights, cfg.root_weight)
        norm = norm_loss(out.rotation_params, model.head)
        return {"loss": pose + cfg.norm_weight * norm, "pose": pose, "norm": norm}

    return loss_fn


class PreparedData(NamedTuple):
    """The training data every model sees, what the denoiser did to get it, and the validation windows.

    Attributes:
        codec: pose-vector codec (root statistics of the captured training split, skeletons).
        captured: pose vectors of the captured (noisy) training split ``(N, T, 90)``.
        batches: windows of the denoised training split (:class:`~.data.WindowBatches`).
        fingerprint: identifies the denoised data in the models' cache keys.
        denoiser: the trained denoiser; denoiser_result: its training result.
        errors: mean joint-rotation error (degrees) against the clean clips, ``"captured"`` and
            ``"denoised"``.
        val: windows of the validation split, captured, denoised and encoded like the training split
            (``shuffle=False, drop_last=False``: every clip in its order, one window each, its start drawn
            from the loop's validation stream, so the same in every pass); the runs' held-out curve.
            ``None``: no validation windows.
    """

    codec: PoseCodec
    captured: Tensor
    batches: WindowBatches
    fingerprint: str
    denoiser: nn.Module
    denoiser_result: TrainResult
    errors: dict[str, float]
    val: WindowBatches | None = None
