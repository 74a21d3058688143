"""The Motion Cell network (Ghorbani et al. 2020): its config, motion words, the cell and the full model.

**Motion words.** A sequence of poses is cut into words of ``l`` consecutive poses. The Motion Cell runs
its recurrence once per word instead of once per frame (the paper: ``l = 3``), which shortens the
recurrence threefold and lets one latent variable describe a short movement. ``f_enc^w`` maps the ``l``
pose vectors of a word to a code; ``f_dec^w`` maps a code back to ``l`` raw poses (the output head of
:mod:`.heads` turns them into rotations). The SL ablation (the paper's §5.1) removes both: ``l = 1`` and
``word_layers=False``, so the cell reads and writes single pose vectors.

**The cell** is one step of a conditional variational RNN over motion words (the paper's Algorithms 1,
2). At word ``t`` with recurrent state ``h_{t-1} = [h^1_{t-1}, h^2_{t-1}]`` (both of the two stacked GRU
cells, concatenated, as in §3.3.1) and control ``c``:

* prior      ``p(z_t | h_{t-1}, c) = N(mu_p, sigma_p^2)``, an MLP of ``[h_{t-1}, f_c(c)]`` (eq. 8);
* posterior  ``q(z_t | w_t, h_{t-1}, c) = N(mu_q, sigma_q^2)``, an MLP of ``[f_w(w_t), h_{t-1}, f_c(c)]``
  (eq. 5);
* decoder    the code of word ``t`` from ``[f_z(z_t), h_{t-1}, f_c(c)]`` (eq. 10; then ``f_dec^w`` gives its
  poses);
* transition ``h_t = GRU_2(GRU_1([f_w(w_t), f_z(z_t), f_c(c)], h^1_{t-1}), h^2_{t-1})``: eq. 11 with the
  control added (ours; the paper's ``f_h(f_w(w_t), f_z(z_t), h_{t-1})`` in eq. 11, 13 and Algorithms 1-2
  reads no control).

``f_w``, ``f_z`` are feature MLPs of a word code and a latent, ``f_c`` embeds the one-hot action and body
type. The initial state of both GRU cells is drawn from a learned Gaussian, one per attribute combination.

**The model.** Training (:meth:`MotionCellModel.forward`) reconstructs windows of pose vectors through the
posterior, teacher-forced, with *scheduled motion-word dropping* (§4.2, strategy ii): with probability
``word_drop`` the ground-truth word is dropped from the transition's input and the model's own output for
that step, ``w~_t`` (decoded from the posterior latent), takes its place, as it does at generation time.
A fed-back word is decoded into its poses and encoded again, ``f_w(f_enc^w(f_dec^w(w~_t)))``, the path a
real word takes (ours; eq. 13 feeds ``f_w(w~_t)``). The posterior always sees the real word. Generation
(:meth:`MotionCellModel.generate`) draws the initial state and then, word after word, a latent from the
prior, decodes it, and feeds the generated word back (the same way); it runs for any number of frames, and
smooths the boundaries between words (:mod:`.smoothing`, ours).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from motionlab.models.gaussian import gaussian_kl, reparameterize
from motionlab.models.motion_cell.data import PoseCodec, pose_dim
from motionlab.models.motion_cell.heads import (
    OUTPUT_KINDS,
    PoseNetwork,
    assemble_pose,
    split_raw_pose,
)
from motionlab.models.motion_cell.smoothing import smooth_word_boundaries
from motionlab.validation import Checked, check_scalar, check_tensor, choice, flag, integer


@dataclass(frozen=True)
class MotionCellConfig(Checked):
    """The hierarchical Motion Cell (and its SL ablation with ``word_length=1``).

    Attributes:
        n_joints: skeleton joints ``J``; a pose vector has ``(J - 1) * 4 + 6`` channels.
        word_length: poses per motion word ``l`` (the paper: 3; the SL ablation: 1).
        word_layers: whether the word encoder ``f_enc^w`` and decoder ``f_dec^w`` exist; without them (the SL
            ablation) ``f_w`` reads the ``l`` pose vectors and the cell's decoder outputs the raw poses.
        word_dim: size of a motion word's code (output of ``f_enc^w``, input of ``f_dec^w``).
        feature_dim: output size of the feature MLPs ``f_w`` and ``f_z``.
        latent_dim: size of the per-word latent ``z_t``.
        hidden_dim: width of each of the two stacked GRU cells (the state ``h`` the prior, posterior and
            decoder read is both, ``2 * hidden_dim``) and of those MLPs' hidden layers.
        control_dim: size of the control embedding ``f_c(c)`` of action and body type.
        n_actions, n_bodies: number of action classes and body types (the control attributes).
        output: rotation output of the decoder, one of :data:`~.heads.OUTPUT_KINDS`.
    """

    n_joints: int = integer(22, minimum=2)
    word_length: int = integer(3, minimum=1)
    word_dim: int = integer(64, minimum=1)
    feature_dim: int = integer(64, minimum=1)
    latent_dim: int = integer(24, minimum=1)
    hidden_dim: int = integer(128, minimum=1)
    control_dim: int = integer(32, minimum=1)
    n_actions: int = integer(6, minimum=1)
    n_bodies: int = integer(2, minimum=1)
    output: str = choice(OUTPUT_KINDS, "quaternion")
    word_layers: bool = flag(True)

    @property
    def pose_dim(self) -> int:
        """Channels of one pose vector (:func:`~.data.pose_dim`)."""
        return pose_dim(self.n_joints)


def to_words(poses: Tensor, length: int) -> Tensor:
    """Words ``(B, T / l, l * D)`` from poses ``(B, T, D)``; ``T`` must be a multiple of ``l``."""
    check_tensor(poses, "poses", "to_words", ndim=3, finite=False)
    check_scalar(length, "length", "to_words", kind=numbers.Integral, minimum=1)
    if poses.shape[1] % length:
        raise ValueError(f"to_words: {poses.shape[1]} frames do not split into words of {length}")
    return poses.reshape(poses.shape[0], poses.shape[1] // length, length * poses.shape[2])


def from_words(words: Tensor, length: int) -> Tensor:
    """Poses ``(B, N * l, D)`` from words ``(B, N, l * D)`` (the inverse of :func:`to_words`)."""
    check_tensor(words, "words", "from_words", ndim=3, finite=False)
    check_scalar(length, "length", "from_words", kind=numbers.Integral, minimum=1)
    if words.shape[-1] % length:
        raise ValueError(
            f"from_words: words must be (B, N, l * D) with l = {length}, got {tuple(words.shape)}"
        )
    return words.reshape(words.shape[0], words.shape[1] * length, words.shape[2] // length)


def mlp(sizes: list[int]) -> nn.Sequential:
    """Linear layers of ``sizes`` with ELU between them (none after the last)."""
    layers: list[nn.Module] = []
    for fan_in, fan_out in zip(sizes[:-1], sizes[1:]):
        layers += [nn.Linear(fan_in, fan_out), nn.ELU()]
    return nn.Sequential(*layers[:-1])


class WordEncoder(nn.Module):
    """``f_enc^w``: a word of ``l`` pose vectors ``(..., l * pose_dim)`` -> its code ``(..., word_dim)``."""

    def __init__(self, pose_dim: int, word_length: int, word_dim: int) -> None:
        super().__init__()
        self.net = mlp([pose_dim * word_length, 2 * word_dim, word_dim])

    def forward(self, words: Tensor) -> Tensor:
        return self.net(words)


class WordDecoder(nn.Module):
    """``f_dec^w``: a code ``(..., word_dim)`` -> ``l`` raw poses ``(..., l * raw_dim)``."""

    def __init__(self, word_dim: int, word_length: int, raw_dim: int) -> None:
        super().__init__()
        self.net = mlp([word_dim, 2 * word_dim, raw_dim * word_length])
        nn.init.zeros_(self.net[-1].weight)  # start at the rest pose (zero raw = identity rotations)
        nn.init.zeros_(self.net[-1].bias)

    def forward(self, codes: Tensor) -> Tensor:
        return self.net(codes)


#: Log-variances are squashed smoothly into ``(-LOGVAR_BOUND, LOGVAR_BOUND)`` so a bad step cannot overflow
#: ``exp``.
LOGVAR_BOUND = 8.0


def bounded_logvar(raw: Tensor) -> Tensor:
    """``LOGVAR_BOUND * tanh(raw / LOGVAR_BOUND)``: the identity near zero, bounded far from it."""
    return LOGVAR_BOUND * torch.tanh(raw / LOGVAR_BOUND)


def check_attributes(
    action: Tensor, body: Tensor, n_actions: int, n_bodies: int, where: str
) -> tuple[Tensor, Tensor]:
    """``action`` and ``body`` as int64 ``(B,)`` tensors, checked against the number of classes.

    Raises ``TypeError`` for floating-point attributes, ``ValueError`` for a wrong shape or a class index
    out of range (naming ``where``).
    """
    for name, value in (("action", action), ("body", body)):
        if torch.is_tensor(value) and value.is_floating_point():
            raise TypeError(f"{where}: {name} must hold integer class indices, got dtype {value.dtype}")
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


def cell_step(
    word: Tensor,
    state: Tensor,
    eps: Tensor,
    prior: Callable[[Tensor], tuple[Tensor, Tensor]],
    posterior: Callable[[Tensor, Tensor], tuple[Tensor, Tensor]],
    decode: Callable[[Tensor, Tensor], Tensor],
    transition: Callable[[Tensor, Tensor, Tensor], Tensor],
) -> tuple[Tensor, Tensor, Tensor]:
    """One teacher-forced step of a VRNN over motion words (one word of Algorithm 1), written plainly.

    :meth:`MotionCellModel.forward` is this step for every word of a window, with the pieces of
    :class:`MotionCell`, its control, word dropping and the batching that takes work out of the loop.

    Args:
        word: the real word ``w_t`` (or its features) ``(B, D_w)``; state: ``h_{t-1}`` ``(B, D_h)``; eps:
            noise ``N(0, I)`` ``(B, D_z)`` for the draw from the posterior.
        prior: ``h -> (mu_p, logvar_p)``, each ``(B, D_z)``; posterior: ``(w, h) -> (mu_q, logvar_q)``;
        decode: ``(z, h) -> w~`` the reconstructed word; transition: ``(w, z, h) -> h_t`` ``(B, D_h)``.

    Returns:
        ``(w~_t, kl, h_t)``: the word decoded from ``z_t ~ q(z_t | w_t, h_{t-1})``, the KL from that
        posterior to the prior ``p(z_t | h_{t-1})`` summed over the latent's dimensions ``(B,)``, and the
        next state, which reads the real word (teacher forcing).
    """
    mu_p, logvar_p = prior(state)
    mu_q, logvar_q = posterior(word, state)
    if eps.shape != mu_q.shape:
        raise ValueError(
            f"cell_step: eps must have the posterior's shape {tuple(mu_q.shape)}, got {tuple(eps.shape)}"
        )
    z = mu_q + torch.exp(0.5 * logvar_q) * eps
    kl = gaussian_kl(mu_q, logvar_q, mu_p, logvar_p).sum(-1)
    return decode(z, state), kl, transition(word, z, state)


class MotionCell(nn.Module):
    """The recurrent core of the Motion Cell model (see the module notes for the equations).

    The training pass is split so that everything that does not feed the recurrence runs batched over
    all words after the loop: :meth:`posterior_input` before it, :meth:`prior` and :meth:`decode` after it.
    """

    def __init__(
        self, cfg: MotionCellConfig, word_in: int | None = None, word_out: int | None = None
    ) -> None:
        """``word_in``, ``word_out``: sizes of the words ``f_w`` reads and the decoder writes (default: the
        code size ``cfg.word_dim``; without word layers, the pose vectors and the raw poses of a word)."""
        super().__init__()
        self.cfg = cfg
        h, f, z, c = cfg.hidden_dim, cfg.feature_dim, cfg.latent_dim, cfg.control_dim
        word_in = cfg.word_dim if word_in is None else word_in
        word_out = cfg.word_dim if word_out is None else word_out
        self.control = ControlEmbedding(cfg.n_actions, cfg.n_bodies, c)  # f_c
        self.word_feature = mlp([word_in, f, f])  # f_w
        self.latent_feature = mlp([z, f, f])  # f_z
        self.prior_net = mlp([2 * h + c, h, 2 * z])
        self.posterior_in = nn.Linear(f + c, h)  # the posterior's first layer, split: [f_w, f_c] part ...
        self.posterior_state = nn.Linear(2 * h, h, bias=False)  # ... and h_{t-1} part
        self.posterior_out = nn.Linear(h, 2 * z)
        self.decoder_net = mlp([f + 2 * h + c, h, word_out])
        self.gru = nn.ModuleList([nn.GRUCell(2 * f + c, h), nn.GRUCell(h, h)])
        self.initial = InitialState(cfg.n_actions, cfg.n_bodies, 2 * h)

    def initial_state(
        self, action: Tensor, body: Tensor, generator: torch.Generator | None = None
    ) -> tuple[Tensor, Tensor]:
        """Sampled states ``(h^1_0, h^2_0)``, each ``(B, hidden_dim)``."""
        return tuple(self.initial(action, body, generator).chunk(2, dim=-1))  # type: ignore[return-value]

    @staticmethod
    def state(layers: tuple[Tensor, Tensor]) -> Tensor:
        """The Motion Cell state ``h = [h^1, h^2]`` ``(B, 2 * hidden_dim)`` of both GRU cells (§3.3.1)."""
        return torch.cat(layers, dim=-1)

    def prior(self, state: Tensor, control: Tensor) -> tuple[Tensor, Tensor]:
        """Prior mean and log-variance ``(..., latent_dim)`` from states and controls ``(..., 2 h)``, ``(...,
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
        """The two stacked GRU cells: ``(h^1_{t-1}, h^2_{t-1}) -> (h^1_t, h^2_t)``, each ``(B, hidden_dim)``.

        The lower cell reads ``[f_w(w_t), f_z(z_t), f_c(c)]`` ``(B, 2 * feature_dim + control_dim)``; eq. 11
        has no control in ``f_h`` (the control input is ours).
        """
        lower = self.gru[0](torch.cat([word_features, latent_features, control], dim=-1), layers[0])
        return lower, self.gru[1](lower, layers[1])


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


class MotionCellModel(PoseNetwork[MotionCellConfig]):
    """Words -> Motion Cell -> words; ``codec`` carries the root statistics and the skeletons."""

    def __init__(self, cfg: MotionCellConfig, codec: PoseCodec) -> None:
        super().__init__(cfg, codec, cfg.output)
        raw_dim = self.head.raw_dim(cfg.n_joints)
        if cfg.word_layers:
            self.word_encoder: nn.Module = WordEncoder(cfg.pose_dim, cfg.word_length, cfg.word_dim)
            self.word_decoder: nn.Module = WordDecoder(cfg.word_dim, cfg.word_length, raw_dim)
            self.cell = MotionCell(cfg)
        else:  # SL: the cell reads pose vectors and writes raw poses itself
            self.word_encoder = self.word_decoder = nn.Identity()
            self.cell = MotionCell(cfg, cfg.pose_dim * cfg.word_length, raw_dim * cfg.word_length)
            nn.init.zeros_(self.cell.decoder_net[-1].weight)  # start at the rest pose, as WordDecoder does
            nn.init.zeros_(self.cell.decoder_net[-1].bias)

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
        check_tensor(poses, "poses", "MotionCellModel", ndim=3, trailing=(self.cfg.pose_dim,))
        if poses.shape[1] % self.cfg.word_length:
            raise ValueError(
                f"MotionCellModel: {poses.shape[1]} frames are not a whole number of words of "
                f"{self.cfg.word_length} frames"
            )

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
            word_drop: probability in ``[0, 1]`` of dropping each ground-truth word from the transition's
                input; the model's own output for that word (decoded from its posterior latent, without
                gradient) is fed instead, as at generation time (scheduled sampling).
            generator: draws the initial state, the dropped words and the latents (default: global RNG).
        """
        self._check_poses(poses)
        check_scalar(word_drop, "word_drop", "MotionCellModel", minimum=0.0, maximum=1.0)
        cell = self.cell
        word_features = self.encode_words(poses)
        batch, n_words = word_features.shape[:2]
        control = cell.control(action, body)
        controls = control[:, None].expand(batch, n_words, control.shape[-1])
        posterior_pre = cell.posterior_input(word_features, controls)
        keep = torch.rand(batch, n_words, 1, generator=generator) >= word_drop
        layers = cell.initial_state(action, body, generator)
        states, latent_features, mus, logvars = [], [], [], []
        for t in range(n_words):
            state = cell.state(layers)
            states.append(state)
            mu, logvar = cell.posterior(posterior_pre[:, t], state)
            features = cell.latent_feature(reparameterize(mu, logvar, generator))
            word_input = word_features[:, t]
            if not bool(keep[:, t].all()):
                with torch.no_grad():  # w~_t re-encoded, f_w(f_enc^w(f_dec^w(w~_t))) (eq. 13: f_w(w~_t))
                    own, _ = self.decode_words(cell.decode(features, state, control)[:, None])
                    own_features = self.encode_words(own)[:, 0]
                word_input = torch.where(keep[:, t], word_input, own_features)
            layers = cell.transition(layers, word_input, features, control)
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
        self,
        action: Tensor,
        body: Tensor,
        n_frames: int,
        generator: torch.Generator | None = None,
        temperature: float = 1.0,
        smooth: bool = True,
    ) -> Tensor:
        """Sample pose vectors ``(B, n_frames, 90)`` for attributes ``(B,)``, any ``n_frames >= 1``.

        The same ``generator`` state gives bitwise-identical samples. ``temperature`` scales the prior's
        standard deviation (1: the model's prior, 0: every word's prior mean). ``smooth`` passes the clips
        through :func:`~.smoothing.smooth_word_boundaries` (ours; ``False``: the words as decoded, as in the
        paper).
        """
        poses = self.rollout(action, body, n_frames, generator, temperature=temperature)
        return smooth_word_boundaries(poses, self.cfg.word_length) if smooth else poses

    def rollout(
        self,
        action: Tensor,
        body: Tensor,
        n_frames: int,
        generator: torch.Generator | None = None,
        truncate: bool = False,
        temperature: float = 1.0,
    ) -> Tensor:
        """:meth:`generate` with gradients (for losses on samples).

        With ``truncate`` the recurrent state is detached after every word, so gradients reach each word's
        prior, decoder and word features but not the earlier words through the state (truncated
        back-propagation through time). ``temperature`` scales the prior's standard deviation.
        """
        check_scalar(n_frames, "n_frames", "MotionCellModel.generate", kind=numbers.Integral, minimum=1)
        check_scalar(temperature, "temperature", "MotionCellModel.generate", minimum=0.0)
        cell = self.cell
        control = cell.control(action, body)
        layers = cell.initial_state(action, body, generator)
        words = []
        for _ in range(math.ceil(n_frames / self.cfg.word_length)):
            state = cell.state(layers)
            mu, logvar = cell.prior(state, control)
            z = reparameterize(mu, logvar, generator)
            features = cell.latent_feature(z if temperature == 1.0 else mu + temperature * (z - mu))
            word, _ = self.decode_words(cell.decode(features, state, control)[:, None])
            words.append(word)
            layers = cell.transition(layers, self.encode_words(word)[:, 0], features, control)
            if truncate:
                layers = (layers[0].detach(), layers[1].detach())
        return torch.cat(words, dim=1)[:, :n_frames]
