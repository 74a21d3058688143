"""Chapter 03's experiment: its sizes per profile, its five named training runs, and training them all.

Every model is an :class:`~motionlab.models.vae.model.MLPVAE` trained on
:func:`~motionlab.models.vae.losses.elbo_loss` through :func:`motionlab.train.train_or_load` with the same
optimiser settings: the pose models on standardised pose vectors, the clip CVAEs on standardised 2-second
MoGlow windows (:mod:`~motionlab.models.vae.data`).

The likelihood variance of the clip CVAE is the weighting of ODMO's released code in disguise: the
code minimises, per clip, the squared error averaged over the D features of a frame and summed over
frames, plus the KL with weight 1. That equals the Gaussian negative log-likelihood with
sigma_x^2 = D / 2 (up to a constant), which is what :meth:`ExperimentConfig.clip_model` uses. (The
paper's eq. 3 sums over the features as well, which with its eq. 1 is sigma_x^2 = 1 in its units.)
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import torch
from torch import nn

from motionlab import config
from motionlab.evaluation.benchmark import benchmark_evaluator, evaluator_runs, load_benchmark
from motionlab.evaluation.evaluator import data_fingerprint
from motionlab.models.vae.data import CLIP_FEATURES, POSE_FEATURES, BenchmarkClips, BenchmarkPoses
from motionlab.models.vae.evaluate import sample_clip_metrics
from motionlab.models.vae.losses import elbo_loss, elbo_terms, kl_weight
from motionlab.models.vae.model import MLPVAE, VAEConfig
from motionlab.train import TensorBatches, TrainConfig, build_seeded, validation_every
from motionlab.train.many import Trained, train_many
from motionlab.train.run import Run, given
from motionlab.validation import check_scalar, integer, real


@dataclass(frozen=True)
class ExperimentConfig(config.ProfileConfig):
    """The chapter's sizes and budgets for one profile (:meth:`quick`: every code path in seconds;
    :meth:`full`: the reported runs).

    Attributes:
        pose_every: take every this many frames of a clip as a pose.
        pose_latent, pose_hidden, pose_steps: the pose models' latent size, width and training steps.
        pose_obs_var: sigma_x^2 of the pose VAEs' likelihood (standardised units).
        small_prior_var: sigma_p^2 of the small-prior pose VAE (appendix 08a), the variance of its full
            N(0, sigma_p^2 I) prior (ODMO's number, 0.05; ODMO's own term constrains only the posterior
            variances, towards it).
        clip_length, clip_stride: window length and hop in frames (30 fps).
        clip_latent, clip_hidden, clip_steps: the clip CVAEs' latent size, width and training steps.
        tiny_steps: training steps of the tiny CVAE the chapter writes in the notebook (its live run; the
            package's CVAEs train ``clip_steps``).
        batch_size, lr, grad_clip, seed: for every run.
        per_action, n_repeats: evaluation sample sets (clips per action) and how many of them.
    """

    pose_every: int = integer(10, minimum=1)
    pose_latent: int = integer(8, minimum=1)
    pose_hidden: int = integer(128, minimum=1)
    pose_steps: int = integer(800, minimum=1)
    pose_obs_var: float = real(0.1, above=0)
    small_prior_var: float = real(0.05, above=0)
    clip_length: int = integer(60, minimum=1)
    clip_stride: int = integer(15, minimum=1)
    clip_latent: int = integer(16, minimum=1)
    clip_hidden: int = integer(128, minimum=1)
    clip_steps: int = integer(2400, minimum=1)
    tiny_steps: int = integer(600, minimum=1)
    batch_size: int = integer(64, minimum=1)
    lr: float = real(2e-3, above=0)
    grad_clip: float = real(1.0, above=0)
    seed: int = config.seed_field()
    per_action: int = integer(50, minimum=1)
    n_repeats: int = integer(10, minimum=2)

    @classmethod
    def quick(cls) -> ExperimentConfig:
        """Every code path in seconds: small widths, few steps, few evaluation samples."""
        return cls(
            pose_every=20,
            pose_hidden=32,
            pose_steps=30,
            clip_hidden=32,
            clip_steps=30,
            tiny_steps=30,
            per_action=10,
            n_repeats=3,
        )

    @classmethod
    def long(cls) -> ExperimentConfig:
        """A longer, larger run for the training command (``python -m motionlab.apps.training vae --config
        long``): longer runs (16,000 steps for the pose models, 20 times the full profile's; 12,000 for the
        clip CVAEs, 5 times) at twice the width (256); data and evaluation as in :meth:`full`."""
        return cls(pose_hidden=256, pose_steps=16_000, clip_hidden=256, clip_steps=12_000)

    def pose_model(self, variational: bool = True, prior_var: float = 1.0) -> VAEConfig:
        """An unconditional pose (V)AE on 64-number pose vectors; ``prior_var`` is sigma_p^2."""
        check_scalar(
            prior_var, "prior_var", "ExperimentConfig.pose_model", minimum=0.0, include_minimum=False
        )
        return VAEConfig(
            (POSE_FEATURES,),
            latent_dim=self.pose_latent,
            hidden=self.pose_hidden,
            variational=variational,
            obs_logvar=math.log(self.pose_obs_var),
            prior_logvar=math.log(prior_var),
        )

    def clip_model(self, n_actions: int, prior_var: float = 1.0) -> VAEConfig:
        """The action-conditioned clip VAE: windows ``(clip_length, 67)``, sigma_x^2 = 67 / 2 (the
        weighting of ODMO's released code)."""
        where = "ExperimentConfig.clip_model"
        check_scalar(n_actions, "n_actions", where, kind=numbers.Integral, minimum=1)
        check_scalar(prior_var, "prior_var", where, minimum=0.0, include_minimum=False)
        return VAEConfig(
            (self.clip_length, CLIP_FEATURES),
            latent_dim=self.clip_latent,
            hidden=self.clip_hidden,
            n_classes=n_actions,
            obs_logvar=math.log(CLIP_FEATURES / 2),
            prior_logvar=math.log(prior_var),
        )

    def train_config(self, steps: int, anneal: bool) -> TrainConfig:
        """AdamW for ``steps`` steps; the KL weight ramps up over the first half (``anneal``) or stays 1; 40
        validation passes (:func:`~motionlab.train.validation_every`) over the run."""
        return TrainConfig(
            steps=steps,
            batch_size=self.batch_size,
            lr=self.lr,
            grad_clip=self.grad_clip,
            seed=self.seed,
            schedules={"beta": kl_weight(steps, anneal)},
            val_every=validation_every(steps),  # the held-out curve: 40 passes over the validation data
        )

    @property
    def poses(self) -> BenchmarkPoses:
        """The pose data of the benchmark at this config's ``pose_every``."""
        return BenchmarkPoses(self.pose_every)

    @property
    def clips(self) -> BenchmarkClips:
        """The benchmark's windows of this config's ``clip_length`` and ``clip_stride``."""
        return BenchmarkClips(self.clip_length, self.clip_stride)


def training_batches(data: BenchmarkPoses | BenchmarkClips, model: nn.Module) -> TensorBatches:
    """The batches of a run on ``data``: its training inputs, with the actions for the clip CVAEs."""
    x, label = data.training_inputs()
    return TensorBatches((x,) if label is None else (x, label))


def validation_batches(data: BenchmarkPoses | BenchmarkClips, model: nn.Module) -> TensorBatches:
    """The validation batches of a run on ``data``: its validation inputs (the benchmark's val split, prepared
    like the training inputs), every one in its order, with the actions for the clip CVAEs."""
    x, label = data.validation_inputs()
    return TensorBatches((x,) if label is None else (x, label), shuffle=False, drop_last=False)


def vae_run(
    name: str, model: VAEConfig, train_config: TrainConfig, data: BenchmarkPoses | BenchmarkClips
) -> Run:
    """The :class:`~motionlab.train.run.Run` of an :class:`MLPVAE` of config ``model`` on ``data`` (built
    where the run trains; its fingerprint is the cache key's data part), its weights drawn from
    ``train_config.seed``; it validates on ``data``'s validation inputs every ``train_config.val_every`` steps
    when that is set."""
    x, label = data.training_inputs()
    return Run(
        name,
        model,
        partial(build_seeded, partial(MLPVAE, model)),
        given(elbo_loss),
        partial(training_batches, data),
        train_config,
        {"x": data_fingerprint(x), "label": None if label is None else data_fingerprint(label.float())},
        val_batches=None if train_config.val_every is None else partial(validation_batches, data),
    )


def runs(cfg: ExperimentConfig, n_actions: int) -> dict[str, Run]:
    """The chapter's runs by name, the clip CVAEs (the longest) first.

    ``cvae`` and ``cvae_no_anneal`` (chapter 03, sections 3 and 4: the KL weight ramped, or 1 from the first
    step), ``pose_ae`` and ``pose_vae`` (appendix 03a) and ``pose_vae_small_prior`` (appendix 08a: sigma_p^2 =
    ``cfg.small_prior_var``). ``n_actions`` is the number of actions the CVAEs are conditioned on.
    """
    clip_cvae = cfg.clip_model(n_actions)
    clip_steps, pose_steps = cfg.clip_steps, cfg.pose_steps
    return {
        "cvae": vae_run("vae03_cvae", clip_cvae, cfg.train_config(clip_steps, anneal=True), cfg.clips),
        "cvae_no_anneal": vae_run(
            "vae03_cvae_no_anneal", clip_cvae, cfg.train_config(clip_steps, anneal=False), cfg.clips
        ),
        "pose_ae": vae_run(
            "vae03_pose_ae", cfg.pose_model(variational=False), cfg.train_config(pose_steps, True), cfg.poses
        ),
        "pose_vae": vae_run(
            "vae03_pose_vae", cfg.pose_model(), cfg.train_config(pose_steps, True), cfg.poses
        ),
        "pose_vae_small_prior": vae_run(
            "vae03_pose_vae_small_prior",
            cfg.pose_model(prior_var=cfg.small_prior_var),
            cfg.train_config(pose_steps, True),
            cfg.poses,
        ),
    }


def train_all(
    cfg: ExperimentConfig, n_actions: int, processes: int | None = None, progress: bool | None = None
) -> dict[str, Trained]:
    """Train (or load from the cache) every run of :func:`runs` on ``processes`` worker processes, the
    benchmark's two evaluators after them on the same workers (this is the first chapter that needs them;
    :func:`~motionlab.evaluation.benchmark.benchmark_evaluator` loads them); ``{name: Trained}`` of the
    chapter's runs, every model loaded here."""
    return train_many(
        runs(cfg, n_actions), processes=processes, progress=progress, alongside=evaluator_runs()
    )


#: The chapter that trains this family, and its main run (the training command's default).
CHAPTER, DEFAULT_RUN = "03_variational_autoencoders", "cvae"

#: The runs on clip windows (the others model single poses).
CLIP_RUNS = ("cvae", "cvae_no_anneal")


def load_data(cfg: ExperimentConfig) -> int:
    """What :func:`runs` needs besides ``cfg``: the number of actions the clip CVAEs are conditioned on (the
    benchmark's; each run loads its poses or clips where it trains)."""
    return len(load_benchmark().train.action_names)


def measure(cfg: ExperimentConfig, n_actions: int, name: str, model: nn.Module) -> dict[str, Any]:
    """The training command's measurement of run ``name``: for the clip CVAEs the chapter's sample metrics
    (section 3), for the pose models the held-out reconstruction and KL terms of the negative ELBO."""
    if name in CLIP_RUNS:
        evaluator = benchmark_evaluator("gru", progress=False)
        codec, train, _ = cfg.clips.load()
        reference = evaluator.features(codec.to_positions(train.features))
        return {"samples": sample_clip_metrics(model, codec, evaluator, reference, cfg, seed=10)}
    with torch.no_grad():
        terms = elbo_terms(model, cfg.poses.load().test, generator=torch.Generator().manual_seed(0))
    return {"test_" + term: float(terms[term]) for term in ("recon", "kl")}


def with_steps(cfg: ExperimentConfig, name: str, steps: int) -> ExperimentConfig:
    """``cfg`` with run ``name`` trained for ``steps`` steps (the clip CVAEs share ``clip_steps``, the pose
    models ``pose_steps``)."""
    return replace(cfg, clip_steps=steps) if name in CLIP_RUNS else replace(cfg, pose_steps=steps)
