r"""MDM (Tevet et al., "Human Motion Diffusion Model", ICLR 2023): the denoiser and its config.

Shapes: ``B`` clips, ``T`` frames, ``F`` channels per frame (the family's representation, :mod:`.data`),
``d`` the transformer width.

**What the network predicts.** MDM's denoiser :math:`G(x_t, t, c)` predicts the clean motion
:math:`\hat x_0` itself, not the noise (§3, after Ramesh et al. 2022): the geometric losses of
:mod:`.losses` are then computed on a motion, and the sampler (:mod:`.sampling`) puts :math:`\hat x_0` into
the posterior of :mod:`.schedule`.

**The network** (§3 and Fig. 2; repository ``model/mdm.py``, ``arch='trans_enc'``):

1. every frame of the noised motion ``x_t (B, T, F)`` is projected to ``d`` by one linear layer
   (``InputProcess``);
2. the time step ``t`` is embedded by a sinusoidal code followed by ``Linear → SiLU → Linear``
   (``TimestepEmbedder``); the action ``c`` by a learned table of ``d``-vectors (``EmbedAction``); their sum
   is one extra token ``z_tk``, put in front of the frames;
3. a sinusoidal position code is added to all ``T + 1`` tokens, and a transformer encoder (self-attention
   over all of them: every frame sees the condition token and every other frame) mixes them;
4. the condition token is dropped and every frame is projected back to ``F`` channels by one linear layer
   (``OutputProcess``): ``x̂_0 (B, T, F)``.

**The null condition** (classifier-free guidance, Ho & Salimans 2022; MDM §3): in training the action
embedding is replaced by zeros with probability ``cond_mask_prob`` (0.1), independently per clip, so the
same network also learns the unconditioned model :math:`G(x_t, t, \varnothing)`. In the repository the null
condition is exactly this zero vector (``mask_cond``); the time-step embedding is kept.

**Paper and repository.** The paper says ``t`` and ``c`` are projected "by separate feed-forward networks";
in the repository the action's is a learned table (a ``(C, d)`` parameter drawn from ``N(0, 1)``), which we
follow (an ``nn.Embedding``, same initialisation). The transformer layers are PyTorch's post-norm encoder
layers with GELU and dropout 0.1, as in the repository; the position code's dropout is the same 0.1.
The sizes (8 layers, width 512, 4 heads, feed-forward 1024, 1,000 diffusion steps) are the repository's
defaults (``utils/parser_util.py``: ``--layers 8 --latent_dim 512``; ``model/mdm.py``: ``ff_size=1024``,
``num_heads=4``); the paper gives no table of them.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, replace
from typing import ClassVar

import torch
from torch import Tensor, nn

from motionlab.data.datasets import Standardizer
from motionlab.models.diffusion.data import joint_positions, n_features
from motionlab.models.diffusion.schedule import NoiseSchedule, check_steps
from motionlab.models.trajevae.model import sinusoidal_encoding
from motionlab.skeleton import JOINT
from motionlab.validation import check_scalar, check_tensor

#: The joints whose velocity the foot-contact loss reads, in the repository's order (SMPL's left ankle,
#: left foot, right ankle, right foot: the course skeleton has the same indices).
FOOT_JOINTS: tuple[int, ...] = (
    JOINT["left_ankle"],
    JOINT["left_foot"],
    JOINT["right_ankle"],
    JOINT["right_foot"],
)


@dataclass(frozen=True)
class MDMConfig:
    """MDM's sizes, diffusion length and loss weights. The defaults are the paper's and the repository's
    (sources per field); :meth:`course` gives the chapter's CPU-sized model.

    Attributes:
        n_joints: skeleton joints ``J``; channels per frame ``F = 6 J + 3`` (:mod:`.data`).
        n_frames: frames per clip ``T`` (60: MDM's action-to-motion clips, and the benchmark's 4 s at 15 fps).
        n_actions: action classes ``C`` (6 on the benchmark).
        latent_dim: transformer width ``d`` (repository ``--latent_dim`` 512).
        ff_size: width of each layer's feed-forward block (repository ``ff_size`` 1024).
        layers: transformer encoder layers (repository ``--layers`` 8).
        heads: attention heads (repository ``num_heads`` 4).
        dropout: dropout in the transformer and after the position code (repository 0.1).
        cond_mask_prob: probability that a training clip's action is replaced by the null condition
            (repository ``--cond_mask_prob`` 0.1; paper §3: the null condition for 10 % of the samples).
        diffusion_steps: steps ``S`` of the cosine schedule (repository ``--diffusion_steps`` 1,000 with
            ``--noise_schedule cosine``).
        lambda_pos: weight of the joint-position loss; lambda_vel: of the velocity loss; lambda_foot: of
            the foot-contact loss (:mod:`.losses`). All 1: the repository's action-to-motion
            training command (README: ``--lambda_rcxyz 1 --lambda_vel 1 --lambda_fc 1``; its parser's
            defaults are 0, the text-to-motion setting).
        contact_threshold: a foot joint is in contact in a frame when its real speed to the next frame is at
            most this many metres per frame (repository: 0.01, at its 20 fps; see :mod:`.losses`).
    """

    n_joints: int = 22
    n_frames: int = 60
    n_actions: int = 6
    latent_dim: int = 512
    ff_size: int = 1024
    layers: int = 8
    heads: int = 4
    dropout: float = 0.1
    cond_mask_prob: float = 0.1
    diffusion_steps: int = 1000
    lambda_pos: float = 1.0
    lambda_vel: float = 1.0
    lambda_foot: float = 1.0
    contact_threshold: float = 0.01

    def __post_init__(self) -> None:
        where = "MDMConfig"
        for name in ("n_joints", "n_frames", "n_actions", "latent_dim", "ff_size", "layers", "heads"):
            check_scalar(getattr(self, name), name, where, kind=numbers.Integral, minimum=1)
        check_scalar(self.diffusion_steps, "diffusion_steps", where, kind=numbers.Integral, minimum=2)
        if self.latent_dim % self.heads or self.latent_dim % 2:
            raise ValueError(
                f"{where}: latent_dim must be even and divisible by heads={self.heads}, got {self.latent_dim}"
            )
        check_scalar(self.dropout, "dropout", where, minimum=0, maximum=1, include_maximum=False)
        check_scalar(self.cond_mask_prob, "cond_mask_prob", where, minimum=0, maximum=1)
        for name in ("lambda_pos", "lambda_vel", "lambda_foot"):
            check_scalar(getattr(self, name), name, where, minimum=0)
        check_scalar(self.contact_threshold, "contact_threshold", where, minimum=0, include_minimum=False)

    @classmethod
    def course(cls, **overrides: object) -> MDMConfig:
        """The chapter's CPU size: width 128, feed-forward 256, 4 layers, 4 heads (everything else the
        paper's, 1,000 diffusion steps included); ``overrides`` replace any field."""
        return replace(cls(latent_dim=128, ff_size=256, layers=4, heads=4), **overrides)

    #: What a frame's channels hold: per-joint 6-D rotations and the root position (:mod:`.data`).
    representation: ClassVar[str] = "rot6d"

    @property
    def n_features(self) -> int:
        """Channels per frame ``F = 6 J + 3``."""
        return n_features(self.n_joints)

    @property
    def feet(self) -> tuple[int, ...]:
        """The joints the foot-contact loss reads (:data:`FOOT_JOINTS` of the course skeleton)."""
        return FOOT_JOINTS


@dataclass(frozen=True)
class PositionMDMConfig(MDMConfig):
    """MDM on joint positions: every frame is the xyz of the ``J`` joints in metres, ``F = 3 J`` channels (the
    repository's ``data_rep='xyz'``), for motion recorded without rotations (chapter 10's CMU clips). The
    joint-position loss then compares the channels themselves in metres (forward kinematics is the identity);
    the velocity and foot-contact losses are as for rotations.

    Attributes:
        foot_joints: the joints the foot-contact loss reads (the skeleton's ankles and toes).
    """

    foot_joints: tuple[int, ...] = FOOT_JOINTS

    representation: ClassVar[str] = "xyz"

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.foot_joints or any(
            not isinstance(j, numbers.Integral) or not 0 <= j < self.n_joints for j in self.foot_joints
        ):
            raise ValueError(
                f"PositionMDMConfig: foot_joints must be joints in [0, {self.n_joints}), "
                f"got {self.foot_joints}"
            )

    @property
    def n_features(self) -> int:
        """Channels per frame ``F = 3 J``."""
        return 3 * self.n_joints

    @property
    def feet(self) -> tuple[int, ...]:
        """The joints the foot-contact loss reads (:attr:`foot_joints`)."""
        return self.foot_joints


class TimestepEmbedder(nn.Module):
    """Time steps ``(B,)`` int64 in ``[0, S)`` -> ``(B, d)``: a sinusoidal code of the step, then ``Linear →
    SiLU → Linear``."""

    def __init__(self, n_steps: int, dim: int) -> None:
        super().__init__()
        self.register_buffer("codes", sinusoidal_encoding(n_steps, dim), persistent=False)
        self.mlp = nn.Sequential(nn.Linear(dim, dim), nn.SiLU(), nn.Linear(dim, dim))

    def forward(self, t: Tensor) -> Tensor:
        return self.mlp(self.codes[t])


class MDM(nn.Module):
    r"""MDM's denoiser :math:`\hat x_0 = G(x_t, t, c)` on standardised motions, from an :class:`MDMConfig`.

    ``standardizer`` (fitted on the training clips with :meth:`fit_standardizer`, saved with the weights)
    maps the features of :mod:`.data` to standardised channels and back; ``schedule`` is the cosine schedule
    of ``cfg.diffusion_steps`` steps (not a parameter: rebuilt from the config).
    """

    def __init__(self, cfg: MDMConfig) -> None:
        super().__init__()
        if not isinstance(cfg, MDMConfig):
            raise TypeError(f"MDM: cfg must be an MDMConfig, got {type(cfg).__name__}")
        self.cfg = cfg
        self.schedule = NoiseSchedule.cosine(cfg.diffusion_steps)
        self.standardizer = Standardizer(cfg.n_features)
        d = cfg.latent_dim
        self.input_process = nn.Linear(cfg.n_features, d)
        self.embed_timestep = TimestepEmbedder(cfg.diffusion_steps, d)
        self.embed_action = nn.Embedding(cfg.n_actions, d)
        self.register_buffer("positions", sinusoidal_encoding(cfg.n_frames + 1, d), persistent=False)
        self.position_dropout = nn.Dropout(cfg.dropout)
        layer = nn.TransformerEncoderLayer(
            d,
            cfg.heads,
            dim_feedforward=cfg.ff_size,
            dropout=cfg.dropout,
            activation="gelu",
            batch_first=True,
        )
        self.encoder = nn.TransformerEncoder(layer, cfg.layers, enable_nested_tensor=False)
        self.output_process = nn.Linear(d, cfg.n_features)

    def joint_positions(self, features: Tensor) -> Tensor:
        """Joint positions ``(..., T, J, 3)`` in metres of features ``(..., T, F)`` in the units of
        :mod:`.data`: forward kinematics of the rotations on the average skeleton
        (:func:`~motionlab.models.diffusion.data.joint_positions`), or the channels themselves for a
        :class:`PositionMDMConfig`."""
        if self.cfg.representation == "xyz":
            check_tensor(features, "features", "MDM.joint_positions", trailing=(self.cfg.n_features,))
            return features.unflatten(-1, (self.cfg.n_joints, 3))
        return joint_positions(features)

    def fit_standardizer(self, features: Tensor) -> MDM:
        """Fit the standardiser on training clips ``(N, T, F)`` (metres and 6-D rotations); returns self."""
        check_tensor(features, "features", "MDM.fit_standardizer", trailing=(self.cfg.n_features,), ndim=3)
        self.standardizer.fit(features)
        return self

    def condition(self, action: Tensor | None, null: Tensor | None, batch: int) -> Tensor:
        """The condition embeddings ``(B, d)``: the action's, zeros where the condition is null.

        ``action`` ``(B,)`` int64 in ``[0, C)``, or ``None`` for the null condition everywhere; ``null``
        ``(B,)`` bool marks clips whose condition is null. In training mode each clip's action is also
        dropped with probability ``cond_mask_prob`` (global RNG).
        """
        where = "MDM"
        d = self.cfg.latent_dim
        if action is None:
            return self.positions.new_zeros(batch, d)
        if not isinstance(action, Tensor) or action.is_floating_point() or action.dtype == torch.bool:
            raise TypeError(
                f"{where}: action must be an integer tensor, got {getattr(action, 'dtype', type(action))}"
            )
        if action.shape != (batch,):
            raise ValueError(f"{where}: action must be ({batch},), got {tuple(action.shape)}")
        if action.numel() and (int(action.min()) < 0 or int(action.max()) >= self.cfg.n_actions):
            raise ValueError(
                f"{where}: actions must lie in [0, {self.cfg.n_actions}), "
                f"got [{int(action.min())}, {int(action.max())}]"
            )
        drop = torch.zeros(batch, dtype=torch.bool)
        if null is not None:
            if not isinstance(null, Tensor) or null.dtype != torch.bool:
                raise TypeError(f"{where}: null must be a bool tensor, got {getattr(null, 'dtype', null)!r}")
            if null.shape != (batch,):
                raise ValueError(f"{where}: null must be ({batch},), got {tuple(null.shape)}")
            drop = null
        if self.training and self.cfg.cond_mask_prob > 0:
            drop = drop | (torch.rand(batch) < self.cfg.cond_mask_prob)
        return self.embed_action(action) * (~drop).to(self.positions.dtype)[:, None]

    def forward(self, x_t: Tensor, t: Tensor, action: Tensor | None, null: Tensor | None = None) -> Tensor:
        """The predicted clean motion ``x̂_0 (B, T, F)`` (standardised) of noised motions ``x_t (B, T, F)`` at
        diffusion steps ``t`` ``(B,)`` (int64, steps of the full ``S``-step process) for actions ``(B,)`` or
        ``None`` (the null condition); ``null`` ``(B,)`` bool forces the null condition per clip."""
        cfg, where = self.cfg, "MDM"
        check_tensor(x_t, "x_t", where, trailing=(None, cfg.n_features), ndim=3)
        batch, frames = x_t.shape[:2]
        if frames > cfg.n_frames:
            raise ValueError(f"{where}: x_t has {frames} frames, the model at most n_frames={cfg.n_frames}")
        check_steps(t, batch, cfg.diffusion_steps, where)
        token = self.embed_timestep(t) + self.condition(action, null, batch)
        sequence = torch.cat([token[:, None, :], self.input_process(x_t)], dim=1)
        sequence = self.position_dropout(sequence + self.positions[: frames + 1])
        return self.output_process(self.encoder(sequence)[:, 1:])
