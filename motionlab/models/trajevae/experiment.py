"""Chapter 07's experiment: its sizes and schedule, its seven training runs, all of them trained and swept.

* :class:`ExperimentConfig` holds every knob of the chapter for one profile (:meth:`~ExperimentConfig.quick`,
  :meth:`~ExperimentConfig.full`, :meth:`~ExperimentConfig.current`): the full TrajeVAE, the two baselines,
  the one training schedule they all share (so they are compared at equal cost) and the test windows.
* :func:`ladder` builds the paper's Table 4 ablation ladder from the full TrajeVAE: **Base** (attention over
  frames, one encoder ``q(z | Y)`` pulled towards ``N(0, I)``, no augmentation), **+ DCT**, **+ learnable
  prior** (posterior ``q_pose(z | X)`` and prior ``p_traj(z | Y)``), **+ augmentation** (random yaw),
  **+ masked future poses** (the posterior sees ``X ⊙ (1 - M)``), which is the full TrajeVAE.
* :func:`completion_run` is one training run (a :class:`~motionlab.train.run.Run`), which validates on the
  benchmark's val clips (:func:`validation_batches`); :func:`runs` names the chapter's seven: the five rungs
  and the GRU and CVAE-RNN baselines.
* :func:`train_all` trains them on both cores and sweeps every model over the number of given trajectories
  in a worker as soon as it is trained (:func:`sweep`), so the sweeps fill the core that the last training
  leaves idle. A sweep loads its model from the checkpoint cache and is seeded by its arguments alone, so the
  tables do not depend on where or when it ran.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np
import torch
from torch import Tensor, nn

from motionlab import config
from motionlab.evaluation.benchmark import load_benchmark
from motionlab.evaluation.evaluator import data_fingerprint
from motionlab.metrics import mean_ci
from motionlab.models.trajevae.baselines import CVAERNN, GRUCompletion, RecurrentConfig
from motionlab.models.trajevae.data import (
    FRAME_STEP,
    CompletionBatches,
    CompletionData,
    completion_task,
    completion_windows,
    decimate,
)
from motionlab.models.trajevae.evaluate import (
    FIGURE6_KS,
    N_SAMPLES,
    PAPER_KS,
    Sweep,
    complete,
    decoded_means_error,
    dlow_metrics,
    follow_error,
    multimodal_futures,
    sweep_given_joints,
)
from motionlab.models.trajevae.losses import cvae_rnn_loss, gru_loss, trajevae_loss
from motionlab.models.trajevae.masks import first_joints
from motionlab.models.trajevae.model import TrajeVAE, TrajeVAEConfig
from motionlab.train import PiecewiseLinear, TrainConfig, validation_every
from motionlab.train.loop import LossFn
from motionlab.train.many import Trained, train_many
from motionlab.train.run import Run
from motionlab.validation import check_scalar, instance, integer

#: A completion model's config: TrajeVAE (any rung of the ladder) or a recurrent baseline.
ModelConfig = TrajeVAEConfig | RecurrentConfig

#: The ablation switches in the order the ladder turns them on.
SWITCHES: tuple[str, ...] = ("use_dct", "learnable_prior", "augment", "mask_future_poses")

#: Rung names, Base first; rung ``i`` has the first ``i`` switches on.
RUNGS: tuple[str, ...] = ("Base", "+ DCT", "+ learnable prior", "+ augmentation", "+ masked future poses")

#: Each run's checkpoint cache name.
CACHE_NAMES: dict[str, str] = {
    "Base": "trajevae_base",
    "+ DCT": "trajevae_dct",
    "+ learnable prior": "trajevae_learnable_prior",
    "+ augmentation": "trajevae_augmentation",
    "+ masked future poses": "trajevae_masked_future_poses",
    "GRU": "trajevae_gru",
    "CVAE-RNN": "trajevae_cvae_rnn",
}

#: The order to start the runs: the longest (training and sweep, measured in the full profile) first.
START_ORDER: tuple[str, ...] = (
    "+ masked future poses",
    "GRU",
    "CVAE-RNN",
    "+ augmentation",
    "+ learnable prior",
    "Base",
    "+ DCT",
)

#: The runs swept over Figure 6's k (up to all 22 joints); the others over Table 1's k = 0..4.
FIGURE6_RUNS: tuple[str, ...] = ("+ masked future poses", "GRU")


def _train_config(steps: int, batch_size: int, checkpoint_every: int | None) -> TrainConfig:
    """The chapter's one schedule: AdamW at 2e-3, a warm-up over the first eighth, then a linear decay; 40
    validation passes spread over it (:func:`~motionlab.train.validation_every`)."""
    return TrainConfig(
        steps=steps,
        batch_size=batch_size,
        lr=2e-3,
        grad_clip=None,
        lr_schedule=PiecewiseLinear(((0, 0.05), (steps // 8, 1.0), (steps, 0.05))),
        checkpoint_every=checkpoint_every,
        val_every=validation_every(steps),  # the held-out curve: passes over the validation clips
    )


@dataclass(frozen=True)
class ExperimentConfig(config.ProfileConfig):
    """Every size and schedule of chapter 07 for one profile.

    Attributes:
        trajevae: the full TrajeVAE, the last rung of the ablation ladder (:func:`ladder` builds the others).
        gru: the deterministic GRU baseline; cvae_rnn: the CVAE-RNN baseline.
        train: the schedule every model trains with (and validates with, on the val split's clips).
        n_eval_windows: test windows the metrics average over; n_samples: completions drawn per window and
            number of given trajectories (``N_SAMPLES``, DLow's 50).
    """

    trajevae: TrajeVAEConfig = instance(TrajeVAEConfig)
    gru: RecurrentConfig = instance(RecurrentConfig)
    cvae_rnn: RecurrentConfig = instance(RecurrentConfig)
    train: TrainConfig = instance(TrainConfig)
    n_eval_windows: int = integer(minimum=2)
    n_samples: int = integer(N_SAMPLES, minimum=2)

    def __post_init__(self) -> None:
        super().__post_init__()
        where = "ExperimentConfig"
        if not self.trajevae.n_frames == self.gru.n_frames == self.cvae_rnn.n_frames:
            raise ValueError(
                f"{where}: every model must complete the same windows, got n_frames "
                f"{self.trajevae.n_frames}, {self.gru.n_frames} and {self.cvae_rnn.n_frames}"
            )
        if self.gru.latent_dim != 0 or self.cvae_rnn.latent_dim < 1:
            raise ValueError(f"{where}: gru needs latent_dim 0 and cvae_rnn latent_dim >= 1")

    @classmethod
    def quick(cls) -> ExperimentConfig:
        """Tiny widths, ten steps and ten completions per window, so every code path runs in seconds."""
        return cls(
            trajevae=TrajeVAEConfig(n_frames=60, width=8, latent_dim=4, dct_components=4, heads=2),
            gru=RecurrentConfig(n_frames=60, hidden=8),
            cvae_rnn=RecurrentConfig(n_frames=60, hidden=8, latent_dim=4),
            train=_train_config(steps=10, batch_size=16, checkpoint_every=None),
            n_eval_windows=12,
            n_samples=10,
        )

    @classmethod
    def full(cls) -> ExperimentConfig:
        """The models whose numbers the chapter reports, sized for its budget on two CPU cores."""
        return cls(
            trajevae=TrajeVAEConfig(n_frames=60, width=32, latent_dim=8, dct_components=8, heads=2),
            gru=RecurrentConfig(n_frames=60, hidden=64),
            cvae_rnn=RecurrentConfig(n_frames=60, hidden=48, latent_dim=16),
            train=_train_config(steps=300, batch_size=32, checkpoint_every=100),
            n_eval_windows=48,
        )

    @classmethod
    def long(cls) -> ExperimentConfig:
        """A longer, larger run for the training command (``python -m motionlab.apps.training trajevae
        --config long``): 20 times the full profile's steps (8,000, batches of 64), TrajeVAE twice as wide
        (64, latent 16, 16 DCT components, 4 heads) and the baselines too; the same test windows as
        :meth:`full`."""
        return cls(
            trajevae=TrajeVAEConfig(n_frames=60, width=64, latent_dim=16, dct_components=16, heads=4),
            gru=RecurrentConfig(n_frames=60, hidden=128),
            cvae_rnn=RecurrentConfig(n_frames=60, hidden=96, latent_dim=16),
            train=_train_config(steps=8_000, batch_size=64, checkpoint_every=500),
            n_eval_windows=48,
        )

    def with_train_steps(self, steps: int) -> ExperimentConfig:
        """This config with every run trained for ``steps`` steps (the chapter's schedule, stretched)."""
        check_scalar(steps, "steps", "ExperimentConfig.with_train_steps", kind=numbers.Integral, minimum=1)
        return replace(self, train=_train_config(steps, self.train.batch_size, self.train.checkpoint_every))


def ladder(full: TrajeVAEConfig) -> dict[str, TrajeVAEConfig]:
    """The five rungs ``{name: config}`` of Table 4 built from ``full`` (architecture and loss weight shared).

    The last rung equals ``full`` with every switch on.
    """
    if not isinstance(full, TrajeVAEConfig):
        raise TypeError(f"ladder: full must be a TrajeVAEConfig, got {type(full).__name__}")
    return {
        name: replace(full, **{switch: index < rung for index, switch in enumerate(SWITCHES)})
        for rung, name in enumerate(RUNGS)
    }


def build_model(model: ModelConfig, seed: int = 0) -> nn.Module:
    """TrajeVAE for a :class:`TrajeVAEConfig`; the GRU (``latent_dim == 0``) or the CVAE-RNN for a
    :class:`RecurrentConfig`. Their weights are drawn from the model config's own ``seed`` (part of the cache
    key), so the training seed ``seed`` seeds only the batches and the loop."""
    if isinstance(model, TrajeVAEConfig):
        return TrajeVAE(model)
    return CVAERNN(model) if model.latent_dim > 0 else GRUCompletion(model)


def loss_function(model: ModelConfig) -> LossFn:
    """The model's training loss (see :mod:`motionlab.models.trajevae.losses`)."""
    if isinstance(model, TrajeVAEConfig):
        return trajevae_loss
    return cvae_rnn_loss if model.latent_dim > 0 else gru_loss


def _batches(batches: CompletionBatches, model: nn.Module) -> CompletionBatches:
    return batches


def validation_batches(model: ModelConfig, positions: Tensor, rotations: Tensor) -> CompletionBatches:
    """The validation batch source of a run of config ``model``: the clips ``positions`` ``(V, T, J, 3)``
    (``rotations`` ``(V, T, J, 4)``) all served in their order, the last batch possibly short, each with a
    joint mask drawn as in training (``model.keep_probability``; the loop seeds the generator identically
    every pass, so every pass sees the same masks) and never turned by the yaw augmentation."""
    return CompletionBatches(
        positions, rotations, False, model.keep_probability, shuffle=False, drop_last=False
    )


def completion_run(
    name: str,
    model: ModelConfig,
    train_config: TrainConfig,
    positions: Tensor,
    rotations: Tensor,
    val_clips: tuple[Tensor, Tensor] | None = None,
) -> Run:
    """The :class:`~motionlab.train.run.Run` of a completion model of config ``model`` on the training clips
    ``positions`` ``(N, T, J, 3)`` and ``rotations`` ``(N, T, J, 4)`` at the chapter's frame rate
    (:func:`~motionlab.models.trajevae.data.decimate`): masked batches (and, if the config says so, the yaw
    augmentation); the clips' fingerprint and the frame step are the cache key's data part.

    When ``train_config.val_every`` is set the run validates every ``val_every`` steps on
    :func:`validation_batches` of ``val_clips``, the validation clips ``(positions (V, T, J, 3), rotations
    (V, T, J, 4))`` at the same frame rate (the benchmark's val split: :func:`load_data`'s
    ``val_positions``, ``val_rotations``)."""
    if not isinstance(model, (TrajeVAEConfig, RecurrentConfig)):
        raise TypeError(
            f"completion_run: model must be a TrajeVAEConfig or RecurrentConfig, got {type(model).__name__}"
        )
    batches = CompletionBatches(positions, rotations, model.augment, model.keep_probability)
    val_batches = None
    if train_config.val_every is not None:
        if val_clips is None:
            raise ValueError(
                f"completion_run {name!r}: train_config validates every {train_config.val_every} steps, "
                "give it val_clips (positions, rotations) to validate on"
            )
        val_batches = partial(_batches, validation_batches(model, *val_clips))
    return Run(
        name,
        model,
        partial(build_model, model),
        partial(loss_function, model),
        partial(_batches, batches),
        train_config,
        {"clips": data_fingerprint(batches.positions), "frame_step": FRAME_STEP},
        val_batches=val_batches,
    )


def load_data(cfg: ExperimentConfig) -> CompletionData:
    """The benchmark at the chapter's frame rate: its training clips, ``cfg.n_eval_windows`` test windows
    spread evenly over the test split (so over all style modes), with their multimodal ground truth, and its
    validation clips (all of them)."""
    if not isinstance(cfg, ExperimentConfig):
        raise TypeError(f"load_data: cfg must be an ExperimentConfig, got {type(cfg).__name__}")
    bench = load_benchmark()
    all_test = completion_windows(decimate(bench.test.positions))
    pick = torch.linspace(0, all_test.shape[0] - 1, cfg.n_eval_windows).round().long()
    test_windows = all_test[pick]
    return CompletionData(
        train_positions=decimate(bench.train.positions),
        train_rotations=decimate(bench.train.rotations),
        test_windows=test_windows,
        test_action=bench.test.action[pick.numpy()],
        multimodal=multimodal_futures(test_windows),
        val_positions=decimate(bench.val.positions),
        val_rotations=decimate(bench.val.rotations),
    )


def runs(cfg: ExperimentConfig, data: CompletionData) -> dict[str, Run]:
    """The chapter's seven runs ``{name: run}`` in :data:`START_ORDER`: the rungs of :func:`ladder` (named by
    :data:`RUNGS`), ``"GRU"`` and ``"CVAE-RNN"``, each validating on ``data``'s validation clips."""
    if not isinstance(cfg, ExperimentConfig):
        raise TypeError(f"runs: cfg must be an ExperimentConfig, got {type(cfg).__name__}")
    models: dict[str, ModelConfig] = {**ladder(cfg.trajevae), "GRU": cfg.gru, "CVAE-RNN": cfg.cvae_rnn}
    val_clips = data.val_positions, data.val_rotations
    return {
        name: completion_run(
            CACHE_NAMES[name], models[name], cfg.train, data.train_positions, data.train_rotations, val_clips
        )
        for name in START_ORDER
    }


def sweep(
    name: str,
    model: nn.Module,
    windows: Tensor,
    multimodal: Sequence[np.ndarray],
    n_samples: int = N_SAMPLES,
) -> Sweep:
    """The DLow metrics of run ``name``'s model on ``windows`` ``(N, T, J * 3)`` for each number of given
    trajectories: Figure 6's k for :data:`FIGURE6_RUNS`, Table 1's for the others
    (:func:`~motionlab.models.trajevae.evaluate.sweep_given_joints`, ``n_samples`` samples, seed 0)."""
    ks = FIGURE6_KS if name in FIGURE6_RUNS else PAPER_KS
    return sweep_given_joints(model, windows, ks, n_samples, 0, multimodal)


def train_all(
    cfg: ExperimentConfig, data: CompletionData, processes: int | None = None
) -> dict[str, Trained[Sweep]]:
    """Train (or load) every run of :func:`runs` and :func:`sweep` each model, ``processes`` calls at a time.

    Returns:
        ``{name: Trained}`` in :data:`START_ORDER`; ``measured`` is the run's sweep ``{k: {metric: (mean,
        ci95)}}`` on ``data.test_windows``.
    """
    then = partial(sweep, windows=data.test_windows, multimodal=data.multimodal, n_samples=cfg.n_samples)
    return train_many(runs(cfg, data), then=then, processes=processes)


#: The chapter that trains this family, and its main run (the training command's default).
CHAPTER, DEFAULT_RUN = "07_masked_trajectory_completion", RUNGS[-1]


def measure(cfg: ExperimentConfig, data: CompletionData, name: str, model: nn.Module) -> dict[str, Any]:
    """The training command's measurement of run ``name``: the chapter's :func:`sweep`, DLow metrics per
    number ``k`` of given joint trajectories ``{"k=K": {metric: {"mean", "ci95"}}}``."""
    table = sweep(name, model, data.test_windows, data.multimodal, cfg.n_samples)
    return {
        "sweep": {
            f"k={k}": {metric: {"mean": mean, "ci95": half} for metric, (mean, half) in row.items()}
            for k, row in table.items()
        }
    }


def with_steps(cfg: ExperimentConfig, name: str, steps: int) -> ExperimentConfig:
    """``cfg`` with every run (``name`` too) trained for ``steps`` steps
    (:meth:`~ExperimentConfig.with_train_steps`)."""
    return cfg.with_train_steps(steps)


#: Given trajectories of :func:`schedule_check`'s decoding errors.
SCHEDULE_CHECK_KS: tuple[int, ...] = (0, 2, 4)


def schedule_check(
    cfg: ExperimentConfig, data: CompletionData, steps: int, reconstruction: str = "sum"
) -> dict[str, float]:
    """Train the full TrajeVAE of ``cfg`` for ``steps`` steps (the chapter's schedule stretched to them) with
    the given ``reconstruction`` term and measure the two gaps the chapter reports: how far the given joints
    of its completions stay from their trajectories, and how far the prior is from the posterior.

    Returns:
        ``follow``, ``follow_ci95``: the mean distance (m) between the given joints of ``N_SAMPLES``
        completions and the four trajectories of Table 1 (seed 5, as in the chapter's Table 5);
        ``decode_prior_k{k}``, ``decode_posterior_k{k}``, ``sigma_p_k{k}``, ``sigma_q_k{k}`` for ``k`` in
        :data:`SCHEDULE_CHECK_KS` (:func:`~motionlab.models.trajevae.evaluate.decoded_means_error`);
        ``apd_k0``, ``apd_k4`` and their ``_ci95``: APD with no trajectory and with four (seed ``k``);
        ``train_seconds``: the training time (as recorded in the checkpoint when loaded from the cache).
    """
    if not isinstance(cfg, ExperimentConfig):
        raise TypeError(f"schedule_check: cfg must be an ExperimentConfig, got {type(cfg).__name__}")
    check_scalar(steps, "steps", "schedule_check", kind=numbers.Integral, minimum=8)
    train = _train_config(steps, cfg.train.batch_size, cfg.train.checkpoint_every)
    model_cfg = replace(cfg.trajevae, reconstruction=reconstruction)
    name = f"trajevae_schedule_{reconstruction}_{steps}"
    val_clips = data.val_positions, data.val_rotations
    run = completion_run(name, model_cfg, train, data.train_positions, data.train_rotations, val_clips)
    model, result = run.train(progress=False)
    four = first_joints(4)
    start, trajectories = completion_task(data.test_windows, four)
    samples = complete(model, start, trajectories, N_SAMPLES, torch.Generator().manual_seed(5))
    follow, half = mean_ci(follow_error(samples, trajectories, four))
    out = {"follow": follow, "follow_ci95": half, "train_seconds": float(result.metrics["train_seconds"])}
    for k in (0, 4):  # diversity with no trajectory and with Table 1's four (seed k)
        start, trajectories = completion_task(data.test_windows, first_joints(k))
        samples = complete(model, start, trajectories, N_SAMPLES, torch.Generator().manual_seed(k))
        apd, apd_half = mean_ci(dlow_metrics(samples, data.test_windows, data.multimodal)["apd"])
        out[f"apd_k{k}"], out[f"apd_k{k}_ci95"] = apd, apd_half
    for k in SCHEDULE_CHECK_KS:
        measured = decoded_means_error(model, data.test_windows, k)
        out[f"decode_prior_k{k}"] = measured["prior mean"]
        out[f"decode_posterior_k{k}"] = measured["posterior mean"]
        out[f"sigma_p_k{k}"] = measured["sigma_p"]
        out[f"sigma_q_k{k}"] = measured["sigma_q"]
    return out
