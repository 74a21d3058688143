r"""The paper's recurrent baselines, given the same initial pose and trajectories as TrajeVAE.

The paper's supplement B says only that both are built as in DLow, with GRUs, at TrajeVAE's sizes, and that
the recurrent decoder also reads :math:`Y_t`; the architecture below is ours.

Both read the task frame by frame: the trajectories :math:`Y_t` (``J * 3``, zeros for joints to complete)
with the initial pose :math:`x_0`. Like TrajeVAE they output per-frame offsets accumulated from the
initial pose, :math:`\hat x_t = x_0 + \sum_{s \le t} \Delta_s`, so the three models differ only in how they
turn the task into offsets.

* :class:`GRUCompletion` -- deterministic: a bidirectional GRU summarises the whole task into a context
  vector; a forward GRU reads the context and :math:`Y_t` and emits :math:`\Delta_t`. Every "sample" is the
  same completion.
* :class:`CVAERNN` -- a conditional VAE in the style of DLow's base model: the same context, a GRU
  posterior :math:`q(z \mid X, \text{context})` with **one** latent vector for the whole sequence, prior
  :math:`\mathcal N(0, I)`, and the decoder GRU reads :math:`z` at every frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor, nn

from motionlab import config
from motionlab.models.gaussian import reparameterize
from motionlab.models.trajevae.data import check_batch
from motionlab.models.trajevae.masks import KEEP_PROBABILITY, given_trajectories
from motionlab.models.trajevae.model import (
    RECONSTRUCTIONS,
    Completer,
    CompletionTask,
    Gaussian,
    WindowShape,
)
from motionlab.validation import choice, flag, integer, real


@dataclass(frozen=True)
class RecurrentConfig(WindowShape):
    """A recurrent completion baseline.

    Attributes:
        n_joints, n_frames: as in :class:`~motionlab.models.trajevae.model.TrajeVAEConfig`.
        hidden: GRU width (the bidirectional context GRU has ``hidden`` per direction).
        latent_dim: numbers in the sequence's latent vector; 0 makes the deterministic GRU model.
        beta: KL weight of the CVAE (unused when ``latent_dim == 0``).
        reconstruction: ``"sum"`` or ``"mean"`` over frames and coordinates, as for TrajeVAE (the GRU's loss
            is the reconstruction alone, so for it the two differ only by a constant factor).
        keep_probability, augment: the training data, as for TrajeVAE.
        seed: seeds the weight initialisation.
    """

    n_frames: int = 60
    hidden: int = integer(64, minimum=1)
    latent_dim: int = integer(0, minimum=0)
    beta: float = real(0.01, minimum=0)
    reconstruction: str = choice(RECONSTRUCTIONS, "sum")
    keep_probability: float = real(KEEP_PROBABILITY, minimum=0, maximum=1)
    augment: bool = flag(True)
    seed: int = config.seed_field()


class TaskContext(nn.Module):
    """Bidirectional GRU over ``[Y_t, x_0]``, averaged over time and mixed: ``(B, F, J*3), (B, J*3) -> (B,
    H)``."""

    def __init__(self, n_channels: int, hidden: int) -> None:
        super().__init__()
        self.rnn = nn.GRU(2 * n_channels, hidden, batch_first=True, bidirectional=True)
        self.mix = nn.Sequential(nn.Linear(2 * hidden, hidden), nn.Tanh())

    def forward(self, trajectories: Tensor, initial_pose: Tensor) -> Tensor:
        start = initial_pose[:, None, :].expand(-1, trajectories.shape[1], -1)
        states, _ = self.rnn(torch.cat([trajectories, start], dim=-1))
        return self.mix(states.mean(dim=1))


class OffsetDecoder(nn.Module):
    """Forward GRU over ``[Y_t, context, z]`` emitting offsets accumulated from ``x_0``: → ``(B, F, J *
    3)``."""

    def __init__(self, n_channels: int, hidden: int, latent_dim: int) -> None:
        super().__init__()
        self.initial_state = nn.Linear(hidden + latent_dim, hidden)
        self.rnn = nn.GRU(n_channels + hidden + latent_dim, hidden, batch_first=True)
        self.offsets = nn.Linear(hidden, n_channels)
        nn.init.zeros_(self.offsets.weight)  # start from a still pose
        nn.init.zeros_(self.offsets.bias)

    def forward(self, trajectories: Tensor, initial_pose: Tensor, condition: Tensor) -> Tensor:
        steps = condition[:, None, :].expand(-1, trajectories.shape[1], -1)
        state = torch.tanh(self.initial_state(condition))[None]
        hidden, _ = self.rnn(torch.cat([trajectories, steps], dim=-1), state.contiguous())
        return initial_pose[:, None, :] + torch.cumsum(self.offsets(hidden), dim=1)


class _RecurrentCompletion(Completer):
    """What both baselines share: the config check, the context and the decoder."""

    def __init__(self, cfg: RecurrentConfig, stochastic: bool) -> None:
        super().__init__()
        if not isinstance(cfg, RecurrentConfig):
            raise TypeError(f"{type(self).__name__} needs a RecurrentConfig, got {type(cfg).__name__}")
        if (cfg.latent_dim > 0) != stochastic:
            raise ValueError(
                f"{type(self).__name__} needs RecurrentConfig.latent_dim "
                f"{'>= 1' if stochastic else '= 0'}, got {cfg.latent_dim}"
            )
        self.cfg = cfg
        generator_state = torch.random.get_rng_state()
        torch.manual_seed(cfg.seed)
        self.context = TaskContext(cfg.n_channels, cfg.hidden)
        self.decoder = OffsetDecoder(cfg.n_channels, cfg.hidden, cfg.latent_dim)
        self.build_extra()
        torch.random.set_rng_state(generator_state)

    def build_extra(self) -> None:
        """Modules a subclass adds (built under the same seed)."""

    def _check_batch(self, windows: Tensor, mask: Tensor, where: str) -> tuple[Tensor, Tensor, Tensor]:
        """Check a training batch; return the initial poses, the true future and the given trajectories."""
        check_batch(windows, mask, self.cfg.n_frames, self.cfg.n_joints, where)
        return windows[:, 0], windows[:, 1:], given_trajectories(windows[:, 1:], mask)


class GRUCompletion(_RecurrentCompletion):
    """The deterministic GRU baseline (``RecurrentConfig.latent_dim == 0``)."""

    def __init__(self, cfg: RecurrentConfig) -> None:
        super().__init__(cfg, stochastic=False)

    def complete(self, initial_pose: Tensor, trajectories: Tensor) -> Tensor:
        """The completion ``(B, F, J * 3)`` of initial poses ``(B, J * 3)`` and trajectories ``(B, F, J *
        3)``."""
        return self.decoder(trajectories, initial_pose, self.context(trajectories, initial_pose))

    def forward(self, windows: Tensor, mask: Tensor) -> Tensor:
        """Completed frames ``(B, F, J * 3)`` of windows ``(B, T, J * 3)`` given joint masks ``(B, J)``."""
        initial_pose, _, trajectories = self._check_batch(windows, mask, "GRUCompletion.forward")
        return self.complete(initial_pose, trajectories)

    def draw(self, task: CompletionTask) -> Tensor:
        """``(B, K, F, J * 3)``: the one deterministic completion repeated ``K`` times (temperature, generator
        unused)."""
        completion = self.complete(task.initial_pose, task.trajectories)
        return completion[:, None].expand(-1, task.n_samples, -1, -1)


class CVAERNN(_RecurrentCompletion):
    """The CVAE-RNN baseline (DLow style): one latent vector ``(B, L)`` per sequence, prior ``N(0, I)``."""

    def __init__(self, cfg: RecurrentConfig) -> None:
        super().__init__(cfg, stochastic=True)

    def build_extra(self) -> None:
        self.posterior_rnn = nn.GRU(self.cfg.n_channels, self.cfg.hidden, batch_first=True)
        self.posterior_head = nn.Linear(2 * self.cfg.hidden, 2 * self.cfg.latent_dim)

    def posterior(self, future: Tensor, context: Tensor) -> Gaussian:
        """``q(z | X, context)``: mean and log-variance ``(B, L)`` each from the true frames ``(B, F, J *
        3)``."""
        _, last = self.posterior_rnn(future)
        mu, logvar = self.posterior_head(torch.cat([last[-1], context], dim=-1)).chunk(2, dim=-1)
        return Gaussian(mu, logvar)

    def forward(
        self, windows: Tensor, mask: Tensor, generator: torch.Generator | None = None
    ) -> tuple[Tensor, Gaussian]:
        """Reconstruction ``(B, F, J * 3)`` through a posterior sample, and the posterior."""
        initial_pose, future, trajectories = self._check_batch(windows, mask, "CVAERNN.forward")
        context = self.context(trajectories, initial_pose)
        posterior = self.posterior(future, context)
        z = reparameterize(posterior.mu, posterior.logvar, generator)
        return self.decoder(trajectories, initial_pose, torch.cat([context, z], dim=-1)), posterior

    def draw(self, task: CompletionTask) -> Tensor:
        """Completions ``(B, K, F, J * 3)`` with ``z ~ N(0, temperature² I)`` (``K = 1``: ``z = 0``, the prior
        mean)."""
        initial_pose, trajectories, batch, n_samples, temperature, generator = task
        context = self.context(trajectories, initial_pose).repeat_interleave(n_samples, dim=0)
        shape = (batch * n_samples, self.cfg.latent_dim)
        z = torch.zeros(shape) if n_samples == 1 else temperature * torch.randn(shape, generator=generator)
        poses = self.decoder(
            trajectories.repeat_interleave(n_samples, dim=0),
            initial_pose.repeat_interleave(n_samples, dim=0),
            torch.cat([context, z], dim=-1),
        )
        return poses.unflatten(0, (batch, n_samples))
