"""Chapter 10's ODMO on the CMU motion capture, in the shape every family has for the training command
(``python -m motionlab.apps.training odmo_cmu``): :data:`CHAPTER`, :data:`DEFAULT_RUN`, the config
(:class:`~.experiment.RealExperimentConfig`, here ``ExperimentConfig``), :func:`load_data`, :func:`runs`,
:func:`measure` and :func:`with_steps`. The chapter's own pieces are in :mod:`.experiment`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from torch import nn

from motionlab.evaluation import real
from motionlab.models.odmo.data import ODMOData, prepare_real
from motionlab.models.odmo.experiment import RealExperimentConfig as ExperimentConfig
from motionlab.models.odmo.experiment import measure_real, real_runs
from motionlab.train.run import Run

#: The chapter that trains this family, and its main run (the training command's default).
CHAPTER, DEFAULT_RUN = "10_real_motion_capture", "ODMO"

#: ``load_data`` reads a folder of clips given as ``--data PATH``.
READS_FOLDER = True


@dataclass(frozen=True)
class ChapterData:
    """ODMO's windows of the training clips ``train``, the real-data ``evaluator`` and Table 2's
    ``protocol``."""

    train: ODMOData
    evaluator: real.XYZEvaluator
    protocol: real.Protocol


def load_data(cfg: ExperimentConfig, folder: Path | None = None) -> ChapterData:
    """Chapter 10's data: the CMU clips (floors levelled, stratified split), ODMO's windows of the training
    clips, the real-data evaluator (chapter 10's sizes) and Table 2's protocol. ``folder``: a downloaded
    Action2Motion folder (``pose_clip.csv`` and one ``.npy`` per clip) instead of the compact copy."""
    bench, evaluator, protocol = real.chapter_table2(
        cfg.n_clips, cfg.n_per_set, cfg.n_sets, cfg.window, folder
    )
    train = prepare_real(bench.train, cfg.window, cfg.frame_stride, cfg.draws, cfg.seed)
    return ChapterData(train, evaluator, protocol)


def runs(cfg: ExperimentConfig, data: ChapterData) -> dict[str, Run]:
    """The runs of ``cfg.variants`` on the real windows (:func:`~.experiment.real_runs`)."""
    return real_runs(cfg, data.train)


def measure(cfg: ExperimentConfig, data: ChapterData, name: str, model: nn.Module) -> dict[str, Any]:
    """The variant's row of chapter 10's Table 2 (accuracy, FID, diversity, multimodality)."""
    return {"table2": measure_real(name, model, data.train, data.evaluator, data.protocol, cfg).row}


def with_steps(cfg: ExperimentConfig, name: str, steps: int) -> ExperimentConfig:
    """``cfg`` with every variant (``name`` too) trained for ``steps`` steps."""
    return replace(cfg, steps=steps)
