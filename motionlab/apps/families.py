"""The model families the training command knows: each chapter's experiment, its data sets and evaluation.

A :class:`Family` ties the command (:mod:`motionlab.apps.training`) to one chapter's
``motionlab.models.<family>.experiment`` module, which it uses as the chapter does: the same
``ExperimentConfig`` (``quick()``, ``full()`` or the longer ``long()``), the same ``runs(cfg, ...)`` (each a
:class:`~motionlab.train.many.Run` that trains through the checkpoint cache) and the chapter's own
evaluation of a trained model. Heavy modules are imported only when a family is used, so ``--help`` is quick.

Data sets: every family trains on the course benchmark (``benchmark``), the synthetic data of the chapters.
A data set is a :class:`DataSet` whose ``load(cfg)`` returns what the family's ``runs`` take; adding one (for
instance ODMO on the CMU MoCap data) is one entry in the family's :attr:`Family.datasets`.
"""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from torch import nn


@dataclass(frozen=True)
class DataSet:
    """A data set a family can train on.

    Attributes:
        description: one line for ``--help``.
        load: ``load(cfg) -> prepared data`` (what the family's runs and evaluation take).
        evaluate: ``evaluate(cfg, data, run_name, model)`` for this data set, when it differs from the
            family's (``None``: the family's).
        reads_folder: ``load`` reads the folder of clips given as ``--data PATH`` (``load(cfg, path)``).
        config: ``config(profile) -> cfg``, the experiment config for this data (``None``: the family's).
        runs: ``runs(cfg, data) -> {name: Run}`` for this data (``None``: the family's).
    """

    description: str
    load: Callable[..., Any]
    evaluate: Callable[[Any, Any, str, nn.Module], dict[str, Any]] | None = None
    reads_folder: bool = False
    config: Callable[[str], Any] | None = None
    runs: Callable[[Any, Any], dict[str, Any]] | None = None


@dataclass(frozen=True)
class Family:
    """One model family: its chapter's experiment module, default run, data sets and evaluation.

    Attributes:
        name: the command's FAMILY argument; chapter: the notebook that trains it.
        module: the experiment module (``ExperimentConfig``, ``runs``).
        default_run: the run trained when ``--run`` is not given (the chapter's main model).
        train_field: the name of a run's :class:`~motionlab.train.TrainConfig` attribute (``--seed`` sets
            its ``seed``, which seeds the initial weights and the batches).
        steps: ``steps(cfg, run_name, n) -> cfg`` with the run's number of optimiser steps set to ``n``.
        runs: ``runs(cfg, data) -> {name: Run}``.
        evaluate: ``evaluate(cfg, data, run_name, model) -> JSON-ready dict`` (the chapter's measurements).
        datasets: ``{name: DataSet}``; the first is the default.
    """

    name: str
    chapter: str
    module: str
    default_run: str
    train_field: str
    steps: Callable[[Any, str, int], Any]
    runs: Callable[[Any, Any], dict[str, Any]]
    evaluate: Callable[[Any, Any, str, nn.Module], dict[str, Any]]
    datasets: dict[str, DataSet] = field(default_factory=dict)

    def experiment(self) -> Any:
        """The family's experiment module."""
        return importlib.import_module(self.module)

    def config(self, profile: str) -> Any:
        """The chapter's ``ExperimentConfig`` of ``profile`` (``quick``, ``full`` or ``long``)."""
        return getattr(self.experiment().ExperimentConfig, profile)()


def jsonable(value: Any) -> Any:
    """``value`` as plain JSON types: intervals as ``{"mean", "ci95"}``, tensors and arrays as lists,
    dataclasses and named tuples as dicts, dict keys as strings."""
    if hasattr(value, "half_width") and hasattr(value, "mean"):  # motionlab.metrics.Interval
        return {"mean": float(value.mean), "ci95": float(value.half_width)}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, tuple) and hasattr(value, "_asdict"):
        return {key: jsonable(item) for key, item in value._asdict().items()}
    if isinstance(value, dict):
        return {str(key): jsonable(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(item) for item in value]
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return repr(value)


def _interval(values: Any) -> dict[str, float]:
    from motionlab.metrics import mean_ci

    mean, half = mean_ci(values)
    return {"mean": float(mean), "ci95": float(half)}


# --- chapter 03: VAEs --------------------------------------------------------------------------------------
CLIP_RUNS = ("cvae", "cvae_no_anneal")


def _vae_data(cfg: Any) -> int:
    from motionlab.evaluation.benchmark import load_benchmark

    return len(load_benchmark().train.action_names)


def _vae_runs(cfg: Any, n_actions: int) -> dict[str, Any]:
    from motionlab.models.vae.experiment import runs

    return runs(cfg, n_actions)


def _vae_steps(cfg: Any, run: str, n: int) -> Any:
    return replace(cfg, clip_steps=n) if run in CLIP_RUNS else replace(cfg, pose_steps=n)


def _vae_evaluate(cfg: Any, n_actions: int, run: str, model: nn.Module) -> dict[str, Any]:
    """Clip CVAEs: the chapter's sample metrics (section 2); pose models: the held-out negative ELBO."""
    import torch

    from motionlab.evaluation.benchmark import benchmark_evaluator
    from motionlab.models.vae.evaluate import sample_clip_metrics
    from motionlab.models.vae.losses import elbo_terms

    if run in CLIP_RUNS:
        evaluator = benchmark_evaluator("gru", progress=False)
        codec, train, _ = cfg.clips.load()
        reference = evaluator.features(codec.to_positions(train.features))
        return {"samples": jsonable(sample_clip_metrics(model, codec, evaluator, reference, cfg, seed=10))}
    with torch.no_grad():
        terms = elbo_terms(model, cfg.poses.load().test, generator=torch.Generator().manual_seed(0))
    return {"test_" + name: float(terms[name]) for name in ("recon", "kl")}


# --- chapter 04: the Motion Cell ---------------------------------------------------------------------------
@dataclass(frozen=True)
class _MotionCellData:
    prepared: Any
    evaluator: Any
    reference: Any


def _motion_cell_data(cfg: Any) -> _MotionCellData:
    from motionlab.evaluation.benchmark import load_benchmark, prepare_evaluators
    from motionlab.models.motion_cell.experiment import prepare_training_data

    benchmark = load_benchmark()
    judges = prepare_evaluators(("conv", "gru"), processes=1).result(progress=False)
    prepared = prepare_training_data(benchmark.train, benchmark.val, cfg)
    gru = judges["gru"].model
    return _MotionCellData(prepared, gru, gru.features(benchmark.train.positions))


def _motion_cell_runs(cfg: Any, data: _MotionCellData) -> dict[str, Any]:
    from motionlab.models.motion_cell.experiment import runs

    return runs(cfg, data.prepared)


def _motion_cell_steps(cfg: Any, run: str, n: int) -> Any:
    return replace(cfg, representation_steps=n) if run.startswith("output_") else replace(cfg, steps=n)


def _motion_cell_evaluate(cfg: Any, data: _MotionCellData, run: str, model: nn.Module) -> dict[str, Any]:
    """The chapter's Table 2 row (IS, FID, accuracy, diversity); the output-head runs have none."""
    from motionlab.models.motion_cell.experiment import table_row

    row = table_row(run, model, data.evaluator, data.reference, cfg.n_per_combination, cfg.n_repeats)
    if row is None:
        return {"table2": None, "note": f"{run!r} is not a row of the chapter's Table 2"}
    return {"table2": {key: {"mean": mean, "ci95": half} for key, (mean, half) in row.row.items()}}


# --- chapter 06: MoGlow -------------------------------------------------------------------------------------
def _moglow_data(cfg: Any) -> Any:
    from motionlab.evaluation.benchmark import load_benchmark
    from motionlab.models.moglow.experiment import load_data

    return load_data(cfg, load_benchmark())


def _moglow_runs(cfg: Any, data: Any) -> dict[str, Any]:
    from motionlab.models.moglow.experiment import runs

    return runs(cfg, data)


def _moglow_steps(cfg: Any, run: str, n: int) -> Any:
    from motionlab.models.moglow.experiment import BASELINE

    return replace(cfg, baseline_train_steps=n) if run == BASELINE else replace(cfg, moglow_train_steps=n)


def _moglow_evaluate(cfg: Any, data: Any, run: str, model: nn.Module) -> dict[str, Any]:
    """The chapter's held-out NLL per frame and the control test's mismatch on the zero-latent path."""
    import torch

    from motionlab.evaluation.benchmark import load_benchmark
    from motionlab.models import moglow as mg
    from motionlab.models.moglow.evaluate import control_test

    benchmark = load_benchmark()
    test_set = mg.select_actions(benchmark.test, cfg.data.actions)
    test_raw = mg.clip_features(benchmark.test, cfg.data, augment=False)
    out: dict[str, Any] = {
        "test_nll_per_frame": _interval(mg.held_out_nll_per_window(model, data.test).numpy())
    }
    names = [str(name) for name in test_set.action_names]
    history = model.cfg.history
    commands = control_test(test_raw, test_set.action, names, cfg.n_commands, history, cfg.piece_seconds)
    try:
        motion = mg.generate_motion(
            model, data.scalers, commands.control, commands.seed, 0.0, torch.Generator().manual_seed(0)
        )
    except ValueError as error:  # a diverging sample is reported, not hidden
        out["control_mismatch_zero_latent"] = f"generation diverged: {error}"
        return out
    mismatch = mg.control_mismatch(motion.pose[:, history:], motion.control[:, history:])
    out["control_mismatch_zero_latent"] = _interval(mismatch.numpy())
    return out


# --- chapter 07: TrajeVAE ----------------------------------------------------------------------------------
def _trajevae_data(cfg: Any) -> Any:
    from motionlab.models.trajevae.experiment import load_data

    return load_data(cfg)


def _trajevae_runs(cfg: Any, data: Any) -> dict[str, Any]:
    from motionlab.models.trajevae.experiment import runs

    return runs(cfg, data)


def _trajevae_steps(cfg: Any, run: str, n: int) -> Any:
    return cfg.with_train_steps(n)


def _trajevae_evaluate(cfg: Any, data: Any, run: str, model: nn.Module) -> dict[str, Any]:
    """The chapter's sweep: DLow metrics per number of given joint trajectories ``k``."""
    from motionlab.models.trajevae.experiment import sweep

    table = sweep(run, model, data.test_windows, data.multimodal)
    return {
        "sweep": {
            f"k={k}": {m: {"mean": mean, "ci95": half} for m, (mean, half) in row.items()}
            for k, row in table.items()
        }
    }


# --- chapter 10: ODMO on the CMU motion capture ------------------------------------------------------------
@dataclass(frozen=True)
class _RealODMOData:
    train: Any
    evaluator: Any
    protocol: Any


def _odmo_cmu_config(profile: str) -> Any:
    from motionlab.models.odmo.experiment import RealExperimentConfig

    return getattr(RealExperimentConfig, profile)()


def _odmo_cmu(cfg: Any, folder: Path | None = None) -> _RealODMOData:
    """Chapter 10's data: the CMU clips (floors levelled, stratified split), ODMO's windows of the training
    clips, the real-data evaluator (chapter 10's sizes) and Table 2's protocol. ``folder``: a downloaded
    Action2Motion folder (``pose_clip.csv`` and one ``.npy`` per clip) instead of the compact copy."""
    from motionlab import config
    from motionlab.evaluation import real
    from motionlab.models.odmo.data import prepare_real

    bench = real.load_real_benchmark(cfg.n_clips, source=folder)
    evaluator_cfg = real.RealEvaluatorConfig(
        steps=config.choose(quick=20, full=250), hidden=config.choose(quick=32, full=128)
    )
    evaluator, _ = real.RealEvaluatorRun(bench.train, evaluator_cfg).train(progress=False)
    protocol = real.Protocol.build(evaluator, bench.train, cfg.n_per_set, cfg.n_sets, cfg.window)
    train = prepare_real(bench.train, cfg.window, cfg.frame_stride, cfg.draws, cfg.seed)
    return _RealODMOData(train, evaluator, protocol)


def _odmo_cmu_runs(cfg: Any, data: _RealODMOData) -> dict[str, Any]:
    from motionlab.models.odmo.experiment import real_runs

    return real_runs(cfg, data.train)


def _odmo_cmu_evaluate(cfg: Any, data: _RealODMOData, run: str, model: nn.Module) -> dict[str, Any]:
    """Chapter 10's Table 2 row of the variant (accuracy, FID, diversity, multimodality)."""
    from motionlab.models.odmo.experiment import measure_real

    return {"table2": jsonable(measure_real(run, model, data.train, data.evaluator, data.protocol, cfg).row)}


# --- chapter 08: ODMO ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _ODMOData:
    train: Any
    reference: Any


def _odmo_benchmark(cfg: Any) -> _ODMOData:
    from motionlab.evaluation.benchmark import benchmark_evaluator, load_benchmark
    from motionlab.models.odmo import evaluate, prepare

    benchmark = load_benchmark()
    train = prepare(benchmark.train, cfg.frame_stride)
    evaluator = benchmark_evaluator("gru", progress=False)
    return _ODMOData(
        train, evaluate.Reference.build(evaluator, benchmark.train, benchmark.val, train.floor_clearance)
    )


def _odmo_runs(cfg: Any, data: _ODMOData) -> dict[str, Any]:
    from motionlab.models.odmo.experiment import runs

    return runs(cfg, data.train)


def _odmo_steps(cfg: Any, run: str, n: int) -> Any:
    return replace(cfg, steps=n)


def _odmo_evaluate(cfg: Any, data: _ODMOData, run: str, model: nn.Module) -> dict[str, Any]:
    """The chapter's measurements of the variant: Tables 1-2 rows, Tables 3-4 where the chapter has them."""
    from motionlab.models.odmo.experiment import measure_variant

    measured = measure_variant(run, model, data.train, data.reference, cfg)
    return {
        "rows": jsonable(measured.rows),
        "mode_homogeneity": jsonable(measured.homogeneity),
        "style_purity": jsonable(measured.purity),
        "end_point": jsonable(measured.end_point),
    }


BENCHMARK = "the course benchmark: the chapters' synthetic motion data (6 actions x 2 styles x 2 bodies)"

FAMILIES: dict[str, Family] = {
    "vae": Family(
        "vae",
        "03_variational_autoencoders",
        "motionlab.models.vae.experiment",
        "cvae",
        "train_config",
        _vae_steps,
        _vae_runs,
        _vae_evaluate,
        {"benchmark": DataSet(BENCHMARK, _vae_data)},
    ),
    "motion_cell": Family(
        "motion_cell",
        "04_motion_cell",
        "motionlab.models.motion_cell.experiment",
        "mcell",
        "train_config",
        _motion_cell_steps,
        _motion_cell_runs,
        _motion_cell_evaluate,
        {"benchmark": DataSet(BENCHMARK, _motion_cell_data)},
    ),
    "moglow": Family(
        "moglow",
        "06_moglow",
        "motionlab.models.moglow.experiment",
        "MoGlow p=0.95",
        "train_cfg",
        _moglow_steps,
        _moglow_runs,
        _moglow_evaluate,
        {"benchmark": DataSet(BENCHMARK, _moglow_data)},
    ),
    "trajevae": Family(
        "trajevae",
        "07_masked_trajectory_completion",
        "motionlab.models.trajevae.experiment",
        "+ masked future poses",
        "train_config",
        _trajevae_steps,
        _trajevae_runs,
        _trajevae_evaluate,
        {"benchmark": DataSet(BENCHMARK, _trajevae_data)},
    ),
    "odmo": Family(
        "odmo",
        "08_contrastive_mode_discovery",
        "motionlab.models.odmo.experiment",
        "ODMO",
        "training",
        _odmo_steps,
        _odmo_runs,
        _odmo_evaluate,
        {
            "benchmark": DataSet(BENCHMARK, _odmo_benchmark),
            "cmu": DataSet(
                "chapter 10: the CMU MoCap clips of data_real/ (Action2Motion's 7 classes; "
                "RealExperimentConfig); --data FOLDER reads a downloaded Action2Motion folder instead",
                _odmo_cmu,
                evaluate=_odmo_cmu_evaluate,
                reads_folder=True,
                config=_odmo_cmu_config,
                runs=_odmo_cmu_runs,
            ),
        },
    ),
}
