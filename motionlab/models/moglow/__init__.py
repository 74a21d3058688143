"""MoGlow (chapter 06): autoregressive, controllable motion with normalising flows, and its baseline.

Modules: :mod:`~.data` (features, augmentation, standardisation, windows), :mod:`~.config`,
:mod:`~.autoregression` (conditioning, history dropout, a frame-by-frame loop), :mod:`~.coupling`
(the LSTM affine coupling), :mod:`~.model` (MoGlow), :mod:`~.sampler` (MoGlow's generation loop),
:mod:`~.baseline` (Gaussian autoregressive LSTM), :mod:`~.training` (data splits, loss, held-out NLL),
:mod:`~.generate` (control programmes, physical units, joint positions), :mod:`~.measures` (support-foot
slide, joint-speed ratio).
"""

from motionlab.models.moglow.autoregression import (
    autoregressive_conditioning,
    autoregressive_sample,
    frame_conditioning,
    history_keep_mask,
)
from motionlab.models.moglow.baseline import GaussianAR
from motionlab.models.moglow.config import GaussianARConfig, MoGlowConfig
from motionlab.models.moglow.coupling import LSTMAffineCoupling
from motionlab.models.moglow.data import (
    LOCOMOTION,
    MoGlowDataConfig,
    MoGlowFeatures,
    Scalers,
    augment_clips,
    clip_features,
    fit_scalers,
    moglow_features,
    select_actions,
    sequence_windows,
    standardize,
)
from motionlab.models.moglow.generate import (
    GeneratedMotion,
    Segment,
    control_programme,
    generate_motion,
    seed_features,
    splice_controls,
)
from motionlab.models.moglow.measures import (
    control_mismatch,
    gait_speed,
    joint_speed,
    speed_ratio,
    support_foot_slide,
)
from motionlab.models.moglow.model import MoGlow
from motionlab.models.moglow.training import (
    PreparedData,
    data_identity,
    held_out_nll,
    nll_per_frame_loss,
    prepare_data,
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
    "fit_scalers",
    "frame_conditioning",
    "gait_speed",
    "generate_motion",
    "held_out_nll",
    "history_keep_mask",
    "joint_speed",
    "moglow_features",
    "nll_per_frame_loss",
    "prepare_data",
    "seed_features",
    "select_actions",
    "sequence_windows",
    "speed_ratio",
    "splice_controls",
    "standardize",
    "support_foot_slide",
]
