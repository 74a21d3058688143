"""ODMO's configuration: network sizes, the embedding objective and the switches of the ablations.

One frozen dataclass builds every model of the chapter. The paper's model, the reference implementation's
variant, the ablations of Table 2 and the standard-VAE baseline differ only in fields of this config
(:data:`VARIANTS` lists them), never in code.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import Literal

#: Which Gaussian the prior term of the embedding loss compares with what (see :mod:`.contrastive`):
#: ``"noise"`` KL(N(0, s²) || N(0, σ²)) on the noise alone (reference implementation),
#: ``"code"`` KL(N(μ, s²) || N(0, σ²)) on the whole code (the paper's equation),
#: ``"standard"`` KL(N(μ, s²) || N(0, I)) (a standard VAE).
PriorTarget = Literal["noise", "code", "standard"]
PRIOR_TARGETS: tuple[str, ...] = ("noise", "code", "standard")


@dataclass(frozen=True)
class ODMOConfig:
    """Sizes and objective of one ODMO model. The defaults are the chapter's ODMO: the reference
    implementation's prior term (on the noise) and same-class slack, at the sizes the full profile trains.

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
        prior_variance: ``σ²`` of the prior term (the paper: 0.05).
        prior_target: see :data:`PriorTarget`.
        use_contrastive: the contrastive term ``L_c`` (off: ``-L_es`` and the standard VAE).
        use_end_point: feed the end point ``r_e`` to the trajectory generator (off: ``-r_e``).
        use_consistency: the consistency loss between the two trajectories (off: ``-L_cons``).
        use_trajectory_loss: the trajectory loss (off together with the consistency loss: ``-L_traj``).
        contrastive_weight, prior_weight: weights of the two embedding terms in the joint objective.
    """

    n_classes: int = 6
    n_frames: int = 40
    n_joints: int = 22
    code_dim: int = 20
    encoder_hidden: int = 64
    encoder_mlp: int = 128
    trajectory_hidden: int = 64
    motion_hidden: int = 64
    margin: float = 5.0
    same_class_slack: float = 0.5
    prior_variance: float = 0.05
    prior_target: PriorTarget = "noise"
    use_contrastive: bool = True
    use_end_point: bool = True
    use_consistency: bool = True
    use_trajectory_loss: bool = True
    contrastive_weight: float = 1.0
    prior_weight: float = 1.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.type == "int" and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
                raise ValueError(f"ODMOConfig.{f.name} must be a positive integer, got {value!r}")
            if f.type == "bool" and not isinstance(value, bool):
                raise ValueError(f"ODMOConfig.{f.name} must be True or False, got {value!r}")
        if self.n_frames < 2 or self.n_joints < 2:
            raise ValueError(
                f"ODMOConfig: n_frames and n_joints must be at least 2, got {self.n_frames}, {self.n_joints}"
            )
        for name in ("margin", "same_class_slack", "prior_variance", "contrastive_weight", "prior_weight"):
            value = getattr(self, name)
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float))
                or not math.isfinite(value)
                or value < 0
            ):
                raise ValueError(f"ODMOConfig.{name} must be a finite non-negative number, got {value!r}")
        if self.margin == 0 or self.prior_variance == 0:
            raise ValueError("ODMOConfig: margin and prior_variance must be positive")
        if self.prior_target not in PRIOR_TARGETS:
            raise ValueError(
                f"ODMOConfig.prior_target must be one of {PRIOR_TARGETS}, got {self.prior_target!r}"
            )
        if self.use_consistency and not self.use_trajectory_loss:
            raise ValueError(
                "ODMOConfig: the consistency loss is part of the trajectory losses; "
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


#: The chapter's models, as changes to the default config (the default is ODMO as the chapter uses it).
VARIANTS: dict[str, dict[str, object]] = {
    "ODMO": {},
    "ODMO (paper's prior term)": {"prior_target": "code"},
    "-L_es": {"use_contrastive": False},
    "-r_e": {"use_end_point": False},
    "-L_cons": {"use_consistency": False},
    "-L_traj": {"use_consistency": False, "use_trajectory_loss": False},
    "standard VAE": {"use_contrastive": False, "prior_target": "standard"},
}


def variant_config(name: str, base: ODMOConfig) -> ODMOConfig:
    """``base`` with the changes of the variant ``name`` (a key of :data:`VARIANTS`)."""
    if name not in VARIANTS:
        raise KeyError(f"unknown ODMO variant {name!r}; variants: {list(VARIANTS)}")
    return replace(base, **VARIANTS[name])
