"""Configuration of TrajeVAE and its ablation switches (one frozen dataclass builds every rung of Table 4)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from motionlab.models.trajevae.masks import KEEP_PROBABILITY


def check_positive_int(owner: str, name: str, value: int) -> None:
    """Raise ``ValueError`` unless ``value`` is an int >= 1 (bools refused)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ValueError(f"{owner}.{name} must be a positive integer, got {value!r}")


def check_probability(owner: str, name: str, value: float) -> None:
    """Raise ``ValueError`` unless ``value`` is a number in ``[0, 1]``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value <= 1.0:
        raise ValueError(f"{owner}.{name} must be a probability in [0, 1], got {value!r}")


def check_non_negative(owner: str, name: str, value: float) -> None:
    """Raise ``ValueError`` unless ``value`` is a finite number >= 0."""
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or value < 0
    ):
        raise ValueError(f"{owner}.{name} must be a finite non-negative number, got {value!r}")


def check_seed(owner: str, value: int) -> None:
    """Raise ``ValueError`` unless ``value`` is an int >= 0 (bools refused)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"{owner}.seed must be a non-negative integer, got {value!r}")


def check_flags(owner: str, config: object, names: tuple[str, ...]) -> None:
    """Raise ``ValueError`` unless each attribute of ``config`` in ``names`` is a bool."""
    for name in names:
        if not isinstance(getattr(config, name), bool):
            raise ValueError(f"{owner}.{name} must be a bool, got {getattr(config, name)!r}")


class WindowShape:
    """The window geometry every completion model's config shares (needs ``n_joints`` and ``n_frames``)."""

    n_joints: int
    n_frames: int

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
        beta: weight of ``KL(q_pose || p_traj)`` (the paper: 0.01).
        keep_probability: chance that a joint's trajectory is given in a training sequence (0.15).
        use_dct: attend over DCT components (``False``: over frames).
        learnable_prior: a posterior ``q_pose(z | X)`` and a learned prior ``p_traj(z | Y)`` (``False``: one
            encoder ``q(z | Y)`` regularised towards ``N(0, I)``, the Base model).
        augment: turn every training sequence by a random yaw.
        mask_future_poses: the posterior sees ``X ⊙ (1 - M)`` instead of ``X`` (needs ``learnable_prior``).
        seed: seeds the weight initialisation.
    """

    n_joints: int = 22
    n_frames: int = 120
    width: int = 64
    latent_dim: int = 32
    dct_components: int = 40
    heads: int = 4
    layers: int = 1
    beta: float = 0.01
    keep_probability: float = KEEP_PROBABILITY
    use_dct: bool = True
    learnable_prior: bool = True
    augment: bool = True
    mask_future_poses: bool = True
    seed: int = 0

    def __post_init__(self) -> None:
        owner = "TrajeVAEConfig"
        for name in ("n_joints", "n_frames", "width", "latent_dim", "dct_components", "heads", "layers"):
            check_positive_int(owner, name, getattr(self, name))
        if self.n_frames < 2:
            raise ValueError(
                f"{owner}.n_frames must be at least 2 (an initial pose and one frame), got {self.n_frames}"
            )
        if self.dct_components > self.n_frames - 1:
            raise ValueError(
                f"{owner}.dct_components ({self.dct_components}) cannot exceed the {self.n_frames - 1} "
                "completed frames"
            )
        if (2 * self.width) % self.heads:
            raise ValueError(
                f"{owner}: the token size 2 * width = {2 * self.width} must be divisible by "
                f"heads={self.heads}"
            )
        check_non_negative(owner, "beta", self.beta)
        check_probability(owner, "keep_probability", self.keep_probability)
        check_flags(owner, self, ("use_dct", "learnable_prior", "augment", "mask_future_poses"))
        if self.mask_future_poses and not self.learnable_prior:
            raise ValueError(
                f"{owner}: mask_future_poses masks the posterior's input, so it needs learnable_prior=True"
            )
        check_seed(owner, self.seed)

    @property
    def n_latent_steps(self) -> int:
        """Latent vectors per sequence: the DCT components, or one per completed frame without the DCT."""
        return self.dct_components if self.use_dct else self.n_future
