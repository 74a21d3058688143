"""The one training entry point: runs trained in workers, measured there, loaded here, identical weights."""

from __future__ import annotations

import functools
from pathlib import Path

import pytest
import torch
from torch import nn

from motionlab.train import TensorBatches, TrainConfig, build_seeded
from motionlab.train.many import Trained, train_many, train_meanwhile
from motionlab.train.run import Run, given

CFG = TrainConfig(steps=12, batch_size=8, lr=1e-2, checkpoint_every=None)


@pytest.fixture(autouse=True)
def own_build(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Workers receive the caller's MOTIONLAB_* settings with every call, so they use this test's cache.
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "build"))
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")


def _loss(model: nn.Module, x: torch.Tensor, step: int, coeffs: dict) -> dict:
    return {"loss": ((model(x) - x.sum(-1, keepdim=True)) ** 2).mean()}


def _batches(width: int, model: nn.Module) -> TensorBatches:
    return TensorBatches(torch.randn(32, width, generator=torch.Generator().manual_seed(width)))


def _failing_loss(name: str):
    raise RuntimeError(f"run {name} failed on purpose")


def line_run(name: str, width: int, fail: bool = False) -> Run:
    """A toy run: a linear model of ``width`` inputs fitted to the sum of its inputs."""
    return Run(
        name,
        {"width": width},
        functools.partial(build_seeded, functools.partial(nn.Linear, width, 1)),
        functools.partial(_failing_loss, name) if fail else given(_loss),
        functools.partial(_batches, width),
        CFG,
    )


def weight_norm(scale: float, name: str, model: nn.Module) -> float:
    """A measurement for ``then``: a scaled norm of the model's weights."""
    return scale * float(model.weight.detach().norm())


RUNS = {"wide": line_run("line_wide", 6), "narrow": line_run("line_narrow", 3)}


@pytest.mark.parametrize("processes", [1, 2])
def test_train_many_trains_then_loads_from_the_cache(processes: int) -> None:
    first = train_many(RUNS, processes=processes)
    assert list(first) == ["wide", "narrow"]
    assert all(isinstance(t, Trained) and t.seconds is not None and t.seconds > 0 for t in first.values())
    again = train_many(RUNS, processes=processes)
    assert all(t.seconds is None and t.result.loaded_from_cache for t in again.values())
    for name in RUNS:
        assert torch.equal(first[name].model.weight, again[name].model.weight)


def test_weights_do_not_depend_on_the_process_that_trained_them(tmp_path: Path, monkeypatch) -> None:
    here = train_many(RUNS, processes=1)
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "other"))
    there = train_many(RUNS, processes=2)
    assert all(t.seconds is not None for t in there.values())
    for name in RUNS:
        assert torch.equal(here[name].model.weight, there[name].model.weight)


@pytest.mark.parametrize("processes", [1, 2])
def test_then_measures_every_model_where_it_was_trained(processes: int) -> None:
    trained = train_many(RUNS, then=functools.partial(weight_norm, 2.0), processes=processes)
    for t in trained.values():
        assert t.measured == pytest.approx(2.0 * float(t.model.weight.detach().norm()))
    cached = train_many(RUNS, then=functools.partial(weight_norm, 2.0), processes=processes)
    assert [t.measured for t in cached.values()] == [t.measured for t in trained.values()]


@pytest.mark.parametrize("processes", [1, 2])
def test_train_meanwhile_trains_while_the_work_runs_here(processes: int) -> None:
    done = train_meanwhile(RUNS, functools.partial(sum, (1, 2)), processes=processes)
    assert done == 3 and all(run.is_cached() for run in RUNS.values())


def test_train_meanwhile_starts_no_worker_when_every_run_is_cached(monkeypatch) -> None:
    train_meanwhile(RUNS, functools.partial(sum, (1, 2)), processes=1)  # into the cache
    monkeypatch.setattr("motionlab.train.many.shared_pool", lambda processes: pytest.fail("a worker started"))
    assert train_meanwhile(RUNS, functools.partial(sum, (3, 4)), processes=2) == 7


@pytest.mark.parametrize("processes", [1, 2])
def test_runs_alongside_are_trained_into_the_cache_not_loaded(processes: int) -> None:
    extra = line_run("line_extra", 5)
    trained = train_many({"wide": RUNS["wide"]}, processes=processes, alongside={"extra": extra})
    assert list(trained) == ["wide"] and extra.is_cached()


def test_a_run_loads_without_making_its_loss_or_batches() -> None:
    first, result = line_run("line_lazy", 2).train()
    assert not result.loaded_from_cache
    again, cached = line_run("line_lazy", 2, fail=True).train()  # its loss would raise if it were made
    assert cached.loaded_from_cache and torch.equal(first.weight, again.weight)


def test_a_run_checks_its_fields() -> None:
    with pytest.raises(TypeError, match="train_config must be a TrainConfig"):
        Run("x", {}, nn.Identity, given(_loss), _batches, {"steps": 3})
    with pytest.raises(TypeError, match="loss must be callable"):
        Run("x", {}, nn.Identity, _loss(nn.Identity(), torch.zeros(1), 0, {}), _batches, CFG)


@pytest.mark.parametrize("processes", [1, 2])
def test_a_failed_run_raises_its_own_error(processes: int) -> None:
    runs = {"ok": line_run("line_ok", 2), "bad": line_run("line_bad", 4, fail=True)}
    with pytest.raises(RuntimeError, match="line_bad failed on purpose"):
        train_many(runs, processes=processes)
