"""ODMO (Lu et al., "Action-conditioned On-demand Motion Generation", ACM MM 2022) on the course benchmark.

Modules, in the order of the chapter: :mod:`.data` (local movement profile + root trajectory, class-balanced
batches), :mod:`.model` (the config, the LMP encoder and the two generators), :mod:`.losses` (the joint
objective, eq. 5, with the contrastive term of eq. 1 and the σ₀² prior term), :mod:`.modes` (mode discovery
and sampling in the code space), :mod:`.sampling` (codes to joint positions, on-demand customisation),
:mod:`.evaluate` (Tables 1–4 and the adjusted Rand index against the true modes) and :mod:`.experiment`
(the chapter's sizes and variants, every variant trained and measured on both cores).
"""

from motionlab.models.odmo.data import ODMOData, prepare, to_positions
from motionlab.models.odmo.experiment import VARIANTS, ExperimentConfig, train_all, variant_config
from motionlab.models.odmo.losses import joint_objective
from motionlab.models.odmo.model import ODMO, ODMOConfig
from motionlab.models.odmo.modes import ModeSet, choose_component_count, discover_modes
from motionlab.models.odmo.sampling import ODMOSampler, Samples, encode_clips

__all__ = [
    "ODMO",
    "VARIANTS",
    "ExperimentConfig",
    "ModeSet",
    "ODMOConfig",
    "ODMOData",
    "ODMOSampler",
    "Samples",
    "choose_component_count",
    "discover_modes",
    "encode_clips",
    "joint_objective",
    "prepare",
    "to_positions",
    "train_all",
    "variant_config",
]
