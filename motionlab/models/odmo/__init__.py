"""ODMO (Lu et al., "Action-conditioned On-demand Motion Generation", ACM MM 2022) on the course benchmark.

Modules, in the order of the chapter: :mod:`.data` (local movement profile + root trajectory),
:mod:`.config` (sizes, objective, ablation switches), :mod:`.encoder` (LMP encoder), :mod:`.contrastive`
(eq. 1, the σ² prior term, class-balanced pairs), :mod:`.trajectory` and :mod:`.generator` (the two
generators), :mod:`.model` (the joint objective, eq. 5), :mod:`.training`, :mod:`.modes` (mode discovery
and sampling), :mod:`.sampler` (codes to joint positions), :mod:`.customize` (on-demand generation),
:mod:`.evaluate` (Tables 1–4 and the adjusted Rand index against the true modes) and :mod:`.experiment`
(every variant trained and measured on both cores).
"""

from motionlab.models.odmo.config import VARIANTS, ODMOConfig, variant_config
from motionlab.models.odmo.data import ODMOData, prepare, to_positions
from motionlab.models.odmo.model import ODMO, joint_objective
from motionlab.models.odmo.modes import ModeSet, choose_component_count, discover_modes
from motionlab.models.odmo.sampler import ODMOSampler, Samples, encode_clips
from motionlab.models.odmo.training import ODMOTraining, train_odmo

__all__ = [
    "ODMO",
    "VARIANTS",
    "ModeSet",
    "ODMOConfig",
    "ODMOData",
    "ODMOSampler",
    "ODMOTraining",
    "Samples",
    "choose_component_count",
    "discover_modes",
    "encode_clips",
    "joint_objective",
    "prepare",
    "to_positions",
    "train_odmo",
    "variant_config",
]
