"""Training everything the chapter needs on both cores of the course machine.

Every run uses one thread (small recurrent models do not gain from more), so :func:`train_chapter` runs
two at a time in the workers of the notebook's shared pool (:mod:`motionlab.train.parallel`). Runs are
seeded by their own configs, so a model's weights do not depend on which process trained it or in which order.
"""

from __future__ import annotations

from typing import NamedTuple

from torch import nn

from motionlab.evaluation.benchmark import Benchmark, benchmark_evaluator, cache_benchmark_evaluator
from motionlab.evaluation.evaluator import Evaluator
from motionlab.models.motion_cell.jobs import Job, chapter_jobs, job_is_cached, train_job, uses_classifier
from motionlab.models.motion_cell.preparation import PreparedData, prepare_training_data
from motionlab.models.motion_cell.settings import ChapterSettings
from motionlab.train import TrainResult
from motionlab.train.parallel import run_in_workers, shared_pool, submit


def _train_in_worker(job: Job, settings: ChapterSettings, data: PreparedData) -> float:
    """Body of a worker process: train ``job`` into the cache, return its training seconds."""
    classifier = benchmark_evaluator("conv", progress=False) if uses_classifier(job, settings) else None
    _, result = train_job(job, settings, data, classifier, progress=False)
    return result.metrics["train_seconds"]


class ChapterModels(NamedTuple):
    """Everything :func:`train_chapter` produces.

    Attributes:
        data: the denoised training data (:class:`PreparedData`); conv, gru: the frozen evaluators (the
            conv one is the classifier of eq. 24, the GRU one measures the results);
        models, results: the trained model and its :class:`TrainResult` of every job (loaded from the cache);
        trained: training seconds of the jobs that were trained now (empty when all came from the cache).
    """

    data: PreparedData
    conv: Evaluator
    gru: Evaluator
    models: dict[Job, nn.Module]
    results: dict[Job, TrainResult]
    trained: dict[Job, float]


def train_chapter(
    benchmark: Benchmark,
    settings: ChapterSettings,
    jobs: list[Job] | None = None,
    processes: int = 2,
    progress: bool | None = None,
) -> ChapterModels:
    """Train (or load) everything the chapter needs on the benchmark, using both cores of the course machine.

    Every run uses one thread, so ``processes`` run at a time in worker processes (the shared pool): the two
    evaluators train (or load) in the workers while this process trains the denoiser (on two threads: after
    chapter 03 the evaluators load from the cache at once); then the workers take
    the training jobs (default :func:`chapter_jobs`, longest first). Each run is seeded by
    its own config, so its weights do not depend on where or in which order it ran. At the end every model
    is loaded from the cache.
    """
    jobs = chapter_jobs() if jobs is None else jobs
    pool = shared_pool(processes)
    evaluators_ready = [submit(pool, cache_benchmark_evaluator, kind) for kind in ("conv", "gru")]
    data = prepare_training_data(benchmark.train, benchmark.val, settings, progress=progress)
    for future in evaluators_ready:  # the workers' classifier loss loads the conv evaluator from the cache
        future.result()
    pending = [job for job in jobs if not job_is_cached(job, settings, data)]
    trained = dict(
        zip(pending, run_in_workers(_train_in_worker, [(job, settings, data) for job in pending], processes))
    )
    conv, gru = benchmark_evaluator("conv"), benchmark_evaluator("gru")
    loaded = {job: train_job(job, settings, data, conv, progress=progress) for job in jobs}
    return ChapterModels(
        data,
        conv,
        gru,
        {job: m for job, (m, _) in loaded.items()},
        {job: r for job, (_, r) in loaded.items()},
        trained,
    )
