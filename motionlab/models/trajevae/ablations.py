"""The paper's Table 4 ablation ladder as switches of one :class:`TrajeVAEConfig`.

Each rung adds one component to the one before: **Base** (attention over frames, one encoder
``q(z | Y)`` pulled towards ``N(0, I)``, no augmentation), **+ DCT**, **+ learnable prior** (posterior
``q_pose(z | X)`` and prior ``p_traj(z | Y)``), **+ augmentation** (random yaw), **+ masked future poses**
(the posterior sees ``X ⊙ (1 - M)``), which is the full TrajeVAE.
"""

from __future__ import annotations

from dataclasses import replace

from motionlab.models.trajevae.config import TrajeVAEConfig

#: The switches in the order the ladder turns them on.
SWITCHES: tuple[str, ...] = ("use_dct", "learnable_prior", "augment", "mask_future_poses")

#: Rung names, Base first; rung ``i`` has the first ``i`` switches on.
RUNGS: tuple[str, ...] = ("Base", "+ DCT", "+ learnable prior", "+ augmentation", "+ masked future poses")


def ladder(full: TrajeVAEConfig) -> dict[str, TrajeVAEConfig]:
    """The five rungs ``{name: config}`` built from ``full`` (architecture and loss weight shared).

    The last rung equals ``full`` with every switch on.
    """
    if not isinstance(full, TrajeVAEConfig):
        raise TypeError(f"ladder: expected a TrajeVAEConfig, got {type(full).__name__}")
    return {
        name: replace(full, **{switch: index < rung for index, switch in enumerate(SWITCHES)})
        for rung, name in enumerate(RUNGS)
    }
