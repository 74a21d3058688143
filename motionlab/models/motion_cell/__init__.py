"""The hierarchical Motion Cell of Ghorbani et al. (SCA 2020 / CGF), its baselines, ablations and evaluation.

Modules, in the order the chapter uses them:

- :mod:`.config`: the config dataclasses (model, baselines, loss weights, denoiser);
- :mod:`.data`: pose vectors and the :class:`~.data.PoseCodec`, training windows;
- :mod:`.denoise`: the capture-noise pipeline and the 1D-conv denoising autoencoder;
- :mod:`.words`, :mod:`.cell`, :mod:`.output`, :mod:`.model`: motion words, the Motion Cell, the rotation
  output heads and the full model;
- :mod:`.losses`: eq. 22-26; :mod:`.baselines`: ERD and the QuaterNet-style RNN;
- :mod:`.training`: building models, schedules, the checkpoint cache;
- :mod:`.settings`, :mod:`.preparation`, :mod:`.jobs`, :mod:`.runner`: the chapter's settings, its data
  pipeline (capture noise and denoiser), its training runs, and training them on both cores;
- :mod:`.evaluate`: the paper's protocol (Table 2, mean collapse, t-SNE).
"""

from motionlab.models.motion_cell.baselines import FrameBaseline, baseline_loss
from motionlab.models.motion_cell.config import BaselineConfig, DenoiserConfig, LossConfig, MotionCellConfig
from motionlab.models.motion_cell.data import PoseCodec, WindowBatches, motion_cell_features
from motionlab.models.motion_cell.denoise import DenoisingAutoencoder, noisy_features
from motionlab.models.motion_cell.losses import ClassifierLoss, motion_cell_loss
from motionlab.models.motion_cell.model import MotionCellModel

__all__ = [
    "BaselineConfig",
    "ClassifierLoss",
    "DenoiserConfig",
    "DenoisingAutoencoder",
    "FrameBaseline",
    "LossConfig",
    "MotionCellConfig",
    "MotionCellModel",
    "PoseCodec",
    "WindowBatches",
    "baseline_loss",
    "motion_cell_features",
    "motion_cell_loss",
    "noisy_features",
]
