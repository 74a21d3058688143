"""The Motion Cell: one step of a conditional variational RNN over motion words (the paper's Algorithms 1, 2).

At word ``t`` with recurrent state ``h_{t-1}`` (the top of two stacked GRU cells) and control ``c``:

* prior      ``p(z_t | h_{t-1}, c) = N(mu_p, sigma_p^2)``, an MLP of ``[h_{t-1}, f_c(c)]``;
* posterior  ``q(z_t | w_t, h_{t-1}, c) = N(mu_q, sigma_q^2)``, an MLP of ``[f_w(w_t), h_{t-1}, f_c(c)]``;
* decoder    the code of word ``t`` from ``[f_z(z_t), h_{t-1}, f_c(c)]`` (then ``f_dec^w`` gives its poses);
* transition ``h_t = GRU_2(GRU_1([f_w(w_t), f_z(z_t), f_c(c)], h^1_{t-1}), h^2_{t-1})``.

``f_w``, ``f_z`` are feature MLPs of a word code and a latent, ``f_c`` embeds the one-hot action and body
type. The initial state of both GRU cells is drawn from a learned Gaussian, one per attribute combination.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from motionlab.models.gaussian import reparameterize
from motionlab.models.motion_cell.config import MotionCellConfig
from motionlab.models.motion_cell.words import mlp

#: Log-variances are squashed smoothly into ``(-LOGVAR_BOUND, LOGVAR_BOUND)`` so a bad step cannot overflow
#: ``exp``.
LOGVAR_BOUND = 8.0


def bounded_logvar(raw: Tensor) -> Tensor:
    """``LOGVAR_BOUND * tanh(raw / LOGVAR_BOUND)``: the identity near zero, bounded far from it."""
    return LOGVAR_BOUND * torch.tanh(raw / LOGVAR_BOUND)


def check_attributes(
    action: Tensor, body: Tensor, n_actions: int, n_bodies: int, where: str
) -> tuple[Tensor, Tensor]:
    """``action`` and ``body`` as int64 ``(B,)`` tensors, checked against the number of classes."""
    action = torch.as_tensor(action, dtype=torch.int64)
    body = torch.as_tensor(body, dtype=torch.int64)
    if action.dim() != 1 or action.shape != body.shape:
        raise ValueError(
            f"{where}: action and body must be (B,) each, got {tuple(action.shape)} and {tuple(body.shape)}"
        )
    for name, value, count in (("action", action, n_actions), ("body", body, n_bodies)):
        if value.numel() and (int(value.min()) < 0 or int(value.max()) >= count):
            raise ValueError(
                f"{where}: {name} values must lie in [0, {count}), got {sorted(set(value.tolist()))}"
            )
    return action, body


class ControlEmbedding(nn.Module):
    """``f_c``: one-hot action and body type ``(B,)`` each -> an embedding ``(B, control_dim)``."""

    def __init__(self, n_actions: int, n_bodies: int, control_dim: int) -> None:
        super().__init__()
        self.n_actions, self.n_bodies = n_actions, n_bodies
        self.net = nn.Sequential(nn.Linear(n_actions + n_bodies, control_dim), nn.ELU())

    def forward(self, action: Tensor, body: Tensor) -> Tensor:
        action, body = check_attributes(action, body, self.n_actions, self.n_bodies, "ControlEmbedding")
        onehot = torch.cat([F.one_hot(action, self.n_actions), F.one_hot(body, self.n_bodies)], dim=-1)
        return self.net(onehot.float())


class InitialState(nn.Module):
    """A learned Gaussian ``N(mu_c, sigma_c^2)`` over the initial recurrent state, one per (action, body).

    ``forward(action, body, generator)`` draws ``(B, size)`` states by reparameterisation, so the mean and
    the log-variance are trained with the rest of the model.
    """

    def __init__(self, n_actions: int, n_bodies: int, size: int, initial_logvar: float = -2.0) -> None:
        super().__init__()
        self.n_actions, self.n_bodies = n_actions, n_bodies
        self.mean = nn.Parameter(torch.zeros(n_actions * n_bodies, size))
        self.logvar = nn.Parameter(torch.full((n_actions * n_bodies, size), float(initial_logvar)))

    def forward(self, action: Tensor, body: Tensor, generator: torch.Generator | None = None) -> Tensor:
        action, body = check_attributes(action, body, self.n_actions, self.n_bodies, "InitialState")
        combo = action * self.n_bodies + body
        return reparameterize(self.mean[combo], bounded_logvar(self.logvar[combo]), generator)


class MotionCell(nn.Module):
    """The recurrent core of the Motion Cell model (see the module notes for the equations).

    The training pass is split so that everything that does not feed the recurrence runs batched over
    all words after the loop: :meth:`posterior_input` before it, :meth:`prior` and :meth:`decode` after it.
    """

    def __init__(self, cfg: MotionCellConfig) -> None:
        super().__init__()
        self.cfg = cfg
        h, f, z, c = cfg.hidden_dim, cfg.feature_dim, cfg.latent_dim, cfg.control_dim
        self.control = ControlEmbedding(cfg.n_actions, cfg.n_bodies, c)  # f_c
        self.word_feature = mlp([cfg.word_dim, f, f])  # f_w
        self.latent_feature = mlp([z, f, f])  # f_z
        self.prior_net = mlp([h + c, h, 2 * z])
        self.posterior_in = nn.Linear(f + c, h)  # the posterior's first layer, split: [f_w, f_c] part ...
        self.posterior_state = nn.Linear(h, h, bias=False)  # ... and h_{t-1} part
        self.posterior_out = nn.Linear(h, 2 * z)
        self.decoder_net = mlp([f + h + c, h, cfg.word_dim])
        self.gru = nn.ModuleList([nn.GRUCell(2 * f + c, h), nn.GRUCell(h, h)])
        self.initial = InitialState(cfg.n_actions, cfg.n_bodies, 2 * h)

    def initial_state(
        self, action: Tensor, body: Tensor, generator: torch.Generator | None = None
    ) -> tuple[Tensor, Tensor]:
        """Sampled states ``(h^1_0, h^2_0)``, each ``(B, hidden_dim)``."""
        return tuple(self.initial(action, body, generator).chunk(2, dim=-1))  # type: ignore[return-value]

    def prior(self, state: Tensor, control: Tensor) -> tuple[Tensor, Tensor]:
        """Prior mean and log-variance ``(..., latent_dim)`` from states and controls ``(..., h)``, ``(...,
        c)``."""
        mu, raw = self.prior_net(torch.cat([state, control], dim=-1)).chunk(2, dim=-1)
        return mu, bounded_logvar(raw)

    def posterior_input(self, word_features: Tensor, control: Tensor) -> Tensor:
        """The state-independent part of the posterior's first layer, for all words at once."""
        return self.posterior_in(torch.cat([word_features, control], dim=-1))

    def posterior(self, pre: Tensor, state: Tensor) -> tuple[Tensor, Tensor]:
        """Posterior mean and log-variance from :meth:`posterior_input` ``pre`` and the state ``h_{t-1}``."""
        mu, raw = self.posterior_out(F.elu(pre + self.posterior_state(state))).chunk(2, dim=-1)
        return mu, bounded_logvar(raw)

    def decode(self, latent_features: Tensor, state: Tensor, control: Tensor) -> Tensor:
        """Word codes ``(..., word_dim)`` from ``f_z(z_t)``, ``h_{t-1}`` and ``f_c(c)``."""
        return self.decoder_net(torch.cat([latent_features, state, control], dim=-1))

    def transition(
        self, layers: tuple[Tensor, Tensor], word_features: Tensor, latent_features: Tensor, control: Tensor
    ) -> tuple[Tensor, Tensor]:
        """The two stacked GRU cells: ``(h^1_{t-1}, h^2_{t-1}) -> (h^1_t, h^2_t)``."""
        lower = self.gru[0](torch.cat([word_features, latent_features, control], dim=-1), layers[0])
        return lower, self.gru[1](lower, layers[1])
