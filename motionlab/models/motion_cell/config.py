"""Configuration dataclasses of the Motion Cell chapter: the models, their losses and the denoiser.

Every model is built from one frozen dataclass (it is part of the checkpoint's cache key). Sizes are the
paper's Table 1 scaled down to the course's 22-joint synthetic data and its 2-core CPU budget.
"""

from __future__ import annotations

from dataclasses import dataclass

#: Rotation outputs a decoder can produce (compared in the chapter, the paper's Sec. 6.4).
OUTPUT_KINDS = ("quaternion", "matrix", "axis_angle")

#: Joint weights of the reconstruction loss: eq. 23's impact weights, or all ones (the NL ablation).
JOINT_WEIGHTINGS = ("impact", "uniform")

#: Root channels at the end of every pose vector (:data:`motionlab.data.representations.ROOT_FEATURES`).
ROOT_DIM = 6


def _positive(owner: str, **values: int | float) -> None:
    for name, value in values.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
            raise ValueError(f"{owner}.{name} must be a positive number, got {value!r}")


def _non_negative(owner: str, **values: float) -> None:
    for name, value in values.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value >= 0:
            raise ValueError(f"{owner}.{name} must be a number >= 0, got {value!r}")


def _choice(owner: str, name: str, value: str, allowed: tuple[str, ...]) -> None:
    if value not in allowed:
        raise ValueError(f"{owner}.{name} must be one of {allowed}, got {value!r}")


def _joints(owner: str, n_joints: int) -> None:
    if isinstance(n_joints, bool) or not isinstance(n_joints, int) or n_joints < 2:
        raise ValueError(f"{owner}.n_joints must be an integer >= 2, got {n_joints!r}")


def pose_dim(n_joints: int) -> int:
    """Channels of one pose vector of a ``n_joints`` skeleton: ``J - 1`` quaternions and the 6 root
    channels."""
    return (n_joints - 1) * 4 + ROOT_DIM


@dataclass(frozen=True)
class MotionCellConfig:
    """The hierarchical Motion Cell (and its SL ablation with ``word_length=1``).

    Attributes:
        n_joints: skeleton joints ``J``; a pose vector has ``(J - 1) * 4 + 6`` channels.
        word_length: poses per motion word ``l`` (the paper: 3; 1 feeds poses directly, the SL ablation).
        word_dim: size of a motion word's code (output of ``f_enc^w``, input of ``f_dec^w``).
        feature_dim: output size of the feature MLPs ``f_w`` and ``f_z``.
        latent_dim: size of the per-word latent ``z_t``.
        hidden_dim: width of each of the two stacked GRU cells and of the prior / posterior / decoder MLPs.
        control_dim: size of the control embedding ``f_c(c)`` of action and body type.
        n_actions, n_bodies: number of action classes and body types (the control attributes).
        output: rotation output of the decoder, one of :data:`OUTPUT_KINDS`.
    """

    n_joints: int = 22
    word_length: int = 3
    word_dim: int = 64
    feature_dim: int = 64
    latent_dim: int = 24
    hidden_dim: int = 128
    control_dim: int = 32
    n_actions: int = 6
    n_bodies: int = 2
    output: str = "quaternion"

    def __post_init__(self) -> None:
        _positive(
            "MotionCellConfig",
            word_length=self.word_length,
            word_dim=self.word_dim,
            feature_dim=self.feature_dim,
            latent_dim=self.latent_dim,
            hidden_dim=self.hidden_dim,
            control_dim=self.control_dim,
            n_actions=self.n_actions,
            n_bodies=self.n_bodies,
        )
        _joints("MotionCellConfig", self.n_joints)
        _choice("MotionCellConfig", "output", self.output, OUTPUT_KINDS)

    @property
    def pose_dim(self) -> int:
        """Channels of one pose vector (:func:`pose_dim`)."""
        return pose_dim(self.n_joints)


@dataclass(frozen=True)
class BaselineConfig:
    """A frame-level deterministic recurrent baseline: ERD or the QuaterNet-style quaternion RNN.

    Attributes:
        kind: ``"erd"`` (MLP encoder, 2-layer LSTM, MLP decoder; Fragkiadaki et al. 2015) or
            ``"quaternet"`` (2-layer GRU, quaternion outputs as rotations of the previous pose, trained
            through forward kinematics; Pavllo et al. 2018).
        n_joints, n_actions, n_bodies, control_dim: as in :class:`MotionCellConfig`.
        hidden_dim: recurrent width; encoder_dim: ERD's encoder / decoder width (unused by QuaterNet).
    """

    kind: str = "erd"
    n_joints: int = 22
    hidden_dim: int = 128
    encoder_dim: int = 128
    control_dim: int = 32
    n_actions: int = 6
    n_bodies: int = 2

    def __post_init__(self) -> None:
        _choice("BaselineConfig", "kind", self.kind, ("erd", "quaternet"))
        _positive(
            "BaselineConfig",
            hidden_dim=self.hidden_dim,
            encoder_dim=self.encoder_dim,
            control_dim=self.control_dim,
            n_actions=self.n_actions,
            n_bodies=self.n_bodies,
        )
        _joints("BaselineConfig", self.n_joints)

    @property
    def pose_dim(self) -> int:
        """Channels of one pose vector (:func:`pose_dim`)."""
        return pose_dim(self.n_joints)


@dataclass(frozen=True)
class LossConfig:
    """Fixed weights of the Motion Cell objective (eq. 14); the scheduled ones live in the ``TrainConfig``.

    The schedules the loss reads (``coeffs``): ``"beta"`` (KL weight, :class:`~motionlab.train.KLAnneal`),
    ``"classifier"`` (lambda_CL, a :class:`~motionlab.train.LinearRamp` that starts after a while) and
    ``"word_drop"`` (probability of dropping a motion word from the recurrence input).

    Attributes:
        joint_weights: ``"impact"`` (eq. 23 alpha_k) or ``"uniform"`` (all alpha_k = 1, the NL ablation).
        root_weight: weight of the squared error on the 6 standardised root channels, per frame.
        norm_weight: lambda of the quaternion-norm constraint (eq. 26).
        feature_weight, entropy_weight: weights of the feature-matching and cross-entropy parts of the
            classifier loss (eq. 24).
        classifier_clips: clips sampled per step for the classifier loss, with the attributes of the first
            ``classifier_clips`` clips of the batch (each costs a free-running rollout, forward kinematics and
            the conv net; a small number keeps a step cheap).
        classifier_every: the classifier loss is computed every this many steps, with this factor on its
            weight (the same weight on average, at a fraction of the cost).
        classifier_truncate: the classifier's gradient stops at the recurrent state between words (it
            shapes each word's prior and decoder, not the earlier words; through a rollout of tens of words
            the full gradient explodes and swamps the reconstruction).
    """

    joint_weights: str = "impact"
    root_weight: float = 1.0
    norm_weight: float = 0.1
    feature_weight: float = 1.0
    entropy_weight: float = 1.0
    classifier_clips: int = 8
    classifier_every: int = 3
    classifier_truncate: bool = True

    def __post_init__(self) -> None:
        _choice("LossConfig", "joint_weights", self.joint_weights, JOINT_WEIGHTINGS)
        _non_negative(
            "LossConfig",
            root_weight=self.root_weight,
            norm_weight=self.norm_weight,
            feature_weight=self.feature_weight,
            entropy_weight=self.entropy_weight,
        )
        _positive(
            "LossConfig", classifier_clips=self.classifier_clips, classifier_every=self.classifier_every
        )


@dataclass(frozen=True)
class DenoiserConfig:
    """The 1D-convolutional denoising autoencoder (the paper's Table 1, scaled).

    Attributes:
        n_joints: skeleton joints; channels: width of the outer conv layers; bottleneck: width of the code;
        kernel_size: temporal kernel (odd); every layer keeps the frame count.
    """

    n_joints: int = 22
    channels: int = 128
    bottleneck: int = 64
    kernel_size: int = 5

    def __post_init__(self) -> None:
        _joints("DenoiserConfig", self.n_joints)
        _positive("DenoiserConfig", channels=self.channels, bottleneck=self.bottleneck)
        if not isinstance(self.kernel_size, int) or self.kernel_size < 1 or self.kernel_size % 2 != 1:
            raise ValueError(
                f"DenoiserConfig.kernel_size must be an odd positive integer, got {self.kernel_size!r}"
            )

    @property
    def pose_dim(self) -> int:
        """Channels of one pose vector (:func:`pose_dim`)."""
        return pose_dim(self.n_joints)
