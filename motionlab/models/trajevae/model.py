r"""TrajeVAE (Kania, Kowalski, Trzciński 2021): full-body motion completed from an initial pose and
trajectories.

Shapes: ``B`` sequences, ``T`` frames per window (frame 0 is the initial pose :math:`x_0`), ``F = T - 1``
frames to complete, ``J`` joints, poses as ``J * 3`` global coordinates in metres (the TrajeVAE
representation, :func:`motionlab.data.representations.to_trajevae`), ``d`` the width, ``C`` latent steps (DCT
components, or frames without the DCT), ``L`` latent numbers per step.

**Encoder.** A frame MLP shared by poses and trajectories embeds every frame (``d``); the initial-pose MLP
embeds :math:`x_0` (``d``) and is concatenated to every frame (tokens of ``2 d``, plus a sinusoidal frame
code). Self-attention over frames, the DCT over time keeping ``C`` components (plus a component code),
self-attention over components: this trunk is shared. Then unshared branches give a mean and log-variance
per component: the learnable prior :math:`p_\text{traj}(z \mid Y, x_0)` from the trajectories
:math:`Y = X \odot M` and the posterior :math:`q_\text{pose}(z \mid X \odot (1 - M), x_0)`.

**Decoder** (eq. 1). The inverse DCT brings ``z`` back to ``F`` frames; concatenated with the initial-pose
embedding, mixed by an MLP and self-attention, it gives per-frame offsets that are accumulated from the
initial pose: :math:`\hat x_t = x_0 + \sum_{s=1}^{t} \Delta_s`.

**Training** decodes a posterior sample; the loss is MSE + β KL(q_pose ‖ p_traj) (:mod:`.losses`).
**Sampling** decodes prior samples :math:`z = \mu + \tau \sigma \epsilon` at temperature τ; a single sample
decodes the prior means (the deterministic prediction).

The ablation switches of :class:`~motionlab.models.trajevae.config.TrajeVAEConfig` turn off the DCT, the
learned prior (then one encoder :math:`q(z \mid Y)` is pulled towards :math:`\mathcal N(0, I)` and sampled at
test time), the yaw augmentation (a data switch, see :mod:`.data`) and the posterior's mask.
"""

from __future__ import annotations

from typing import NamedTuple

import torch
from torch import Tensor, nn

from motionlab.models.gaussian import reparameterize
from motionlab.models.trajevae.config import TrajeVAEConfig
from motionlab.models.trajevae.dct import dct, idct
from motionlab.models.trajevae.inputs import check_masks, check_sampling, check_task, check_windows
from motionlab.models.trajevae.layers import (
    GaussianBranch,
    attention_block,
    frame_mlp,
    output_mlp,
    sinusoidal_encoding,
)
from motionlab.models.trajevae.masks import given_trajectories, hidden_poses


class Gaussian(NamedTuple):
    """A diagonal Gaussian per latent step: ``mu`` and ``logvar``, each ``(B, C, L)``."""

    mu: Tensor
    logvar: Tensor


class CompletionOutput(NamedTuple):
    """What a training forward pass gives.

    Attributes:
        poses: completed frames ``(B, F, J * 3)``.
        prior: ``p_traj(z | Y)`` (the Base model's only encoder, ``q(z | Y)``).
        posterior: ``q_pose(z | X ⊙ (1 - M))``, or ``None`` without the learnable prior.
    """

    poses: Tensor
    prior: Gaussian
    posterior: Gaussian | None


class TrajeVAEDecoder(nn.Module):
    """Latents ``(B, C, L)`` + initial pose ``(B, J * 3)`` and its embedding ``(B, d)`` → frames ``(B, F, J *
    3)``."""

    def __init__(self, cfg: TrajeVAEConfig) -> None:
        super().__init__()
        self.cfg = cfg
        token = 2 * cfg.width
        self.mix = output_mlp(cfg.latent_dim + cfg.width, token, token)
        self.attention = attention_block(token, cfg.heads, cfg.layers)
        self.offsets = output_mlp(token, token, cfg.n_channels)
        nn.init.zeros_(
            self.offsets[-1].weight
        )  # start from a still pose: zero offsets, the initial pose held
        nn.init.zeros_(self.offsets[-1].bias)
        self.register_buffer("frame_code", sinusoidal_encoding(cfg.n_future, token), persistent=False)

    def forward(self, z: Tensor, initial_pose: Tensor, initial_embedding: Tensor) -> Tensor:
        frames = idct(z, self.cfg.n_future) if self.cfg.use_dct else z
        context = initial_embedding[:, None, :].expand(-1, frames.shape[1], -1)
        hidden = self.attention(self.mix(torch.cat([frames, context], dim=-1)) + self.frame_code)
        return initial_pose[:, None, :] + torch.cumsum(self.offsets(hidden), dim=1)


class TrajeVAE(nn.Module):
    """The TrajeVAE model of a :class:`TrajeVAEConfig` (see the module docstring)."""

    def __init__(self, cfg: TrajeVAEConfig) -> None:
        super().__init__()
        if not isinstance(cfg, TrajeVAEConfig):
            raise TypeError(f"TrajeVAE needs a TrajeVAEConfig, got {type(cfg).__name__}")
        self.cfg = cfg
        token = 2 * cfg.width
        generator_state = torch.random.get_rng_state()
        torch.manual_seed(cfg.seed)
        self.frame_encoder = frame_mlp(cfg.n_channels, cfg.width)
        self.initial_pose_encoder = frame_mlp(cfg.n_channels, cfg.width)
        self.before_dct = attention_block(token, cfg.heads, cfg.layers)
        self.after_dct = attention_block(token, cfg.heads, cfg.layers)
        self.prior_branch = GaussianBranch(token, cfg.latent_dim, cfg.heads, cfg.layers)
        self.posterior_branch = (
            GaussianBranch(token, cfg.latent_dim, cfg.heads, cfg.layers) if cfg.learnable_prior else None
        )
        self.decoder = TrajeVAEDecoder(cfg)
        torch.random.set_rng_state(generator_state)
        self.register_buffer("frame_code", sinusoidal_encoding(cfg.n_future, token), persistent=False)
        self.register_buffer("step_code", sinusoidal_encoding(cfg.n_latent_steps, token), persistent=False)

    # --- encoder -------------------------------------------------------------------------------------
    def trunk(self, sequence: Tensor, initial_embedding: Tensor) -> Tensor:
        """The shared encoder: frames ``(B, F, J * 3)`` and ``(B, d)`` → tokens per latent step ``(B, C, 2
        d)``."""
        context = initial_embedding[:, None, :].expand(-1, sequence.shape[1], -1)
        tokens = self.before_dct(torch.cat([self.frame_encoder(sequence), context], dim=-1) + self.frame_code)
        if self.cfg.use_dct:
            tokens = dct(tokens, dim=-2, n_components=self.cfg.dct_components)
        return self.after_dct(tokens + self.step_code)

    def prior(self, trajectories: Tensor, initial_embedding: Tensor) -> Gaussian:
        """``p_traj(z | Y, x_0)`` from trajectories ``(B, F, J * 3)`` (zeros for joints to complete)."""
        return Gaussian(*self.prior_branch(self.trunk(trajectories, initial_embedding)))

    def posterior(self, seen_poses: Tensor, initial_embedding: Tensor) -> Gaussian:
        """``q_pose(z | ·, x_0)`` from the poses the posterior sees ``(B, F, J * 3)``."""
        if self.posterior_branch is None:
            raise RuntimeError(
                "TrajeVAE.posterior: this configuration has no learnable prior, hence no posterior"
            )
        return Gaussian(*self.posterior_branch(self.trunk(seen_poses, initial_embedding)))

    # --- training pass -------------------------------------------------------------------------------
    def forward(
        self, windows: Tensor, mask: Tensor, generator: torch.Generator | None = None
    ) -> CompletionOutput:
        """Reconstruct windows ``(B, T, J * 3)`` given joint masks ``(B, J)`` bool (True: trajectory
        given)."""
        func = "TrajeVAE.forward"
        check_windows(windows, self.cfg.n_frames, self.cfg.n_channels, func)
        check_masks(mask, windows.shape[0], self.cfg.n_joints, func)
        initial_pose, future = windows[:, 0], windows[:, 1:]
        initial_embedding = self.initial_pose_encoder(initial_pose)
        prior = self.prior(given_trajectories(future, mask), initial_embedding)
        if self.cfg.learnable_prior:
            seen = hidden_poses(future, mask) if self.cfg.mask_future_poses else future
            posterior = self.posterior(seen, initial_embedding)
            z = reparameterize(posterior.mu, posterior.logvar, generator)
        else:
            posterior = None
            z = reparameterize(prior.mu, prior.logvar, generator)
        return CompletionOutput(self.decoder(z, initial_pose, initial_embedding), prior, posterior)

    # --- sampling ------------------------------------------------------------------------------------
    @torch.no_grad()
    def sample(
        self,
        initial_pose: Tensor,
        trajectories: Tensor,
        n_samples: int,
        temperature: float = 1.0,
        generator: torch.Generator | None = None,
    ) -> Tensor:
        """Completions ``(B, K, F, J * 3)`` from the prior, ``K = n_samples``.

        Args:
            initial_pose: ``(B, J * 3)``; trajectories: ``(B, F, J * 3)``, ``Y = X ⊙ M`` (zeros where
            unknown). n_samples: ``K``; with ``K = 1`` the prior means are decoded (the deterministic
            prediction). temperature: scales the prior's standard deviation (0 decodes the means for every
            sample). generator: the noise's ``torch.Generator`` (same seed, bitwise-identical samples).
        """
        func = "TrajeVAE.sample"
        batch = check_task(initial_pose, trajectories, self.cfg.n_future, self.cfg.n_channels, func)
        check_sampling(n_samples, temperature, func)
        initial_embedding = self.initial_pose_encoder(initial_pose)
        prior = self.prior(trajectories, initial_embedding)
        mu = prior.mu.repeat_interleave(n_samples, dim=0)
        if n_samples == 1 or temperature == 0:
            z = mu
        else:
            std = torch.exp(0.5 * prior.logvar).repeat_interleave(n_samples, dim=0)
            z = mu + temperature * std * torch.randn(mu.shape, generator=generator, dtype=mu.dtype)
        poses = self.decoder(
            z,
            initial_pose.repeat_interleave(n_samples, dim=0),
            initial_embedding.repeat_interleave(n_samples, dim=0),
        )
        return poses.unflatten(0, (batch, n_samples))
