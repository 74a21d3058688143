"""ODMO (Lu et al., "Action-conditioned On-demand Motion Generation", ACM MM 2022) on the course benchmark.

Modules, in the order of the chapter: :mod:`.data` (local movement profile + root trajectory, class-balanced
batches), :mod:`.model` (the config, the LMP encoder and the two generators), :mod:`.losses` (the joint
objective, eq. 5, with the contrastive term of eq. 1 and the σ₀² prior term), :mod:`.modes` (mode discovery
and sampling in the code space), :mod:`.sampling` (codes to joint positions, on-demand customisation),
:mod:`.evaluate` (Tables 1–4 and the adjusted Rand index against the true modes) and :mod:`.experiment`
(the chapter's sizes and variants, every variant trained and measured on both cores).
"""

from motionlab.lazy import lazy_exports

#: Each public name with the module that holds it, imported on first use: a chapter that needs one module
#: (``from motionlab.models.odmo.losses import ...``) does not load the others.
_EXPORTS: dict[str, str] = {
    "ExperimentConfig": "motionlab.models.odmo.experiment",
    "ModeSet": "motionlab.models.odmo.modes",
    "ODMO": "motionlab.models.odmo.model",
    "ODMOConfig": "motionlab.models.odmo.model",
    "ODMOData": "motionlab.models.odmo.data",
    "ODMOSampler": "motionlab.models.odmo.sampling",
    "Samples": "motionlab.models.odmo.sampling",
    "VARIANTS": "motionlab.models.odmo.experiment",
    "choose_component_count": "motionlab.models.odmo.modes",
    "discover_modes": "motionlab.models.odmo.modes",
    "encode_clips": "motionlab.models.odmo.sampling",
    "joint_objective": "motionlab.models.odmo.losses",
    "prepare": "motionlab.models.odmo.data",
    "to_positions": "motionlab.models.odmo.data",
    "train_all": "motionlab.models.odmo.experiment",
    "variant_config": "motionlab.models.odmo.experiment",
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
__all__ = sorted(_EXPORTS)
