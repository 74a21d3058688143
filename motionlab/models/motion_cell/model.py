"""The full Motion Cell model: motion words, the Motion Cell recurrence and the output head.

Training (:meth:`MotionCellModel.forward`) reconstructs windows of pose vectors through the posterior,
teacher-forced, with *scheduled motion-word dropping*: each word's features are replaced by zeros in the
recurrence input with probability ``word_drop`` (the posterior still sees the word), which makes the
state lean on the latents, as it must at generation time. Generation (:meth:`MotionCellModel.generate`)
draws the initial state and then, word after word, a latent from the prior, decodes it, and feeds the
generated word back; it runs for any number of frames.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import torch
from torch import Tensor, nn

from motionlab.models.gaussian import reparameterize
from motionlab.models.motion_cell.cell import MotionCell
from motionlab.models.motion_cell.config import MotionCellConfig
from motionlab.models.motion_cell.data import PoseCodec
from motionlab.models.motion_cell.output import OutputHead, assemble_pose, split_raw_pose
from motionlab.models.motion_cell.words import WordDecoder, WordEncoder, from_words, to_words


class MotionCellOutput(NamedTuple):
    """What a training pass returns (``B`` clips, ``T`` frames, ``N = T / l`` words, ``J`` joints).

    Attributes:
        poses: reconstructed pose vectors ``(B, T, 90)`` with unit quaternions.
        rotation_params: the decoder's rotation outputs ``(B, T, J - 1, p)`` before projection (for eq. 26).
        posterior_mu, posterior_logvar, prior_mu, prior_logvar: ``(B, N, latent_dim)``.
    """

    poses: Tensor
    rotation_params: Tensor
    posterior_mu: Tensor
    posterior_logvar: Tensor
    prior_mu: Tensor
    prior_logvar: Tensor


class MotionCellModel(nn.Module):
    """Words -> Motion Cell -> words; ``codec`` carries the root statistics and the skeletons."""

    def __init__(self, cfg: MotionCellConfig, codec: PoseCodec) -> None:
        super().__init__()
        if codec.n_joints != cfg.n_joints:
            raise ValueError(
                f"MotionCellModel: the codec has {codec.n_joints} joints, the config {cfg.n_joints}"
            )
        self.cfg = cfg
        self.codec = codec
        self.head = OutputHead(cfg.output)
        self.word_encoder = WordEncoder(cfg.pose_dim, cfg.word_length, cfg.word_dim)
        self.word_decoder = WordDecoder(cfg.word_dim, cfg.word_length, self.head.raw_dim(cfg.n_joints))
        self.cell = MotionCell(cfg)

    def decode_words(self, codes: Tensor) -> tuple[Tensor, Tensor]:
        """Pose vectors ``(B, N * l, 90)`` and rotation parameters ``(B, N * l, J - 1, p)`` of word codes
        ``(B, N, word_dim)``."""
        raw = from_words(self.word_decoder(codes), self.cfg.word_length)
        params, root = split_raw_pose(raw, self.head, self.cfg.n_joints)
        return assemble_pose(self.head.quaternions(params), root), params

    def encode_words(self, poses: Tensor) -> Tensor:
        """``f_w(f_enc^w(words))`` ``(B, N, feature_dim)`` of pose vectors ``(B, N * l, 90)``."""
        return self.cell.word_feature(self.word_encoder(to_words(poses, self.cfg.word_length)))

    def _check_poses(self, poses: Tensor) -> None:
        if poses.dim() != 3 or poses.shape[-1] != self.cfg.pose_dim:
            raise ValueError(
                f"MotionCellModel: poses must be (B, T, {self.cfg.pose_dim}), got {tuple(poses.shape)}"
            )
        if poses.shape[1] % self.cfg.word_length:
            raise ValueError(
                f"MotionCellModel: {poses.shape[1]} frames are not a whole number of words of "
                f"{self.cfg.word_length} frames"
            )
        if not bool(torch.isfinite(poses).all()):
            raise ValueError("MotionCellModel: poses contain NaN or inf")

    def forward(
        self,
        poses: Tensor,
        action: Tensor,
        body: Tensor,
        word_drop: float = 0.0,
        generator: torch.Generator | None = None,
    ) -> MotionCellOutput:
        """Reconstruct ``poses`` ``(B, T, 90)`` (``T`` a multiple of ``l``) through the posterior.

        Args:
            action, body: control attributes ``(B,)``.
            word_drop: probability in ``[0, 1]`` of dropping each word from the recurrence input.
            generator: draws the initial state, the dropped words and the latents (default: global RNG).
        """
        self._check_poses(poses)
        if not 0.0 <= word_drop <= 1.0:
            raise ValueError(f"MotionCellModel: word_drop must lie in [0, 1], got {word_drop}")
        cell = self.cell
        word_features = self.encode_words(poses)
        batch, n_words = word_features.shape[:2]
        control = cell.control(action, body)
        controls = control[:, None].expand(batch, n_words, control.shape[-1])
        posterior_pre = cell.posterior_input(word_features, controls)
        keep = torch.rand(batch, n_words, 1, generator=generator) >= word_drop
        recurrent_words = word_features * keep
        layers = cell.initial_state(action, body, generator)
        states, latent_features, mus, logvars = [], [], [], []
        for t in range(n_words):
            states.append(layers[1])
            mu, logvar = cell.posterior(posterior_pre[:, t], layers[1])
            features = cell.latent_feature(reparameterize(mu, logvar, generator))
            layers = cell.transition(layers, recurrent_words[:, t], features, control)
            latent_features.append(features)
            mus.append(mu)
            logvars.append(logvar)
        previous = torch.stack(states, dim=1)
        prior_mu, prior_logvar = cell.prior(previous, controls)
        reconstruction, params = self.decode_words(
            cell.decode(torch.stack(latent_features, dim=1), previous, controls)
        )
        return MotionCellOutput(
            reconstruction,
            params,
            torch.stack(mus, dim=1),
            torch.stack(logvars, dim=1),
            prior_mu,
            prior_logvar,
        )

    @torch.no_grad()
    def generate(
        self, action: Tensor, body: Tensor, n_frames: int, generator: torch.Generator | None = None
    ) -> Tensor:
        """Sample pose vectors ``(B, n_frames, 90)`` for attributes ``(B,)``, any ``n_frames >= 1``.

        The same ``generator`` state gives bitwise-identical samples.
        """
        return self.rollout(action, body, n_frames, generator)

    def rollout(
        self,
        action: Tensor,
        body: Tensor,
        n_frames: int,
        generator: torch.Generator | None = None,
        truncate: bool = False,
    ) -> Tensor:
        """:meth:`generate` with gradients (for losses on samples).

        With ``truncate`` the recurrent state is detached after every word, so gradients reach each word's
        prior, decoder and word features but not the earlier words through the state (truncated
        back-propagation through time).
        """
        if isinstance(n_frames, bool) or not isinstance(n_frames, int) or n_frames < 1:
            raise ValueError(
                f"MotionCellModel.generate: n_frames must be a positive integer, got {n_frames!r}"
            )
        cell = self.cell
        control = cell.control(action, body)
        layers = cell.initial_state(action, body, generator)
        words = []
        for _ in range(math.ceil(n_frames / self.cfg.word_length)):
            mu, logvar = cell.prior(layers[1], control)
            features = cell.latent_feature(reparameterize(mu, logvar, generator))
            word, _ = self.decode_words(cell.decode(features, layers[1], control)[:, None])
            words.append(word)
            layers = cell.transition(layers, self.encode_words(word)[:, 0], features, control)
            if truncate:
                layers = (layers[0].detach(), layers[1].detach())
        return torch.cat(words, dim=1)[:, :n_frames]
