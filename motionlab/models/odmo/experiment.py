"""The chapter's experiment on both cores: train every variant and measure it as soon as it has trained.

Seven variants on two cores leave one core idle while the last one trains. :func:`train_and_measure`
chains every variant's training with its measurements (:func:`~motionlab.train.parallel.run_paired`):
its samplers (:class:`~motionlab.models.odmo.sampler.ODMOSampler`), its rows of Tables 1-2 and, if the
:class:`MeasurePlan` asks, its Table 3 (mode homogeneity) and Table 4 (end-point control) rows. The
measurements of the variants that are done fill the idle core. A measurement loads its model from the
checkpoint cache and every table is seeded by the plan alone, so the numbers equal in-process calls of
:mod:`motionlab.models.odmo.evaluate`, wherever and whenever they ran.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

from motionlab.metrics import Interval
from motionlab.models.odmo.config import ODMOConfig
from motionlab.models.odmo.data import ODMOData
from motionlab.models.odmo.evaluate import Reference, end_point_control, metric_row, mode_homogeneity_interval
from motionlab.models.odmo.model import ODMO
from motionlab.models.odmo.sampler import ODMOSampler, encode_clips
from motionlab.models.odmo.training import ODMOTraining, odmo_data_config, run_name, train_odmo
from motionlab.train import TrainResult, is_cached
from motionlab.train.parallel import run_paired


@dataclass(frozen=True)
class MeasurePlan:
    """What to measure of which variant, and with how many samples.

    Attributes:
        n_per_class, n_sets: clips per class in a sample set of Tables 1-2, and the sets per row;
        n_per_mode: clips per discovered mode in a sample set of Table 3 (also ``n_sets`` sets);
        n_codes, n_end_points: Table 4's codes per class and end points per code.
        prior_sampled: variants whose table sampler draws codes from the prior (the standard VAE); the
            others sample their discovered modes.
        conventional: variants that also get a row with the single-Gaussian sampler, named ``<variant>_conv``.
        homogeneity, end_point: the variants of Table 3 and of Table 4.
    """

    n_per_class: int
    n_sets: int
    n_per_mode: int
    n_codes: int
    n_end_points: int
    prior_sampled: tuple[str, ...] = ("standard VAE",)
    conventional: tuple[str, ...] = ("ODMO",)
    homogeneity: tuple[str, ...] = ("ODMO", "ODMO (paper's prior term)", "standard VAE")
    end_point: tuple[str, ...] = ("ODMO", "-r_e", "-L_cons", "-L_traj")


class Measured(NamedTuple):
    """One variant's measurements.

    Attributes:
        samplers: ``{"table": ..., "modes": ...}`` (the same sampler for variants that sample their modes),
            plus ``"conventional"`` if the plan asks for it.
        rows: Tables 1-2 rows ``{row name: {metric: Interval}}`` (the variant, and ``<variant>_conv``).
        homogeneity: Table 3's interval, or ``None``; end_point: Table 4's row, or ``None``.
    """

    samplers: dict[str, ODMOSampler]
    rows: dict[str, dict[str, Interval]]
    homogeneity: Interval | None
    end_point: dict[str, Interval] | None


def measure_variant(
    variant: str, model: ODMO, data: ODMOData, reference: Reference, plan: MeasurePlan
) -> Measured:
    """Build the samplers of a trained ``model`` and measure what ``plan`` asks of ``variant``."""
    codes = encode_clips(model, data)  # once, for every sampler of the variant
    modes = ODMOSampler.from_codes(model, codes, data, kind="modes")
    samplers = {
        "table": ODMOSampler.from_codes(model, codes, data, kind="prior")
        if variant in plan.prior_sampled
        else modes,
        "modes": modes,
    }
    rows = {variant: metric_row(reference, samplers["table"], plan.n_per_class, plan.n_sets)}
    if variant in plan.conventional:
        samplers["conventional"] = ODMOSampler.from_codes(model, codes, data, kind="conventional")
        rows[f"{variant}_conv"] = metric_row(
            reference, samplers["conventional"], plan.n_per_class, plan.n_sets
        )
    homogeneity = (
        mode_homogeneity_interval(reference, modes, plan.n_per_mode, plan.n_sets)
        if variant in plan.homogeneity
        else None
    )
    end_point = (
        end_point_control(reference, modes, plan.n_codes, plan.n_end_points)
        if variant in plan.end_point
        else None
    )
    return Measured(samplers, rows, homogeneity, end_point)


def _train_in_worker(variant: str, cfg: ODMOConfig, data: ODMOData, training: ODMOTraining) -> float:
    """Body of a worker call: train one variant into the checkpoint cache, return its training seconds."""
    _, result = train_odmo(variant, cfg, data, training, progress=False)
    return result.metrics["train_seconds"]


def _measure_in_worker(
    variant: str,
    cfg: ODMOConfig,
    data: ODMOData,
    training: ODMOTraining,
    reference: Reference,
    plan: MeasurePlan,
) -> Measured:
    """Body of a worker call: load a trained variant from the cache (its chain trained it) and measure it."""
    model, _ = train_odmo(variant, cfg, data, training, progress=False)
    return measure_variant(variant, model, data, reference, plan)


def train_and_measure(
    configs: dict[str, ODMOConfig],
    data: ODMOData,
    training: ODMOTraining,
    reference: Reference,
    plan: MeasurePlan,
    processes: int = 2,
) -> tuple[dict[str, ODMO], dict[str, TrainResult], dict[str, float], dict[str, Measured]]:
    """Train (or load) every ``{variant: config}`` and measure it, ``processes`` calls at a time.

    Trainings start in the order of ``configs`` (put one whose measurement is short last). Returns the
    models and training results (loaded here from the cache), the training seconds of the variants trained
    now, and every variant's :class:`Measured`; all keyed like ``configs``.
    """
    trainings = {
        variant: (_train_in_worker, (variant, cfg, data, training))
        for variant, cfg in configs.items()
        if not is_cached(run_name(variant), cfg, training.train_config(), odmo_data_config(data))
    }
    measurements = {
        variant: (_measure_in_worker, (variant, cfg, data, training, reference, plan))
        for variant, cfg in configs.items()
    }
    seconds, measured = run_paired(trainings, measurements, processes)
    models, results = {}, {}
    for variant, cfg in configs.items():
        models[variant], results[variant] = train_odmo(variant, cfg, data, training)
    return models, results, seconds, measured
