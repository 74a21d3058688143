r"""ODMO: the LMP encoder, the trajectory generator and the motion generator, and their config.

A clip ``x`` (local movement profile and root trajectory, see :mod:`.data`, standardised per channel) of
action ``c`` is encoded to ``q(z | x) = N(μ, diag σ²)``; a code ``z = μ + σ ε``, the class and the end point
``r_e`` of ``x`` give the trajectory ``r̂``, and ``r̂``, ``z`` and ``c`` give the motion ``x̂``. The joint
objective that trains the three networks together is in :mod:`.losses`.

**The condition.** Every ODMO generator is conditioned on the outer product of the class one-hot and the
code, flattened (:func:`class_code_condition`): a ``C · D`` vector that holds the code in the block of its
class and zeros elsewhere, so each class reads the code space with its own weights. (The paper says only that
the generators read the class and the code; the outer product is the reference implementation's.)

**LMP encoder.** An LSTM reads the local movement profile (joints relative to the root, no trajectory) frame
by frame; its outputs, averaged over the frames, go through two fully connected layers with BatchNorm and
PReLU to ``(μ, log σ²)``. The reference implementation reads the LSTM's last hidden state instead of the
average. On our clips the last state forgets what happened mid-clip: with it, a linear probe could not tell
a front kick's code from a side kick's (48 % on two balanced classes), and with the average it could
(100 %), with the same training. The paper's LMP is in world axes (the axes of the clip's first frame here);
with ``encoder_frame="heading"`` (ours) every frame is first turned about the vertical by its own heading,
read from the hips (:func:`heading_frame`), so a walk that curves left and one that curves right look alike
to the encoder; without it the mixtures of chapter 08 split the walks and jogs by the direction of their
turn instead of their style.

**Trajectory generator.** It feeds the condition, the end point ``r_e`` (zeros in the ``-r_e`` ablation)
and the frame's time ``t / (T - 1)`` to an LSTM at every frame, maps each output to a velocity and adds the
velocities up from the origin (:func:`accumulate`). The time input is ours: the paper mentions none, and the
reference implementation spreads the condition over the frames with a linear layer instead. :class:`ODMO`
feeds it a standardised end point and reads its velocities in units of each trajectory channel's standard
deviation.

**Motion generator.** A trajectory encoder (an LSTM over the trajectory generator's output, during
training and sampling alike) hands its last hidden and cell states to an autoregressive LSTM decoder as
its initial state, which is how the trajectory steers the motion (the paper's design). The decoder writes
the full motion frame by frame, local movement profile and root trajectory together (``3 (J - 1) + 3``
channels): at frame ``t`` its input is the previous frame, the condition and the time ``t / T`` (as in the
reference implementation; the paper mentions no time input), and with
``decoder_trajectory="every_frame"`` (ours) also the trajectory's frame ``t``: through the initial state
alone, chapter 08's decoder let its root end where the code's own clip ended, whatever end point the
trajectory generator had been given. In training the previous frame is the real one with probability
``teacher_forcing`` (drawn for each clip and frame), the decoder's own output otherwise; the chapter decays
the probability from 1 to 0.3 over training (see :mod:`.experiment`), so the decoder learns to continue its
own output, which is all it has when sampling (probability 0). Frame 0 starts from a zero frame.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Literal, NamedTuple

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from motionlab.data.datasets import Standardizer
from motionlab.data.representations import rotate_xy
from motionlab.models.gaussian import reparameterize
from motionlab.validation import (
    Checked,
    check_scalar,
    check_tensor,
    choice,
    flag,
    integer,
    real,
    tuple_of,
)

#: The prior term of the embedding loss (see :mod:`.losses`), with the code's ``q(z | x) = N(μ, diag σ²)``:
#: ``"covariance"`` eq. 1's covariance terms, ``-ln det Σ + Tr(Σ) / σ₀²`` per clip (the paper; the reference
#: implementation's KL on the noise is half of it): no term on ``μ``, which only the contrastive springs
#: shape;
#: ``"covariance_and_mean"`` those terms plus ``|μ|² / σ₀²`` (an extension: a Gaussian prior N(0, σ₀²) on
#: ``μ`` as well, which the paper's supplement §3.1 replaces by the springs);
#: ``"standard"`` KL(N(μ, σ²) || N(0, I)) (a standard VAE).
PriorTerm = Literal["covariance", "covariance_and_mean", "standard"]
PRIOR_TERMS: tuple[str, ...] = ("covariance", "covariance_and_mean", "standard")

#: The axes of the local movement profile the LMP encoder reads: ``"world"`` the paper's (joints minus the
#: root, in the axes of the clip's first frame), ``"heading"`` ours: every frame turned about the vertical by
#: its own heading (read from the hips, :func:`heading_frame`), so that a walk that turns reads like one that
#: goes straight.
EncoderFrame = Literal["world", "heading"]
ENCODER_FRAMES: tuple[str, ...] = ("world", "heading")

#: How the motion generator's decoder reads the trajectory: ``"initial_state"`` the paper's (the trajectory
#: encoder's last state starts the decoder), ``"every_frame"`` ours: that, and the trajectory's frame ``t``
#: beside the previous frame in the decoder's input at step ``t``.
DecoderTrajectory = Literal["initial_state", "every_frame"]
DECODER_TRAJECTORIES: tuple[str, ...] = ("initial_state", "every_frame")


@dataclass(frozen=True)
class ODMOConfig(Checked):
    """Sizes and objective of one ODMO model. The defaults follow the paper's design where the course does
    (the encoder reading the LMP in world axes, the decoder reading the trajectory through its initial state),
    with the reference implementation's same-class slack, prior weight and trajectory loss on positions
    (:mod:`.losses`), an encoder that averages its LSTM's outputs over time, and the sizes the full profile
    trains (generators of one 64-unit LSTM layer; the paper's Table S2: two of 128); chapters 08 and 10 list
    every difference in their "Paper vs. us" tables. Chapter 08's ODMO turns on two changes of ours
    (:func:`~.experiment.chapter_model`: ``encoder_frame="heading"``, ``decoder_trajectory="every_frame"``).

    The chapter's ODMO, the extension with a prior on ``μ``, the ablations of Table 2 and the standard-VAE
    baseline differ only in fields of this config (:data:`~.experiment.VARIANTS`), never in code.

    Attributes:
        n_classes: action classes ``C`` (the one-hot condition).
        n_frames: frames per clip ``T`` the model generates (at the model's frame rate: 40 frames at 10 fps
            for the benchmark's 4-second clips).
        n_joints: skeleton joints ``J``; features per frame are ``3 (J - 1)`` (local movement profile) + 3
            (root trajectory).
        code_dim: latent code size ``D`` (the paper: 20).
        encoder_hidden: LSTM width of the LMP encoder; encoder_mlp: width of its two BatchNorm + PReLU layers.
        trajectory_hidden: LSTM width of the trajectory generator.
        motion_hidden: LSTM width of the motion generator (its trajectory encoder and its decoder).
        margin: contrastive margin ``α`` between codes of different classes (the paper: 5).
        same_class_slack: same-class codes closer than this do not attract each other (0 is the paper's
            eq. 1; the reference implementation, and the chapter, use 0.5, which leaves room for styles).
        prior_variance: ``σ₀²`` of the prior term, a variance: the posterior variance ``σ²`` the term pulls
            every code coordinate to (the paper: 0.05, supplement §2.1 and Table S1; the reference code's
            ``sigma = 0.05`` is the scale of a ``torch.distributions.Normal``, a standard deviation, so its
            posterior variance is 0.05² = 0.0025).
        prior: which prior term, see :data:`PriorTerm`.
        use_contrastive: the contrastive term ``L_c`` (off: ``-L_es`` and the standard VAE).
        use_end_point: feed the end point ``r_e`` to the trajectory generator (off: ``-r_e``).
        use_consistency: the consistency loss between the two trajectories (off: ``-L_cons``).
        use_trajectory_loss: the trajectory loss (off together with the consistency loss: ``-L_traj``).
        encoder_frame: the axes of the local movement profile the encoder reads, see :data:`EncoderFrame`.
        hips: the (left, right) hip joints whose horizontal vector gives a frame's heading (``"heading"``
            encoder frame; the default is the course skeleton's).
        decoder_trajectory: how the decoder reads the trajectory, see :data:`DecoderTrajectory`.
        contrastive_weight, prior_weight: weights of the two embedding terms in the joint objective. The
            prior's 0.5 is the reference implementation's balance (it adds KL(N(0, σ²) || N(0, σ₀²)), half of
            eq. 1's covariance terms), which fits our reconstruction terms, averaged over channels like the
            reference's; the standard VAE weighs its KL with 1.
    """

    n_classes: int = integer(6, minimum=1)
    n_frames: int = integer(40, minimum=2)
    n_joints: int = integer(22, minimum=2)
    code_dim: int = integer(20, minimum=1)
    encoder_hidden: int = integer(64, minimum=1)
    encoder_mlp: int = integer(128, minimum=1)
    trajectory_hidden: int = integer(64, minimum=1)
    motion_hidden: int = integer(64, minimum=1)
    margin: float = real(5.0, above=0)
    same_class_slack: float = real(0.5, minimum=0)
    prior_variance: float = real(0.05, above=0)
    prior: PriorTerm = choice(PRIOR_TERMS, "covariance")
    use_contrastive: bool = flag(True)
    use_end_point: bool = flag(True)
    use_consistency: bool = flag(True)
    use_trajectory_loss: bool = flag(True)
    encoder_frame: EncoderFrame = choice(ENCODER_FRAMES, "world")
    hips: tuple[int, int] = tuple_of((1, 2), kind=numbers.Integral, minimum=1, length=2)
    decoder_trajectory: DecoderTrajectory = choice(DECODER_TRAJECTORIES, "initial_state")
    contrastive_weight: float = real(1.0, minimum=0)
    prior_weight: float = real(0.5, minimum=0)

    def __post_init__(self) -> None:
        super().__post_init__()
        where = "ODMOConfig"
        if max(self.hips) >= self.n_joints or self.hips[0] == self.hips[1]:
            raise ValueError(
                f"{where}: hips must be two different non-root joints in [1, {self.n_joints}), "
                f"got {self.hips!r}"
            )
        if self.use_consistency and not self.use_trajectory_loss:
            raise ValueError(
                f"{where}: the consistency loss is part of the trajectory losses; "
                "-L_traj switches both off (use_consistency=False, use_trajectory_loss=False)"
            )

    @property
    def lmp_dim(self) -> int:
        """Channels of the local movement profile, ``3 (J - 1)``."""
        return 3 * (self.n_joints - 1)

    @property
    def feature_dim(self) -> int:
        """Channels per frame: the local movement profile and the 3 root-trajectory channels."""
        return self.lmp_dim + 3

    @property
    def condition_dim(self) -> int:
        """Size of the class-code condition, the flattened outer product one-hot ⊗ code: ``C · D``."""
        return self.n_classes * self.code_dim


def class_code_condition(code: Tensor, action: Tensor, n_classes: int) -> Tensor:
    """The flattened outer product ``one_hot(action) ⊗ code``: ``(B, D)``, ``(B,)`` -> ``(B, C · D)``."""
    where = "class_code_condition"
    check_tensor(code, "code", where, ndim=2)
    check_tensor(action, "action", where, ndim=1, floating=False)
    if action.is_floating_point():
        raise TypeError(f"{where}: action must be an integer tensor, got dtype {action.dtype}")
    if action.shape != code.shape[:1]:
        raise ValueError(
            f"{where}: action must be ({code.shape[0]},) like code's batch, got {tuple(action.shape)}"
        )
    if action.numel() and (int(action.min()) < 0 or int(action.max()) >= n_classes):
        raise ValueError(
            f"{where}: actions must lie in [0, {n_classes}), got [{int(action.min())}, {int(action.max())}]"
        )
    one_hot = F.one_hot(action, n_classes).to(code.dtype)
    return (one_hot[:, :, None] * code[:, None, :]).flatten(1)


def accumulate(velocity: Tensor) -> Tensor:
    """Positions ``(B, T, C)`` from the velocities of frames 1..T-1 ``(B, T - 1, C)``: frame 0 at the
    origin, frame ``t`` the sum of the first ``t`` velocities."""
    check_tensor(velocity, "velocity", "accumulate", ndim=3, finite=False)
    return torch.cat([torch.zeros_like(velocity[:, :1]), torch.cumsum(velocity, dim=1)], dim=1)


def heading_frame(lmp: Tensor, hips: tuple[int, int]) -> Tensor:
    """Local movement profiles ``(B, T, 3 (J - 1))`` (metres) with every frame turned about the vertical so
    that the body faces +x: the heading of a frame is perpendicular to the horizontal vector from the right
    hip to the left hip (``hips``: their joint indices, the root being joint 0)."""
    check_tensor(lmp, "lmp", "heading_frame", ndim=3)
    joints = lmp.unflatten(-1, (-1, 3))
    left, right = joints[..., hips[0] - 1, :2], joints[..., hips[1] - 1, :2]
    across = left - right  # points to the body's left: (0, w) when it faces +x
    yaw = torch.atan2(-across[..., 0], across[..., 1])
    turned = rotate_xy(joints[..., :2], -yaw[..., None])
    return torch.cat([turned, joints[..., 2:]], dim=-1).flatten(-2)


class LMPEncoder(nn.Module):
    """``(B, T, 3 (J - 1))`` local movement profiles -> ``μ (B, D)``, ``log σ² (B, D)``."""

    def __init__(self, cfg: ODMOConfig) -> None:
        super().__init__()
        self.cfg = cfg
        self.lstm = nn.LSTM(cfg.lmp_dim, cfg.encoder_hidden, batch_first=True)
        width = cfg.encoder_mlp
        self.head = nn.Sequential(
            nn.Linear(cfg.encoder_hidden, width),
            nn.BatchNorm1d(width),
            nn.PReLU(),
            nn.Linear(width, width),
            nn.BatchNorm1d(width),
            nn.PReLU(),
            nn.Linear(width, 2 * cfg.code_dim),
        )

    def forward(self, lmp: Tensor) -> tuple[Tensor, Tensor]:
        check_tensor(lmp, "lmp", "LMPEncoder", trailing=(self.cfg.lmp_dim,), ndim=3)
        if self.training and lmp.shape[0] < 2:
            raise ValueError("LMPEncoder: BatchNorm needs at least 2 clips per batch in training mode")
        outputs, _ = self.lstm(lmp)
        mu, logvar = self.head(outputs.mean(dim=1)).chunk(2, dim=-1)
        return mu, logvar


class TrajectoryGenerator(nn.Module):
    """``code (B, D)``, ``action (B,)``, ``end_point (B, 3)`` -> root trajectory ``(B, T, 3)`` from the
    origin.

    With ``use_end_point=False`` (the ``-r_e`` ablation) the end point is replaced by zeros.
    """

    def __init__(self, cfg: ODMOConfig) -> None:
        super().__init__()
        self.cfg = cfg
        hidden = cfg.trajectory_hidden
        self.embed = nn.Sequential(nn.Linear(cfg.condition_dim + 3 + 1, hidden), nn.PReLU())
        self.lstm = nn.LSTM(hidden, hidden, batch_first=True)
        self.velocity = nn.Sequential(nn.Linear(hidden, hidden), nn.PReLU(), nn.Linear(hidden, 3))

    def forward(self, code: Tensor, action: Tensor, end_point: Tensor) -> Tensor:
        check_tensor(end_point, "end_point", "TrajectoryGenerator", trailing=(3,), ndim=2)
        if end_point.shape[0] != code.shape[0]:
            raise ValueError(
                f"TrajectoryGenerator: end_point must be ({code.shape[0]}, 3), got {tuple(end_point.shape)}"
            )
        if not self.cfg.use_end_point:
            end_point = torch.zeros_like(end_point)
        steps = self.cfg.n_frames - 1
        per_clip = torch.cat([class_code_condition(code, action, self.cfg.n_classes), end_point], dim=-1)
        time = torch.linspace(1.0 / steps, 1.0, steps, dtype=code.dtype)
        inputs = torch.cat(
            [per_clip[:, None, :].expand(-1, steps, -1), time[None, :, None].expand(code.shape[0], -1, 1)],
            dim=-1,
        )
        out, _ = self.lstm(self.embed(inputs))
        return accumulate(self.velocity(out))


class MotionGenerator(nn.Module):
    """``trajectory (B, T, 3)``, ``code (B, D)``, ``action (B,)`` -> motion features ``(B, T, 3 (J - 1) +
    3)``."""

    def __init__(self, cfg: ODMOConfig) -> None:
        super().__init__()
        self.cfg = cfg
        hidden = cfg.motion_hidden
        self.trajectory_embed = nn.Sequential(nn.Linear(3, hidden), nn.PReLU())
        self.trajectory_encoder = nn.LSTM(hidden, hidden, batch_first=True)
        # the decoder's input embedding PReLU(W [previous frame; condition; time] + b), split in two linear
        # maps so that the part that does not change from frame to frame is computed once per clip
        self.previous_embed = nn.Linear(cfg.feature_dim, hidden, bias=False)
        per_frame_trajectory = 3 if cfg.decoder_trajectory == "every_frame" else 0
        self.condition_embed = nn.Linear(cfg.condition_dim + 1 + per_frame_trajectory, hidden)
        self.embed_activation = nn.PReLU()
        self.decoder = nn.LSTMCell(hidden, hidden)
        self.out = nn.Linear(hidden, cfg.feature_dim)

    def forward(
        self,
        trajectory: Tensor,
        code: Tensor,
        action: Tensor,
        target: Tensor | None = None,
        teacher_forcing: float = 0.0,
        generator: torch.Generator | None = None,
    ) -> Tensor:
        """Decode a motion; ``target`` ``(B, T, F)`` (standardised) is needed when ``teacher_forcing > 0``.

        ``generator`` draws which frames are teacher-forced (the global generator when ``None``).
        """
        cfg, where = self.cfg, "MotionGenerator"
        batch = code.shape[0]
        check_tensor(trajectory, "trajectory", where, trailing=(cfg.n_frames, 3), ndim=3)
        if trajectory.shape[0] != batch:
            raise ValueError(f"{where}: trajectory has {trajectory.shape[0]} clips, code has {batch}")
        check_scalar(teacher_forcing, "teacher_forcing", where, minimum=0, maximum=1)
        if teacher_forcing > 0:
            if target is None or target.shape != (batch, cfg.n_frames, cfg.feature_dim):
                raise ValueError(
                    f"{where}: teacher forcing needs target ({batch}, {cfg.n_frames}, {cfg.feature_dim}), "
                    f"got {None if target is None else tuple(target.shape)}"
                )
            forced = torch.rand(batch, cfg.n_frames, 1, generator=generator) < teacher_forcing
        _, (h, c) = self.trajectory_encoder(self.trajectory_embed(trajectory))
        h, c = h[0], c[0]
        condition = class_code_condition(code, action, cfg.n_classes)
        time = torch.arange(cfg.n_frames, dtype=code.dtype) / cfg.n_frames
        inputs = [
            condition[:, None, :].expand(-1, cfg.n_frames, -1),
            time[None, :, None].expand(batch, -1, 1),
        ]
        if cfg.decoder_trajectory == "every_frame":
            inputs.append(trajectory)
        per_frame = self.condition_embed(torch.cat(inputs, dim=-1))
        previous = code.new_zeros(batch, cfg.feature_dim)
        frames = []
        for t in range(cfg.n_frames):
            embedded = self.embed_activation(self.previous_embed(previous) + per_frame[:, t])
            h, c = self.decoder(embedded, (h, c))
            frame = self.out(h)
            frames.append(frame)
            previous = torch.where(forced[:, t], target[:, t], frame) if teacher_forcing > 0 else frame
        return torch.stack(frames, dim=1)


class ODMOOutput(NamedTuple):
    """What one pass through ODMO gives: ``mu``, ``logvar``, ``code`` ``(B, D)``; the standardised
    ``trajectory`` ``(B, T, 3)`` and ``motion`` ``(B, T, F)``."""

    mu: Tensor
    logvar: Tensor
    code: Tensor
    trajectory: Tensor
    motion: Tensor


class ODMO(nn.Module):
    """The three networks of ODMO, built from an :class:`ODMOConfig`.

    The networks work on standardised features: ``standardizer`` (fitted on the training clips with
    :meth:`fit_standardizer` before training, saved with the weights) maps metres to zero mean and unit
    variance per channel, so every joint and the root's height count in the losses, not just the long
    horizontal paths of the runs. The trajectory generator accumulates velocities in units of each
    trajectory channel's standard deviation, from the standardised origin. :meth:`encode` takes and
    :meth:`generate` returns metres.
    """

    def __init__(self, cfg: ODMOConfig) -> None:
        super().__init__()
        self.cfg = cfg
        self.standardizer = Standardizer(cfg.feature_dim)
        self.encoder = LMPEncoder(cfg)
        self.trajectory_generator = TrajectoryGenerator(cfg)
        self.motion_generator = MotionGenerator(cfg)

    def fit_standardizer(self, features: Tensor) -> ODMO:
        """Fit the standardiser on training clips ``(N, T, F)`` in metres; returns self."""
        self._check_features(features, "ODMO.fit_standardizer")
        self.standardizer.fit(features)
        return self

    def _check_features(self, features: Tensor, where: str) -> None:
        check_tensor(features, "features", where, trailing=(self.cfg.n_frames, self.cfg.feature_dim), ndim=3)

    def encode(self, features: Tensor) -> tuple[Tensor, Tensor]:
        """``μ`` and ``log σ²`` ``(B, D)`` of clips ``(B, T, F)`` in metres (only the local movement profile
        is read)."""
        self._check_features(features, "ODMO.encode")
        return self._encode(features)

    def _encode(self, features: Tensor) -> tuple[Tensor, Tensor]:
        """The encoder on clips ``(B, T, F)`` in metres: their local movement profile, in the axes of
        ``cfg.encoder_frame``, standardised with the LMP channels' statistics."""
        lmp = features[..., : self.cfg.lmp_dim]
        if self.cfg.encoder_frame == "heading":
            lmp = heading_frame(lmp, self.cfg.hips)
        mean, std = self.standardizer.mean[: self.cfg.lmp_dim], self.standardizer.std[: self.cfg.lmp_dim]
        return self.encoder((lmp - mean.to(lmp)) / std.to(lmp))

    def decode(
        self,
        code: Tensor,
        action: Tensor,
        end_point: Tensor,
        target: Tensor | None = None,
        teacher_forcing: float = 0.0,
    ) -> tuple[Tensor, Tensor]:
        """Standardised trajectory ``(B, T, 3)`` and motion ``(B, T, F)`` from codes ``(B, D)``, actions
        ``(B,)`` and end points ``(B, 3)`` in metres; ``target`` is the standardised clip for teacher
        forcing."""
        check_tensor(code, "code", "ODMO.decode", trailing=(self.cfg.code_dim,), ndim=2)
        check_tensor(end_point, "end_point", "ODMO.decode", trailing=(3,), ndim=2)
        mean, std = self.standardizer.mean[-3:].to(code), self.standardizer.std[-3:].to(code)
        steps = self.trajectory_generator(code, action, (end_point - mean) / std)
        trajectory = steps - mean / std
        motion = self.motion_generator(trajectory, code, action, target, teacher_forcing)
        return trajectory, motion

    def forward(self, features: Tensor, action: Tensor, teacher_forcing: float = 0.0) -> ODMOOutput:
        """Encode clips ``(B, T, F)`` (metres) of actions ``(B,)``, draw their codes and reconstruct them."""
        self._check_features(features, "ODMO.forward")
        standardized = self.standardizer.transform(features)
        mu, logvar = self._encode(features)
        code = reparameterize(mu, logvar)
        trajectory, motion = self.decode(code, action, features[:, -1, -3:], standardized, teacher_forcing)
        return ODMOOutput(mu, logvar, code, trajectory, motion)

    @torch.no_grad()
    def generate(self, code: Tensor, action: Tensor, end_point: Tensor) -> tuple[Tensor, Tensor]:
        """Motion features ``(B, T, F)`` and the trajectory generator's root trajectory ``(B, T, 3)``, both in
        metres, for codes ``(B, D)``, actions ``(B,)`` and end points ``(B, 3)``."""
        trajectory, motion = self.decode(code, action, end_point)
        std = self.standardizer.std[-3:].to(code)
        return self.standardizer.inverse(motion), trajectory * std + self.standardizer.mean[-3:].to(code)
