"""MoGlow (chapter 06): autoregressive, controllable motion with normalising flows, and its baselines.

"The paper" in this package is Henter, Alexanderson & Beskow, arXiv:1905.06598 (2019); its sections,
equations and figures are the ones cited.

Modules: :mod:`~.data` (features, augmentation, standardisation, windows), :mod:`~.conditioning` (the
autoregressive conditioning and its history dropout), :mod:`~.coupling` (the LSTM affine coupling),
:mod:`~.linear` (the least-squares first layer), :mod:`~.model` (MoGlow and its config), :mod:`~.losses`
(NLL per frame), :mod:`~.sampling` (generation: the plain loop, the fused loop, physical units, control
programmes), :mod:`~.baselines` (Gaussian autoregressive LSTM), :mod:`~.fixed_length` (the fixed-length
Glow of §3.4), :mod:`~.evaluate` (control mismatch, support-foot slide, joint-speed ratio, the control and
stability tests), :mod:`~.experiment` (the chapter's config, runs and training).
"""

from motionlab.models.moglow.baselines import GaussianAR, GaussianARConfig
from motionlab.models.moglow.conditioning import (
    autoregressive_conditioning,
    frame_conditioning,
    history_keep_mask,
)
from motionlab.models.moglow.coupling import LSTMAffineCoupling
from motionlab.models.moglow.data import (
    LOCOMOTION,
    MoGlowDataConfig,
    MoGlowFeatures,
    PreparedData,
    Scalers,
    augment_clips,
    clip_features,
    data_identity,
    fit_scalers,
    moglow_features,
    prepare_data,
    select_actions,
    sequence_windows,
    standardize,
)
from motionlab.models.moglow.evaluate import (
    control_mismatch,
    gait_speed,
    joint_speed,
    speed_ratio,
    support_foot_slide,
)
from motionlab.models.moglow.losses import (
    dropout_objective_nll,
    held_out_nll,
    held_out_nll_per_clip,
    held_out_nll_per_window,
    nll_per_frame_loss,
)
from motionlab.models.moglow.model import MoGlow, MoGlowConfig
from motionlab.models.moglow.sampling import (
    GeneratedMotion,
    Segment,
    autoregressive_sample,
    control_programme,
    generate_motion,
    sample_loop,
    sample_plain,
    seed_features,
    splice_controls,
)

__all__ = [
    "LOCOMOTION",
    "GaussianAR",
    "GaussianARConfig",
    "GeneratedMotion",
    "LSTMAffineCoupling",
    "MoGlow",
    "MoGlowConfig",
    "MoGlowDataConfig",
    "MoGlowFeatures",
    "PreparedData",
    "Scalers",
    "Segment",
    "augment_clips",
    "autoregressive_conditioning",
    "autoregressive_sample",
    "clip_features",
    "control_mismatch",
    "control_programme",
    "data_identity",
    "dropout_objective_nll",
    "fit_scalers",
    "frame_conditioning",
    "gait_speed",
    "generate_motion",
    "held_out_nll",
    "held_out_nll_per_clip",
    "held_out_nll_per_window",
    "history_keep_mask",
    "joint_speed",
    "moglow_features",
    "nll_per_frame_loss",
    "prepare_data",
    "sample_loop",
    "sample_plain",
    "seed_features",
    "select_actions",
    "sequence_windows",
    "speed_ratio",
    "splice_controls",
    "standardize",
    "support_foot_slide",
]
