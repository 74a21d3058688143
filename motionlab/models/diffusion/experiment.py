r"""Chapter 11's experiment: MDM's sizes, its two runs, and training and measuring them on both cores.

:class:`ExperimentConfig` holds every knob (the denoiser's config, the frame stride, the training schedule,
the fast sampler and the sample sets); :data:`VARIANTS` lists the two runs as changes to the model's config:
``"mdm"``, MDM with its geometric losses at the repository's action-to-motion weights (1, 1, 1), and
``"mdm_no_geometry"``, the same model with :math:`\lambda_\text{pos} = \lambda_\text{vel} =
\lambda_\text{foot} = 0` (the paper's ablation of the geometric losses). :func:`runs` gives one
:class:`~motionlab.train.run.Run` per variant (:func:`diffusion_run`), each validating on the benchmark's val
split (prepared as the training clips) 40 times (its held-out curve), :func:`train_all` trains them on both
cores and :func:`measure` measures a trained model: sample sets drawn per action with the fast sampler
(DDIM on a respaced schedule, with classifier-free guidance), turned into joint positions at 30 fps and
measured with the benchmark's protocol (:func:`~motionlab.evaluation.benchmark.sample_metrics` with the
GRU evaluator: accuracy, FID, Diversity, Multimodality, IS), foot skating
(:func:`~motionlab.metrics.physical.foot_skating`) and how much the body moves per action
(:func:`action_speeds`, beside the real test clips'). Every sample set is seeded by the config alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from motionlab import config
from motionlab.evaluation import joint_speed
from motionlab.evaluation.benchmark import benchmark_evaluator, load_benchmark, sample_metrics
from motionlab.evaluation.evaluator import Evaluator, data_fingerprint
from motionlab.metrics import Interval, repeat_metric
from motionlab.metrics.physical import foot_skating
from motionlab.models.diffusion.data import MDMData, prepare, to_positions
from motionlab.models.diffusion.losses import diffusion_objective
from motionlab.models.diffusion.model import MDM, MDMConfig
from motionlab.models.diffusion.sampling import GUIDANCE_SCALE, sample
from motionlab.train import TensorBatches, TrainConfig, validation_every
from motionlab.train.many import Trained, train_many
from motionlab.train.run import Run, given
from motionlab.validation import check_choice, instance, integer, real

#: The chapter's runs as changes to the model's config; the names are the runs' cache names.
VARIANTS: dict[str, dict[str, float]] = {
    "mdm": {},
    "mdm_no_geometry": {"lambda_pos": 0.0, "lambda_vel": 0.0, "lambda_foot": 0.0},
}

#: The chapter that trains this family, and its main run (the training command's default).
CHAPTER, DEFAULT_RUN = "11_motion_diffusion", "mdm"


def variant_config(name: str, base: MDMConfig) -> MDMConfig:
    """``base`` with the changes of the variant ``name`` (a key of :data:`VARIANTS`)."""
    check_choice(name, "name", "variant_config", VARIANTS)
    return replace(base, **VARIANTS[name])


@dataclass(frozen=True)
class ExperimentConfig(config.ProfileConfig):
    """Every size and schedule of chapter 11; the defaults are the full profile (:meth:`full`): the course's
    MDM (:meth:`MDMConfig.course`: width 128, 4 layers, 1,000 diffusion steps), 6,000 steps of batches of 32,
    3 sample sets of 20 clips per action, each drawn with 25 guided DDIM steps.

    Why 6,000 steps: the held-out loss levels off within a few hundred (at 600 it fell 3.1 % of its fall over
    the last fifth), but the samples do not move yet. Trained 600 steps, ``"mdm"``'s walks and jogs moved at
    0.30 and 0.26 times the real test clips' body-frame joint speed and its lifts and kicks at 2.8 and 2.5
    times (chapter 11's measurement, seed 0); at 3,000 steps every action was within 0.33 to 1.13 times, at
    6,000 within 0.47 (wave) to 1.12, accuracy 0.95 against 0.88 (the README has the curve). The runs are
    the same for their first steps whatever the total (a constant learning rate), so a longer run extends a
    shorter one. One step takes about 0.21 s on one core of the course machine at batch 32 (the training
    command: 6,000 steps of ``"mdm"`` in 1,285 s with the other core training too), so the full profile
    trains each run in about 21 minutes, still a small fraction of the repository's schedule. The
    repository's evaluation samples with the full 1,000-step ancestral loop; we use the fast sampler
    (:mod:`.sampling`). One guided set of 120 clips costs 12.7 s at 50 DDIM steps on one core, so the
    measurement of both runs with 5 sets at 50 steps (127 s on one core) took most of chapter 11's budget; at
    25 steps the sample stays close to the 100-step one from the same noise (chapter 11, section 6: 0.18 of
    the distance between two different samples, against 0.07 at 50 steps), and 3 sets of 25 steps cost 38 s.

    Attributes:
        model: the denoiser's config (sizes, diffusion length, loss weights); :data:`VARIANTS` change it.
        frame_stride: frames of the 30 fps data per model frame (2: 15 fps, 60 frames per 4-second clip).
        steps, batch_size, lr: optimiser steps, batch size and AdamW learning rate of every run (the
            repository: AdamW at 1e-4, batches of 64; ours is higher for the short schedule).
        seed: seeds every run's initialisation and batches, and the sample sets.
        sample_steps: DDIM steps (``eta = 0``) of the respaced schedule the sample sets are drawn with.
        guidance: the classifier-free guidance scale of the sample sets (the repository's sampling default
            2.5; 1 is the plain conditional model).
        n_per_action: clips per action in a sample set; n_sets: sample sets (each number is a mean with its
            95 % interval over them).
    """

    model: MDMConfig = instance(MDMConfig, default_factory=MDMConfig.course)
    frame_stride: int = integer(2, minimum=1)
    steps: int = integer(6_000, minimum=1)
    batch_size: int = integer(32, minimum=1)
    lr: float = real(5e-4, above=0)
    seed: int = config.seed_field()
    sample_steps: int = integer(25, minimum=1)
    guidance: float = real(GUIDANCE_SCALE, minimum=0)
    n_per_action: int = integer(20, minimum=2)
    n_sets: int = integer(3, minimum=2)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.sample_steps > self.model.diffusion_steps:
            raise ValueError(
                f"ExperimentConfig: sample_steps={self.sample_steps} exceeds the model's "
                f"{self.model.diffusion_steps} diffusion steps"
            )

    @classmethod
    def quick(cls) -> ExperimentConfig:
        """A tiny denoiser (width 16, one layer, 100 diffusion steps), 12 steps and 2 small sample sets of 4
        DDIM steps: every code path in seconds. Its learning rate is ten times the full profile's (5e-3): 12
        steps then take its samples from noise to motion whose feet are planted now and then (at least 235
        planted frame pairs per sample set for seeds 0-9), so that foot skating is defined for every seed (at
        4 steps and 5e-4 the samples were noise, and for seed 2 no foot of a sample set was planted on two
        consecutive frames)."""
        return cls(
            model=MDMConfig.course(latent_dim=16, ff_size=32, layers=1, heads=2, diffusion_steps=100),
            steps=12,
            batch_size=16,
            lr=5e-3,
            sample_steps=4,
            n_per_action=4,
            n_sets=2,
        )

    @classmethod
    def long(cls) -> ExperimentConfig:
        """A longer, larger run for the training command (``python -m motionlab.apps.training diffusion
        --config long``): twice the full profile's steps (12,000) and a denoiser twice as wide (256,
        feed-forward 512, 4 layers); the same sample sets as :meth:`full`."""
        return cls(model=MDMConfig.course(latent_dim=256, ff_size=512), steps=12_000)

    def train_config(self, validate: bool = False) -> TrainConfig:
        """Every run's :class:`~motionlab.train.TrainConfig`; ``validate``: it validates 40 times
        (:func:`~motionlab.train.validation_every`), as the runs on the benchmark do (:func:`variant_runs`);
        the runs on real motion capture (:mod:`.real_experiment`) have no val split."""
        return TrainConfig(
            steps=self.steps,
            batch_size=self.batch_size,
            lr=self.lr,
            grad_clip=1.0,
            seed=self.seed,
            checkpoint_every=None,
            log_every=20,
            val_every=validation_every(self.steps) if validate else None,
        )


def build_mdm(cfg: MDMConfig, data: MDMData, seed: int) -> MDM:
    """MDM of ``cfg``, its weights drawn after seeding torch's global generator with ``seed``, its
    standardiser fitted on ``data``."""
    torch.manual_seed(seed)
    return MDM(cfg).fit_standardizer(data.features)


def training_batches(data: MDMData, model: nn.Module) -> TensorBatches:
    """Shuffled batches of the training clips (:meth:`MDMData.batches`)."""
    return data.batches()


def validation_batches(val: MDMData, model: nn.Module) -> TensorBatches:
    """Batches ``(features (B, T, F), action (B,))`` of the validation clips, every one once in its order,
    for the run's held-out curve (the loss standardises them with the model's standardiser, fitted on the
    training clips)."""
    return TensorBatches((val.features, val.action), shuffle=False, drop_last=False)


def diffusion_run(
    name: str, cfg: MDMConfig, train_config: TrainConfig, data: MDMData, val: MDMData | None = None
) -> Run:
    """A variant's :class:`~motionlab.train.run.Run`, cached as ``name``: MDM of ``cfg`` (seeded by
    ``train_config.seed``) on shuffled batches of ``data`` (its fingerprints and frame stride are the cache
    key's data part); it validates on the clips ``val`` (prepared as ``data``) every
    ``train_config.val_every`` steps when given (give both or neither)."""
    for what, clips in (("data", data), ("val", val)):
        if clips is not None and tuple(clips.features.shape[1:]) != (cfg.n_frames, cfg.n_features):
            raise ValueError(
                f"diffusion_run: the config expects clips of {cfg.n_frames} frames x {cfg.n_features} "
                f"features, the {what} has {tuple(clips.features.shape[1:])}"
            )
    if val is not None and val.frame_stride != data.frame_stride:
        raise ValueError(
            f"diffusion_run: the val clips have frame_stride {val.frame_stride}, the data {data.frame_stride}"
        )
    return Run(
        name,
        cfg,
        partial(build_mdm, cfg, data),
        given(diffusion_objective),
        partial(training_batches, data),
        train_config,
        {
            "features": data_fingerprint(data.features),
            "action": data_fingerprint(data.action.float()),
            "frame_stride": data.frame_stride,
        },
        val_batches=None if val is None else partial(validation_batches, val),
    )


@dataclass(frozen=True, eq=False)
class ChapterData:
    """What the runs train on and are measured with.

    Attributes:
        train: the prepared training clips; val: the benchmark's val split prepared the same way (the runs'
            held-out curve).
        evaluator: the benchmark's frozen GRU evaluator; train_features: its features of the training clips
            ``(N, D)`` (FID's reference).
        fps: the benchmark's frame rate (30), of the positions the sample sets are measured in.
        real_skating: the foot skating (m/s) of the benchmark's test clips, the sample sets' target.
        real_speed: ``{action name: mean body-frame joint speed (m/s)}`` of the benchmark's test clips of
            each action (:func:`action_speeds`), what the samples of that action should move like.
    """

    train: MDMData
    val: MDMData
    evaluator: Evaluator
    train_features: Tensor
    fps: float
    real_skating: float
    real_speed: dict[str, float]


def action_speeds(
    positions: Tensor | np.ndarray, action: Tensor | np.ndarray, action_names: Sequence[str], fps: float
) -> dict[str, float]:
    """``{action name: mean body-frame joint speed (m/s)}``: :func:`~motionlab.evaluation.joint_speed` of
    clips ``(N, T, 22, 3)`` at ``fps``, averaged over the frames of each action's clips (actions ``(N,)``
    indexing ``action_names``); how much the body itself moves, travel over the floor left out. An action
    without clips is left out."""
    speed = joint_speed(positions, fps=fps).mean(-1)  # (N,)
    action = torch.as_tensor(np.asarray(action))
    if action.shape != speed.shape:
        raise ValueError(
            f"action_speeds: need one action per clip ({speed.shape[0]}), got {tuple(action.shape)}"
        )
    return {
        name: float(speed[action == index].mean())
        for index, name in enumerate(action_names)
        if bool((action == index).any())
    }


def load_data(cfg: ExperimentConfig) -> ChapterData:
    """The benchmark's training and val clips prepared at ``cfg.frame_stride``, the GRU evaluator and its
    reference features, and the test clips' foot skating and joint speed per action."""
    if not isinstance(cfg, ExperimentConfig):
        raise TypeError(f"load_data: cfg must be an ExperimentConfig, got {type(cfg).__name__}")
    benchmark = load_benchmark()
    evaluator = benchmark_evaluator("gru", progress=False)
    fps, test = float(benchmark.train.fps), benchmark.test
    return ChapterData(
        prepare(benchmark.train, cfg.frame_stride),
        prepare(benchmark.val, cfg.frame_stride),
        evaluator,
        evaluator.features(benchmark.train.positions),
        fps,
        foot_skating(test.positions, fps=fps),
        action_speeds(test.positions, test.action, test.action_names, fps),
    )


def variant_runs(cfg: ExperimentConfig, train: MDMData, val: MDMData | None = None) -> dict[str, Run]:
    """Both variants' runs ``{name: Run}`` on the prepared training clips ``train``, in :data:`VARIANTS`'
    order, validating on the prepared val clips ``val`` (``None``: they do not validate, and their cache
    key is not the chapter's runs')."""
    if train.frame_stride != cfg.frame_stride:
        raise ValueError(
            f"variant_runs: the data was prepared with frame_stride {train.frame_stride}, the config has "
            f"{cfg.frame_stride}"
        )
    training = cfg.train_config(validate=val is not None)
    return {
        name: diffusion_run(name, variant_config(name, cfg.model), training, train, val) for name in VARIANTS
    }


def runs(cfg: ExperimentConfig, data: ChapterData) -> dict[str, Run]:
    """Both variants' runs ``{name: Run}`` in :data:`VARIANTS`' order (:func:`variant_runs`), validating on
    ``data.val``."""
    return variant_runs(cfg, data.train, data.val)


def generate_positions(
    model: MDM, cfg: ExperimentConfig, action: Tensor, generator: torch.Generator
) -> Tensor:
    """One clip per action of ``action`` ``(N,)`` drawn with the chapter's sampler (``cfg.sample_steps`` DDIM
    steps, guidance ``cfg.guidance``), as joint positions at the data's frame rate ``(N, T · stride, J, 3)``
    on the average skeleton."""
    features = sample(
        model,
        action,
        steps=cfg.sample_steps,
        method="ddim",
        guidance=cfg.guidance,
        generator=generator,
    )
    return to_positions(features, cfg.frame_stride)


def sample_set(model: MDM, cfg: ExperimentConfig, generator: torch.Generator) -> tuple[Tensor, np.ndarray]:
    """One sample set: ``cfg.n_per_action`` clips per action (:func:`generate_positions`), as joint
    positions ``(N, T · stride, J, 3)``, with their actions ``(N,)``."""
    action = torch.arange(model.cfg.n_actions).repeat_interleave(cfg.n_per_action)
    return generate_positions(model, cfg, action, generator), action.numpy()


def set_metrics(
    data: ChapterData, drawn: tuple[Tensor, np.ndarray], rng: np.random.Generator
) -> dict[str, float]:
    """The benchmark's metric row of one sample set (positions ``(N, T, J, 3)``, actions ``(N,)``), its
    foot skating (m/s) and, as ``"speed.<action>"``, its clips' joint speed per action (m/s,
    :func:`action_speeds`; the actions of ``data.real_speed``)."""
    positions, action = drawn
    row = sample_metrics(data.evaluator, positions, action, data.train_features, rng)
    row["skating"] = foot_skating(positions.numpy(), fps=data.fps)
    speeds = action_speeds(positions, action, list(data.real_speed), data.fps)
    row.update({f"speed.{name}": speed for name, speed in speeds.items()})
    return row


def sample_row(cfg: ExperimentConfig, data: ChapterData, model: MDM) -> dict[str, Interval]:
    """``{metric: Interval}`` over ``cfg.n_sets`` sample sets (:func:`sample_set`, :func:`set_metrics`),
    seeded by ``cfg.seed``."""

    def draw(generator: torch.Generator) -> tuple[tuple[Tensor, np.ndarray], np.random.Generator]:
        return sample_set(model, cfg, generator), np.random.default_rng(generator.initial_seed())

    return repeat_metric(lambda drawn: set_metrics(data, *drawn), draw, cfg.n_sets, cfg.seed)


def measure(cfg: ExperimentConfig, data: ChapterData, name: str, model: nn.Module) -> dict[str, Any]:
    """The training command's measurement of run ``name``: the sample sets' metrics ``{metric: Interval}``
    (:func:`sample_row`), the sampler that drew them, and the real test clips' foot skating beside them."""
    check_choice(name, "name", "measure", VARIANTS)
    if not isinstance(model, MDM):
        raise TypeError(f"measure: model must be an MDM, got {type(model).__name__}")
    return {
        "samples": sample_row(cfg, data, model),
        "sampler": {"method": "ddim", "steps": cfg.sample_steps, "guidance": cfg.guidance},
        "real_skating": data.real_skating,
    }


def with_steps(cfg: ExperimentConfig, name: str, steps: int) -> ExperimentConfig:
    """``cfg`` with every run (``name`` too) trained for ``steps`` steps."""
    return replace(cfg, steps=steps)


def train_all(
    cfg: ExperimentConfig, data: ChapterData, processes: int | None = None, progress: bool | None = None
) -> dict[str, Trained[dict[str, Any]]]:
    """Train (or load) both runs on ``processes`` cores and :func:`measure` each as soon as it is trained.

    Returns ``{name: Trained}`` in :data:`VARIANTS`' order, each model loaded here from the cache and its
    measurement in ``measured``.
    """
    then = partial(measure, cfg, data)
    return train_many(runs(cfg, data), then=then, processes=processes, progress=progress)
