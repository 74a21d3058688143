"""The hierarchical Motion Cell of Ghorbani et al. (SCA 2020 / CGF), its baselines, ablations and evaluation.

Modules, in the order the chapter uses them:

- :mod:`.data`: pose vectors and the :class:`~.data.PoseCodec`, training windows;
- :mod:`.heads`: the rotation output heads (quaternion, rotation matrix, axis-angle);
- :mod:`.model`: the Motion Cell network and its config: motion words, the cell, the full model;
- :mod:`.denoise`: the capture-noise pipeline, the 1D-conv denoising autoencoder and the denoised
  training data;
- :mod:`.losses`: eq. 22-26 and their weights; :mod:`.baselines`: ERD and the QuaterNet-style RNN;
- :mod:`.evaluate`: the paper's protocol (Table 2, mean collapse, t-SNE);
- :mod:`.experiment`: the chapter's sizes per profile, its named runs, and training them all.
"""

from motionlab.models.motion_cell.baselines import BaselineConfig, FrameBaseline, baseline_loss
from motionlab.models.motion_cell.data import PoseCodec, WindowBatches, motion_cell_features
from motionlab.models.motion_cell.denoise import DenoiserConfig, DenoisingAutoencoder, noisy_features
from motionlab.models.motion_cell.experiment import ExperimentConfig, motion_cell_run, runs, train_all
from motionlab.models.motion_cell.losses import ClassifierLoss, LossConfig, motion_cell_loss
from motionlab.models.motion_cell.model import MotionCellConfig, MotionCellModel

__all__ = [
    "BaselineConfig",
    "ClassifierLoss",
    "DenoiserConfig",
    "DenoisingAutoencoder",
    "ExperimentConfig",
    "FrameBaseline",
    "LossConfig",
    "MotionCellConfig",
    "MotionCellModel",
    "motion_cell_run",
    "PoseCodec",
    "WindowBatches",
    "baseline_loss",
    "motion_cell_features",
    "motion_cell_loss",
    "noisy_features",
    "runs",
    "train_all",
]
