r"""TrajeVAE (Kania, Kowalski, Trzciński 2021): full-body motion completed from an initial pose and
trajectories.

Shapes: ``B`` sequences, ``T`` frames per window (frame 0 is the initial pose :math:`x_0`), ``F = T - 1``
frames to complete, ``J`` joints, poses as ``J * 3`` global coordinates in metres (the TrajeVAE
representation, :func:`motionlab.data.representations.to_trajevae`), ``d`` the width, ``C`` latent steps (DCT
components, or frames without the DCT), ``L`` latent numbers per step.

**Encoder.** A frame MLP shared by poses and trajectories embeds every frame (``d``); the initial-pose MLP
embeds :math:`x_0` (``d``) and is concatenated to every frame (tokens of ``2 d``). Self-attention over frames
and the DCT over time keeping ``C`` components: as in the paper (§3.2), prior and posterior share every
parameter up to here. Ours then adds a shared self-attention block over the components, and the unshared
branches are self-attention with linear heads (the paper: transformer-like encoders and final MLPs, unshared
from the DCT on); they give a mean and log-variance per component: the learnable prior
:math:`p_\text{traj}(z \mid Y, x_0)` from the trajectories :math:`Y = X \odot M` and the posterior
:math:`q_\text{pose}(z \mid X \odot (1 - M), x_0)`. The sinusoidal frame and component codes added to the
tokens are ours too (the paper does not describe any).

**Decoder** (eq. 1). The inverse DCT brings ``z`` back to ``F`` frames; concatenated with the initial-pose
embedding, mixed by an MLP and self-attention, it gives per-frame offsets that are accumulated from the
initial pose: :math:`\hat x_t = x_0 + \sum_{s=1}^{t} \Delta_s`.

**Training** decodes a posterior sample; the loss is the squared error summed over frames and coordinates (eq.
2) + β KL(q_pose ‖ p_traj) (:mod:`.losses`).
**Sampling** decodes prior samples :math:`z = \mu + \tau \sigma \epsilon` at temperature τ; a single sample
decodes the prior means (the deterministic prediction).

The ablation switches of :class:`TrajeVAEConfig` turn off the DCT, the learned prior (then one encoder
:math:`q(z \mid Y)` is pulled towards :math:`\mathcal N(0, I)` and sampled at test time), the yaw
augmentation (a data switch, see :mod:`.data`) and the posterior's mask.

The module reads top to bottom: the config, the layers (frame MLPs, position codes, attention blocks), the
decoder and the model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import torch
from torch import Tensor, nn

from motionlab import config
from motionlab.models.gaussian import reparameterize
from motionlab.models.trajevae.data import check_batch, check_task
from motionlab.models.trajevae.dct import dct, idct
from motionlab.models.trajevae.masks import KEEP_PROBABILITY, given_trajectories, hidden_poses
from motionlab.validation import Checked, check_scalar, choice, flag, integer, real

#: How the reconstruction term reduces the squared errors of a sequence (see :mod:`.losses`).
RECONSTRUCTIONS: tuple[str, ...] = ("sum", "mean")


@dataclass(frozen=True)
class WindowShape(Checked):
    """The window geometry every completion model's config shares: ``n_joints`` joints, ``n_frames`` frames
    (the initial pose included)."""

    n_joints: int = integer(22, minimum=1)
    n_frames: int = integer(120, minimum=2)

    @property
    def n_channels(self) -> int:
        """Numbers per pose, ``J * 3``."""
        return 3 * self.n_joints

    @property
    def n_future(self) -> int:
        """Frames to complete, ``n_frames - 1``."""
        return self.n_frames - 1


@dataclass(frozen=True)
class TrajeVAEConfig(WindowShape):
    """TrajeVAE's architecture, loss weight and the four ablation switches.

    Windows have ``n_frames`` frames: frame 0 is the initial pose, frames ``1 .. n_frames - 1`` are completed.

    Attributes:
        n_joints: skeleton joints ``J`` (poses are ``J * 3`` global coordinates, metres).
        n_frames: frames per window, initial pose included (120 = 4 s at 30 fps).
        width: ``d``, the size of a frame embedding and of the initial-pose embedding; the transformer
            tokens are their concatenation, ``2 d``.
        latent_dim: latent numbers per DCT component (per frame without the DCT).
        dct_components: the ``C`` lowest frequencies kept (at most ``n_frames - 1``); ignored without the DCT.
        heads: attention heads; layers: transformer layers in each attention block.
        beta: weight of ``KL(q_pose || p_traj)`` (the paper: 0.01, against the summed squared error).
        reconstruction: ``"sum"`` (the paper's eq. 2: squared errors summed over frames and coordinates) or
            ``"mean"`` (averaged over them, which weights the KL ``F * 3J`` times more for the same ``beta``;
            see :mod:`.losses`).
        keep_probability: chance that a joint's trajectory is given in a training sequence (0.15).
        use_dct: attend over DCT components (``False``: over frames).
        learnable_prior: a posterior ``q_pose(z | X)`` and a learned prior ``p_traj(z | Y)`` (``False``: one
            encoder ``q(z | Y)`` regularised towards ``N(0, I)``, the Base model).
        augment: turn every training sequence by a random yaw.
        mask_future_poses: the posterior sees ``X ⊙ (1 - M)`` instead of ``X`` (needs ``learnable_prior``).
        seed: seeds the weight initialisation.
    """

    width: int = integer(64, minimum=1)
    latent_dim: int = integer(32, minimum=1)
    dct_components: int = integer(40, minimum=1)
    heads: int = integer(4, minimum=1)
    layers: int = integer(1, minimum=1)
    beta: float = real(0.01, minimum=0)
    reconstruction: str = choice(RECONSTRUCTIONS, "sum")
    keep_probability: float = real(KEEP_PROBABILITY, minimum=0, maximum=1)
    use_dct: bool = flag(True)
    learnable_prior: bool = flag(True)
    augment: bool = flag(True)
    mask_future_poses: bool = flag(True)
    seed: int = config.seed_field()

    def __post_init__(self) -> None:
        super().__post_init__()
        where = "TrajeVAEConfig"
        check_scalar(self.dct_components, "dct_components", where, maximum=self.n_future)
        if (2 * self.width) % self.heads:
            raise ValueError(
                f"{where}: the token size 2 * width = {2 * self.width} must be divisible by "
                f"heads={self.heads}"
            )
        if self.mask_future_poses and not self.learnable_prior:
            raise ValueError(
                f"{where}: mask_future_poses masks the posterior's input, so it needs learnable_prior=True"
            )

    @property
    def n_latent_steps(self) -> int:
        """Latent vectors per sequence: the DCT components, or one per completed frame without the DCT."""
        return self.dct_components if self.use_dct else self.n_future


# --- layers ----------------------------------------------------------------------------------------


def frame_mlp(n_in: int, n_out: int) -> nn.Sequential:
    """The paper's encoder MLP, applied to every frame: (Linear → LayerNorm → LeakyReLU(0.1)) twice.

    ``(..., n_in) -> (..., n_out)``.
    """
    return nn.Sequential(
        nn.Linear(n_in, n_out),
        nn.LayerNorm(n_out),
        nn.LeakyReLU(0.1),
        nn.Linear(n_out, n_out),
        nn.LayerNorm(n_out),
        nn.LeakyReLU(0.1),
    )


def output_mlp(n_in: int, n_hidden: int, n_out: int) -> nn.Sequential:
    """Linear → LayerNorm → LeakyReLU(0.1) → Linear: ``(..., n_in) -> (..., n_out)`` with an unbounded
    output."""
    return nn.Sequential(
        nn.Linear(n_in, n_hidden), nn.LayerNorm(n_hidden), nn.LeakyReLU(0.1), nn.Linear(n_hidden, n_out)
    )


def sinusoidal_encoding(n_positions: int, dim: int) -> Tensor:
    r"""Fixed position codes ``(n_positions, dim)`` of "Attention is all you need".

    Channel pairs ``(2i, 2i + 1)`` hold :math:`\sin(p\,\omega_i)` and :math:`\cos(p\,\omega_i)` with
    :math:`\omega_i = 10000^{-2i/\mathrm{dim}}`; ``dim`` must be even.
    """
    if dim % 2:
        raise ValueError(f"sinusoidal_encoding: dim must be even, got {dim}")
    position = torch.arange(n_positions, dtype=torch.float64)[:, None]
    frequency = torch.exp(-math.log(10000.0) * torch.arange(0, dim, 2, dtype=torch.float64) / dim)
    codes = torch.zeros(n_positions, dim, dtype=torch.float64)
    codes[:, 0::2] = torch.sin(position * frequency)
    codes[:, 1::2] = torch.cos(position * frequency)
    return codes.float()


def attention_block(dim: int, heads: int, layers: int) -> nn.TransformerEncoder:
    """``layers`` pre-norm transformer encoder layers (self-attention + MLP of width ``2 dim``, no dropout),
    closed by a LayerNorm.

    ``(B, N, dim) -> (B, N, dim)``, attending over all ``N`` tokens (frames or DCT components). The final norm
    matters after the DCT: the first coefficient is ``sqrt(F)`` times the mean frame, and without it that
    scale would reach the Gaussian heads unnormalised.
    """
    layer = nn.TransformerEncoderLayer(
        dim, heads, dim_feedforward=2 * dim, dropout=0.0, batch_first=True, norm_first=True
    )
    return nn.TransformerEncoder(layer, layers, norm=nn.LayerNorm(dim), enable_nested_tensor=False)


class GaussianBranch(nn.Module):
    """An unshared branch: self-attention, then linear heads give each token's latent mean and log-variance
    (the paper's branches end in MLPs).

    ``(B, N, dim) -> (mu, logvar)``, each ``(B, N, latent_dim)``.
    """

    def __init__(self, dim: int, latent_dim: int, heads: int, layers: int) -> None:
        super().__init__()
        self.attention = attention_block(dim, heads, layers)
        self.mean = nn.Linear(dim, latent_dim)
        self.log_variance = nn.Linear(dim, latent_dim)

    def forward(self, tokens: Tensor) -> tuple[Tensor, Tensor]:
        hidden = self.attention(tokens)
        return self.mean(hidden), self.log_variance(hidden)


# --- the model -------------------------------------------------------------------------------------


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


class CompletionTask(NamedTuple):
    """A checked ``sample`` request: initial poses ``(B, J * 3)``, given trajectories ``(B, F, J * 3)``
    (``Y = X ⊙ M``, zeros where unknown), the batch size ``B``, ``K = n_samples`` completions per window,
    the temperature and the noise's generator."""

    initial_pose: Tensor
    trajectories: Tensor
    batch: int
    n_samples: int
    temperature: float
    generator: torch.Generator | None


class Completer(nn.Module):
    """A model that completes windows from their initial pose and given trajectories (TrajeVAE, and the
    GRUCompletion and CVAERNN baselines): what the evaluation needs. :meth:`sample` checks a request once;
    each model's :meth:`draw` answers it."""

    cfg: WindowShape

    @torch.no_grad()
    def sample(
        self,
        initial_pose: Tensor,
        trajectories: Tensor,
        n_samples: int,
        temperature: float = 1.0,
        generator: torch.Generator | None = None,
    ) -> Tensor:
        """Completions ``(B, K, F, J * 3)``, ``K = n_samples`` (how each model draws them: :meth:`draw`).

        Args:
            initial_pose: ``(B, J * 3)``; trajectories: ``(B, F, J * 3)``, ``Y = X ⊙ M`` (zeros where
            unknown). n_samples: ``K``. temperature: a number >= 0 scaling the model's noise. generator: the
            noise's ``torch.Generator`` (same seed, bitwise-identical samples).
        """
        cfg = self.cfg
        where = f"{type(self).__name__}.sample"
        batch = check_task(
            initial_pose, trajectories, n_samples, temperature, cfg.n_frames, cfg.n_joints, where
        )
        return self.draw(CompletionTask(initial_pose, trajectories, batch, n_samples, temperature, generator))

    def draw(self, task: CompletionTask) -> Tensor:
        """Completions ``(B, K, F, J * 3)`` of a checked request (each model defines it)."""
        raise NotImplementedError(f"{type(self).__name__} does not define draw")


class TrajeVAE(Completer):
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
        d)``. The paper shares up to the DCT; the attention block after it is ours."""
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
        check_batch(windows, mask, self.cfg.n_frames, self.cfg.n_joints, "TrajeVAE.forward")
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
    def draw(self, task: CompletionTask) -> Tensor:
        """Completions ``(B, K, F, J * 3)`` from the prior: with ``K = 1`` the prior means are decoded (the
        deterministic prediction); ``temperature`` scales the prior's standard deviation (0 decodes the
        means for every sample)."""
        initial_pose, trajectories, batch, n_samples, temperature, generator = task
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
