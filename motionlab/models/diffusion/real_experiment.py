r"""MDM on the CMU motion capture (chapter 10), beside ODMO under Table 2's protocol, in the shape every
family has for the training command (``python -m motionlab.apps.training diffusion_cmu``): :data:`CHAPTER`,
:data:`DEFAULT_RUN`, :class:`ExperimentConfig` (``quick()``, ``full()``, ``long()``), :func:`load_data`,
:func:`runs`, :func:`measure`, :func:`with_steps` and :func:`train_all`.

**The representation.** The CMU clips hold 20 joint positions per frame and no rotations, so MDM reads
positions here: every frame is the xyz of the 20 joints, 60 channels (:class:`~.model.PositionMDMConfig`, the
repository's ``data_rep='xyz'``). The training windows are ODMO's: ``draws`` random ``window``-frame windows
of every training clip (shorter clips padded with their last frame), each with its first root at the origin
and turned to face +x at its first frame, every ``frame_stride``-th frame kept (:func:`prepare_real`).

**Table 2** (:func:`measure`): each sample set draws its classes stratified as the training clips
(:meth:`~motionlab.evaluation.real.Protocol.stratified_actions`), samples one clip per class label with the
fast sampler (DDIM on a respaced schedule, classifier-free guidance), interpolates the model frames back to
the window's frame rate and measures it with the real-data evaluator
(:func:`~motionlab.evaluation.real.table2_row`), as ODMO's rows are measured.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from motionlab.data.cmu_mocap import FEET, FPS, N_JOINTS, MocapClips, face_x, random_windows
from motionlab.evaluation import real
from motionlab.metrics import Interval
from motionlab.models.diffusion import experiment
from motionlab.models.diffusion.data import MDMData
from motionlab.models.diffusion.experiment import diffusion_run
from motionlab.models.diffusion.model import MDM, PositionMDMConfig
from motionlab.models.diffusion.sampling import sample
from motionlab.models.odmo.data import upsample_frames
from motionlab.train.many import Trained, train_many
from motionlab.train.run import Run
from motionlab.validation import check_scalar, instance, integer

#: The chapter that trains this family, and its main run (the training command's default).
CHAPTER, DEFAULT_RUN = "10_real_motion_capture", "mdm"

#: ``load_data`` reads a folder of clips given as ``--data PATH``.
READS_FOLDER = True

#: MDM's own action-to-motion results (Tevet et al., ICLR 2023), on other data sets than chapter 10's:
#: ``{data set (table): {row: {metric: (mean, 95 % half-width)}}}`` as the paper prints them (accuracy as a
#: fraction; UESTC's FID is its FID against the training set, FID_train). Each row is 20 evaluations of
#: 1,000 samples (§4.2); the models were trained for 750K (HumanAct12) and 2M (UESTC) steps.
PAPER_TABLES: dict[str, dict[str, dict[str, tuple[float, float]]]] = {
    "HumanAct12 (Table 3)": {
        "Real (ours)": {
            "accuracy": (0.990, 0.000),
            "fid": (0.050, 0.000),
            "diversity": (6.880, 0.020),
            "multimodality": (2.590, 0.010),
        },
        "MDM (ours)": {
            "accuracy": (0.990, 0.000),
            "fid": (0.100, 0.000),
            "diversity": (6.860, 0.050),
            "multimodality": (2.520, 0.010),
        },
    },
    "UESTC (Table 4)": {
        "Real": {
            "accuracy": (0.988, 0.001),
            "fid": (2.92, 0.26),
            "diversity": (33.34, 0.320),
            "multimodality": (14.16, 0.06),
        },
        "MDM (ours)": {
            "accuracy": (0.950, 0.000),
            "fid": (9.98, 1.33),
            "diversity": (33.02, 0.28),
            "multimodality": (14.26, 0.12),
        },
    },
}

#: The repository's foot-contact threshold, 0.01 m per frame at its 20 fps, as a speed (m/s).
CONTACT_SPEED = 0.01 * 20


def real_model(
    n_classes: int = 7, n_frames: int = 50, frame_stride: int = 2, **overrides: Any
) -> PositionMDMConfig:
    """MDM on CMU positions at half the course's width (64, feed-forward 128, 2 layers, 4 heads; Table 2
    draws 4,000 clips per row): 20 joints, ``n_classes`` actions, ``n_frames`` model frames, the CMU feet, the
    repository's contact speed at the model's frame rate (the data's 12 fps over ``frame_stride``);
    ``overrides`` replace any field."""
    model_fps = FPS / frame_stride
    base = PositionMDMConfig.course(
        latent_dim=64,
        ff_size=128,
        layers=2,
        n_joints=N_JOINTS,
        n_frames=n_frames,
        n_actions=n_classes,
        foot_joints=FEET,
        contact_threshold=CONTACT_SPEED / model_fps,
    )
    return replace(base, **overrides)


@dataclass(frozen=True)
class ExperimentConfig(experiment.ExperimentConfig):
    """MDM on CMU MoCap: chapter 11's fields (:class:`~.experiment.ExperimentConfig`: the training schedule,
    the sampler, ``n_sets``) plus the data and Table 2's protocol. The defaults are the full profile: all 970
    clips, a denoiser on positions of width 64 and 2 layers (1,000 diffusion steps), 300 steps of batches of
    32, Table 2's 10 sets of 400 clips drawn with 10 guided DDIM steps each (the inherited ``n_per_action``
    is not used: Table 2's sets are stratified as the data).

    Attributes:
        model: the denoiser on positions (:func:`real_model`).
        n_clips: keep a stratified subset of this many benchmark clips (``None``: all 970).
        window: frames per window (ODMO: 100); ``frame_stride`` (inherited): every ``frame_stride``-th frame
            is a model frame (2: 6 fps, 50 model frames); draws: random windows per training clip.
        sample_steps: DDIM steps of the respaced schedule the sample sets are drawn with (fewer than chapter
            11's 50: Table 2 draws 4,000 clips per row).
        n_per_set: Table 2's clips per sample set (the paper: 400); n_sets: sets per row (10).
    """

    model: PositionMDMConfig = instance(PositionMDMConfig, default_factory=real_model)
    steps: int = integer(300, minimum=1)  # not chapter 11's 600: this run levels off at 300 (3.2 %)
    sample_steps: int = integer(10, minimum=1)
    n_sets: int = integer(10, minimum=2)
    n_clips: int | None = integer(None, minimum=28, optional=True)
    window: int = integer(100, minimum=1)
    draws: int = integer(4, minimum=1)
    n_per_set: int = integer(400, minimum=1)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.window != self.model.n_frames * self.frame_stride:
            raise ValueError(
                f"ExperimentConfig: the model's {self.model.n_frames} frames x frame_stride "
                f"{self.frame_stride} must equal the window of {self.window} frames"
            )

    @classmethod
    def quick(cls) -> ExperimentConfig:
        """About a hundred clips, a tiny denoiser (width 16, one layer, 100 diffusion steps), 4 steps, 2 sets
        of 112 clips drawn with 4 DDIM steps: the code paths, in seconds."""
        model = real_model(latent_dim=16, ff_size=32, layers=1, heads=2, diffusion_steps=100)
        return cls(model=model, n_clips=112, steps=4, batch_size=14, sample_steps=4, n_sets=2, n_per_set=112)

    @classmethod
    def long(cls) -> ExperimentConfig:
        """A longer, larger run for the training command: 20 times the full profile's steps (6,000) on 8
        windows per clip, chapter 11's denoiser size (width 128, feed-forward 256, 4 layers); the same
        protocol."""
        return cls(model=real_model(latent_dim=128, ff_size=256, layers=4), steps=6_000, draws=8)


def prepare_real(
    clips: MocapClips, window: int = 100, frame_stride: int = 2, draws: int = 4, seed: int = 0
) -> MDMData:
    """MDM features of real clips (20 joints): ``draws`` random ``window``-frame windows of every clip, each
    turned to face +x at its first frame (first root at the origin), every ``frame_stride``-th frame kept,
    flattened to ``(N, window / frame_stride, 60)`` in metres. The data has no style labels: ``mode`` and
    ``body`` are zeros."""
    where = "prepare_real"
    for name, value in (("window", window), ("frame_stride", frame_stride), ("draws", draws)):
        check_scalar(value, name, where, kind=numbers.Integral, minimum=1)
    if window % frame_stride or window < 2 * frame_stride:
        raise ValueError(f"{where}: windows of {window} frames do not fit frame_stride {frame_stride}")
    windows = [random_windows(clips, window, np.random.default_rng([seed, d])) for d in range(draws)]
    positions = np.concatenate([face_x(w.positions) for w in windows])[:, ::frame_stride]
    features = torch.as_tensor(positions, dtype=torch.float32).flatten(2).contiguous()
    action = torch.as_tensor(np.concatenate([w.action for w in windows]), dtype=torch.int64)
    zeros = torch.zeros_like(action)
    return MDMData(features, action, zeros, zeros, frame_stride)


@dataclass(frozen=True, eq=False)
class ChapterData:
    """MDM's windows of the training clips ``train``, the real-data ``evaluator`` and Table 2's
    ``protocol`` (chapter 10's, shared with ODMO's rows)."""

    train: MDMData
    evaluator: real.XYZEvaluator
    protocol: real.Protocol


def load_data(cfg: ExperimentConfig, folder: Path | None = None) -> ChapterData:
    """Chapter 10's data: the CMU clips (floors levelled, stratified split), MDM's windows of the training
    clips, the real-data evaluator (chapter 10's sizes) and Table 2's protocol. ``folder``: a downloaded
    Action2Motion folder instead of the compact copy."""
    if not isinstance(cfg, ExperimentConfig):
        raise TypeError(f"load_data: cfg must be an ExperimentConfig, got {type(cfg).__name__}")
    bench, evaluator, protocol = real.chapter_table2(
        cfg.n_clips, cfg.n_per_set, cfg.n_sets, cfg.window, folder
    )
    train = prepare_real(bench.train, cfg.window, cfg.frame_stride, cfg.draws, cfg.seed)
    return ChapterData(train, evaluator, protocol)


def runs(cfg: ExperimentConfig, data: ChapterData) -> dict[str, Run]:
    """The one run ``{"mdm": Run}``, cached as ``real_mdm``: MDM with its geometric losses on the real
    windows."""
    if data.train.frame_stride != cfg.frame_stride:
        raise ValueError(
            f"runs: the data was prepared with frame_stride {data.train.frame_stride}, the config has "
            f"{cfg.frame_stride}"
        )
    return {DEFAULT_RUN: diffusion_run("real_mdm", cfg.model, cfg.train_config(), data.train)}


def generate_windows(model: MDM, cfg: ExperimentConfig, action: Tensor, generator: torch.Generator) -> Tensor:
    """One window per action of ``action`` ``(N,)``, drawn with ``cfg.sample_steps`` guided DDIM steps, as
    joint positions at the data's frame rate ``(N, window, 20, 3)``."""
    features = sample(
        model, action, steps=cfg.sample_steps, method="ddim", guidance=cfg.guidance, generator=generator
    )
    return upsample_frames(model.joint_positions(features), cfg.frame_stride)


def draw_generated(
    rng: np.random.Generator, model: MDM, cfg: ExperimentConfig, protocol: real.Protocol
) -> tuple[Tensor, np.ndarray]:
    """A Table 2 sample set: classes stratified as the training clips, one generated window each (the
    sampler's noise seeded from ``rng``)."""
    action = np.sort(protocol.stratified_actions(rng))
    generator = torch.Generator().manual_seed(int(rng.integers(2**62)))
    return generate_windows(model, cfg, torch.as_tensor(action), generator), action


def table2_row(cfg: ExperimentConfig, data: ChapterData, model: MDM) -> dict[str, Interval]:
    """MDM's row of Table 2 ``{metric: Interval}`` (accuracy as a fraction) under ``data.protocol``."""
    if not isinstance(model, MDM):
        raise TypeError(f"table2_row: model must be an MDM, got {type(model).__name__}")
    draw = partial(draw_generated, model=model, cfg=cfg, protocol=data.protocol)
    return real.table2_row(data.evaluator, data.protocol, draw)


def measure(cfg: ExperimentConfig, data: ChapterData, name: str, model: nn.Module) -> dict[str, Any]:
    """The run's row of chapter 10's Table 2 (accuracy, FID, diversity, multimodality) and the sampler that
    drew it."""
    if name != DEFAULT_RUN:
        raise ValueError(f"measure: the only run is {DEFAULT_RUN!r}, got {name!r}")
    return {
        "table2": table2_row(cfg, data, model),
        "sampler": {"method": "ddim", "steps": cfg.sample_steps, "guidance": cfg.guidance},
    }


def with_steps(cfg: ExperimentConfig, name: str, steps: int) -> ExperimentConfig:
    """``cfg`` with the run trained for ``steps`` steps."""
    return replace(cfg, steps=steps)


def train_all(
    cfg: ExperimentConfig,
    data: ChapterData,
    processes: int | None = None,
    progress: bool | None = None,
    alongside: dict[str, Run] | None = None,
) -> dict[str, Trained[dict[str, Any]]]:
    """Train (or load) the run on ``processes`` cores and :func:`measure` it in a worker as soon as it is
    trained; the runs ``alongside`` train on the same workers beside it. Returns ``{"mdm": Trained}``."""
    then = partial(measure, cfg, data)
    return train_many(runs(cfg, data), then=then, processes=processes, progress=progress, alongside=alongside)
