"""Variational autoencoders for poses and clips: an MLP (C)VAE and a recurrent CVAE with an autoregressive
decoder.

Both models share one interface, so one loss function (:func:`~motionlab.models.vae.losses.elbo_loss`)
trains either through :func:`motionlab.train.train_or_load`:

* ``encode(x, label) -> (mu, logvar)``: the Gaussian posterior q(z | x, c), ``(B, latent_dim)`` each;
* ``decode(z, label) -> mean``: the mean of the likelihood p(x | z, c) = N(mean, sigma_x^2 I), shaped like x;
* ``forward(x, label, generator) -> VAEOutput``: both, with a reparameterised draw of z in between;
* ``sample(label, generator)``: decode draws from the prior p(z) = N(0, sigma_p^2 I).

``label`` is the class c of a conditional VAE (``(B,)`` int64, one-hot encoded inside) and must be ``None``
for an unconditional one. Inputs are standardised features (see
:class:`motionlab.data.datasets.Standardizer`).

With ``variational=False`` the MLP model is a plain autoencoder: the code is ``mu`` itself, no noise, no KL.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import NamedTuple

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from motionlab.models.gaussian import reparameterize
from motionlab.validation import Checked, check_scalar, check_tensor, flag, integer, real, tuple_of


class VAEOutput(NamedTuple):
    """What a forward pass gives: the likelihood mean ``(B, ...)`` (x's shape), and ``mu``, ``logvar``, ``z``
    ``(B, latent_dim)`` (for an autoencoder ``logvar`` is ``None`` and ``z`` is ``mu``)."""

    mean: Tensor
    mu: Tensor
    logvar: Tensor | None
    z: Tensor


@dataclass(frozen=True)
class VAEConfig(Checked):
    """An MLP (conditional) VAE on inputs of a fixed shape (a pose ``(D,)`` or a clip ``(L, D)``, flattened
    inside).

    Attributes:
        input_shape: shape of one input, e.g. ``(64,)`` or ``(60, 67)``.
        latent_dim: size of z.
        hidden: width of the hidden layers; depth: hidden layers in the encoder and in the decoder.
        n_classes: number of classes of the condition c (0: unconditional).
        variational: False gives a plain autoencoder (deterministic code, no KL term).
        obs_logvar: log sigma_x^2 of the likelihood N(decoder(z), sigma_x^2 I), in standardised units.
        prior_logvar: log sigma_p^2 of the prior N(0, sigma_p^2 I) (0 is the standard normal).
    """

    input_shape: tuple[int, ...] = tuple_of(kind=numbers.Integral, minimum=1, nonempty=True)
    latent_dim: int = integer(16, minimum=1)
    hidden: int = integer(256, minimum=1)
    depth: int = integer(2, minimum=1)
    n_classes: int = integer(0, minimum=0)
    variational: bool = flag(True)
    obs_logvar: float = real(0.0)
    prior_logvar: float = real(0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "input_shape", tuple(self.input_shape))  # e.g. a torch.Size or a list
        super().__post_init__()

    @property
    def input_size(self) -> int:
        """Number of numbers in one input."""
        return math.prod(self.input_shape)


@dataclass(frozen=True)
class RecurrentVAEConfig(Checked):
    """A recurrent (conditional) VAE on clips ``(L, n_features)`` with a GRU encoder and a GRU decoder.

    Attributes:
        n_features: features per frame.
        length: frames the decoder generates when sampling (the training clips' length).
        latent_dim, hidden: size of z and of the GRU states.
        n_classes: number of classes of the condition c (0: unconditional).
        autoregressive: the decoder also reads the previous frame (teacher forcing in training, its own
            output when sampling). This makes it a *strong* decoder, one that can model a clip without z.
        frame_dropout: in training, the probability that the decoder's previous-frame input is hidden
            (zeroed), independently per frame: Bowman et al.'s word dropout for frames (0: off).
        obs_logvar, prior_logvar: as in :class:`VAEConfig`.
    """

    n_features: int = integer(minimum=1)
    length: int = integer(60, minimum=1)
    latent_dim: int = integer(16, minimum=1)
    hidden: int = integer(128, minimum=1)
    n_classes: int = integer(0, minimum=0)
    autoregressive: bool = flag(True)
    frame_dropout: float = real(0.0, minimum=0, below=1)
    obs_logvar: float = real(0.0)
    prior_logvar: float = real(0.0)


def _mlp(sizes: list[int]) -> nn.Sequential:
    """Linear layers of ``sizes`` with SiLU between them (none after the last)."""
    layers: list[nn.Module] = []
    for i, (a, b) in enumerate(zip(sizes[:-1], sizes[1:])):
        layers.append(nn.Linear(a, b))
        if i < len(sizes) - 2:
            layers.append(nn.SiLU())
    return nn.Sequential(*layers)


class LatentVariableModel(nn.Module):
    """What both VAEs share: label checks, one-hot conditions, the reparameterised forward pass, prior draws.

    Subclasses set ``cfg`` and define ``encode(x, label) -> (mu, logvar)`` and ``decode(z, label) -> mean``.
    """

    cfg: VAEConfig | RecurrentVAEConfig

    @property
    def variational(self) -> bool:
        return getattr(self.cfg, "variational", True)

    def condition(self, label: Tensor | None, batch: int, where: str) -> Tensor | None:
        """One-hot ``(B, n_classes)`` of ``label`` ``(B,)``; ``None`` for an unconditional model."""
        n_classes = self.cfg.n_classes
        if n_classes == 0:
            if label is not None:
                raise ValueError(f"{where}: this model is unconditional (n_classes=0) but a label was given")
            return None
        if label is None:
            raise ValueError(f"{where}: this model is conditional on {n_classes} classes; pass label (B,)")
        label = torch.as_tensor(label)
        if label.is_floating_point() or label.dtype == torch.bool:
            raise TypeError(f"{where}: label must have an integer dtype, got {label.dtype}")
        if label.dim() != 1 or label.shape[0] != batch:
            raise ValueError(f"{where}: label must have shape ({batch},), got {tuple(label.shape)}")
        if batch and (int(label.min()) < 0 or int(label.max()) >= n_classes):
            raise ValueError(
                f"{where}: label values must lie in [0, {n_classes}), got [{int(label.min())}, "
                f"{int(label.max())}]"
            )
        return F.one_hot(label.long(), n_classes).float()

    def forward(
        self, x: Tensor, label: Tensor | None = None, generator: torch.Generator | None = None
    ) -> VAEOutput:
        """Encode, draw ``z = mu + sigma * eps`` (an autoencoder uses ``mu``), decode."""
        mu, logvar = self.encode(x, label)
        z = mu if logvar is None else reparameterize(mu, logvar, generator)
        return VAEOutput(self.reconstruct(x, z, label), mu, logvar, z)

    def reconstruct(self, x: Tensor, z: Tensor, label: Tensor | None) -> Tensor:
        """The likelihood mean of ``x`` given ``z`` (the recurrent model overrides it with teacher
        forcing)."""
        return self.decode(z, label)

    def prior_sample(self, n: int, generator: torch.Generator | None = None) -> Tensor:
        """``n`` draws ``(n, latent_dim)`` from the prior N(0, sigma_p^2 I)."""
        check_scalar(n, "n", "prior_sample", kind=numbers.Integral, minimum=1)
        eps = torch.randn(n, self.cfg.latent_dim, generator=generator)
        return eps * math.exp(0.5 * self.cfg.prior_logvar)

    @torch.no_grad()
    def sample(self, label: Tensor | int, generator: torch.Generator | None = None) -> Tensor:
        """Decode prior draws: ``label`` ``(B,)`` class ids for a CVAE, or the number of samples ``B``
        otherwise."""
        was_training = self.training
        self.eval()
        try:
            if isinstance(label, int) and not isinstance(label, bool):
                if self.cfg.n_classes:
                    raise ValueError("sample: this model is conditional; pass the class of each sample (B,)")
                return self.decode(self.prior_sample(label, generator))
            label = torch.as_tensor(label)
            return self.decode(self.prior_sample(int(label.shape[0]), generator), label)
        finally:
            self.train(was_training)


class MLPVAE(LatentVariableModel):
    """An MLP (conditional) VAE, or autoencoder, on fixed-shape inputs ``(B, *cfg.input_shape)``."""

    def __init__(self, cfg: VAEConfig) -> None:
        super().__init__()
        self.cfg = cfg
        code_size = 2 * cfg.latent_dim if cfg.variational else cfg.latent_dim
        self.encoder = _mlp([cfg.input_size + cfg.n_classes] + [cfg.hidden] * cfg.depth + [code_size])
        self.decoder = _mlp([cfg.latent_dim + cfg.n_classes] + [cfg.hidden] * cfg.depth + [cfg.input_size])

    def encode(self, x: Tensor, label: Tensor | None = None) -> tuple[Tensor, Tensor | None]:
        """Posterior parameters ``mu``, ``logvar`` ``(B, latent_dim)`` of inputs ``x`` ``(B, *input_shape)``
        (``logvar`` is ``None`` for an autoencoder)."""
        shape = self.cfg.input_shape
        x = check_tensor(x, "x", "MLPVAE.encode", ndim=len(shape) + 1, trailing=shape)
        c = self.condition(label, x.shape[0], "MLPVAE.encode")
        h = x.flatten(1) if c is None else torch.cat([x.flatten(1), c], dim=-1)
        code = self.encoder(h)
        if not self.cfg.variational:
            return code, None
        mu, logvar = code.chunk(2, dim=-1)
        return mu, logvar

    def decode(self, z: Tensor, label: Tensor | None = None) -> Tensor:
        """Likelihood mean ``(B, *input_shape)`` from codes ``z`` ``(B, latent_dim)``."""
        check_tensor(z, "z", "MLPVAE.decode", ndim=2, trailing=(self.cfg.latent_dim,), finite=False)
        c = self.condition(label, z.shape[0], "MLPVAE.decode")
        h = z if c is None else torch.cat([z, c], dim=-1)
        return self.decoder(h).unflatten(1, self.cfg.input_shape)


class RecurrentVAE(LatentVariableModel):
    """A GRU (conditional) VAE on clips ``(B, L, n_features)``; the decoder may be autoregressive.

    Encoder: a GRU reads the frames (with c appended to each), its last state gives ``mu``, ``logvar``.
    Decoder: its state starts at ``tanh(W [z, c])``; at frame t it reads ``[x_{t-1}, z, c]`` (``x_{-1} = 0``;
    without ``autoregressive`` just ``[z, c]``) and outputs the mean of frame t. In training (:meth:`forward`)
    ``x_{t-1}`` is the real previous frame (teacher forcing); when sampling it is the decoder's own output.
    """

    def __init__(self, cfg: RecurrentVAEConfig) -> None:
        super().__init__()
        self.cfg = cfg
        cond = cfg.n_classes
        self.encoder = nn.GRU(cfg.n_features + cond, cfg.hidden, batch_first=True)
        self.to_posterior = nn.Linear(cfg.hidden, 2 * cfg.latent_dim)
        self.to_state = nn.Linear(cfg.latent_dim + cond, cfg.hidden)
        frame_in = cfg.n_features if cfg.autoregressive else 0
        self.decoder = nn.GRU(frame_in + cfg.latent_dim + cond, cfg.hidden, batch_first=True)
        self.to_frame = nn.Linear(cfg.hidden, cfg.n_features)

    def _check_clip(self, x: Tensor, where: str) -> Tensor:
        """Clips ``(B, L, n_features)`` with ``L >= 1``, finite."""
        check_tensor(x, "x", where, ndim=3, trailing=(None, self.cfg.n_features))
        if x.shape[1] < 1:
            raise ValueError(f"{where}: x must hold at least one frame, got shape {tuple(x.shape)}")
        return x

    def encode(self, x: Tensor, label: Tensor | None = None) -> tuple[Tensor, Tensor]:
        """Posterior parameters ``mu``, ``logvar`` ``(B, latent_dim)`` of clips ``x`` ``(B, L,
        n_features)``."""
        x = self._check_clip(x, "RecurrentVAE.encode")
        c = self.condition(label, x.shape[0], "RecurrentVAE.encode")
        h = x if c is None else torch.cat([x, c[:, None].expand(-1, x.shape[1], -1)], dim=-1)
        _, last = self.encoder(h)
        mu, logvar = self.to_posterior(last[0]).chunk(2, dim=-1)
        return mu, logvar

    def _context(self, z: Tensor, label: Tensor | None, where: str) -> tuple[Tensor, Tensor]:
        """The per-frame context ``[z, c]`` ``(B, latent + n_classes)`` and the initial decoder state ``(1, B,
        hidden)``."""
        check_tensor(z, "z", where, ndim=2, trailing=(self.cfg.latent_dim,), finite=False)
        c = self.condition(label, z.shape[0], where)
        context = z if c is None else torch.cat([z, c], dim=-1)
        return context, torch.tanh(self.to_state(context))[None]

    def reconstruct(self, x: Tensor, z: Tensor, label: Tensor | None) -> Tensor:
        """Teacher-forced likelihood means ``(B, L, n_features)``: frame t is predicted from real frames < t.

        In training mode each previous-frame input is hidden with probability ``cfg.frame_dropout``.
        """
        x = self._check_clip(x, "RecurrentVAE.reconstruct")
        context, state = self._context(z, label, "RecurrentVAE.reconstruct")
        inputs = context[:, None].expand(-1, x.shape[1], -1)
        if self.cfg.autoregressive:
            previous = torch.cat([torch.zeros_like(x[:, :1]), x[:, :-1]], dim=1)
            if self.training and self.cfg.frame_dropout > 0:
                keep = torch.rand(previous.shape[:2], device=x.device) >= self.cfg.frame_dropout
                previous = previous * keep[..., None]
            inputs = torch.cat([previous, inputs], dim=-1)
        out, _ = self.decoder(inputs, state)
        return self.to_frame(out)

    def decode(self, z: Tensor, label: Tensor | None = None, length: int | None = None) -> Tensor:
        """Free-running decoding of ``length`` frames (default ``cfg.length``): ``(B, length, n_features)``.

        An autoregressive decoder feeds each frame's mean back as the next frame's input.
        """
        length = self.cfg.length if length is None else length
        check_scalar(length, "length", "RecurrentVAE.decode", kind=numbers.Integral, minimum=1)
        context, state = self._context(z, label, "RecurrentVAE.decode")
        if not self.cfg.autoregressive:
            out, _ = self.decoder(context[:, None].expand(-1, length, -1), state)
            return self.to_frame(out)
        frame = z.new_zeros(z.shape[0], 1, self.cfg.n_features)
        frames = []
        for _ in range(length):
            out, state = self.decoder(torch.cat([frame, context[:, None]], dim=-1), state)
            frame = self.to_frame(out)
            frames.append(frame)
        return torch.cat(frames, dim=1)
