"""The one training entry point: runs trained in workers, measured there, loaded here, identical weights."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import pytest
import torch
from torch import nn

from motionlab.train import TensorBatches, TrainConfig, TrainResult, build_seeded, is_cached, train_or_load
from motionlab.train.many import Trained, start_training, train_many

CFG = TrainConfig(steps=12, batch_size=8, lr=1e-2, checkpoint_every=None)


@pytest.fixture(autouse=True)
def own_build(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Workers receive the caller's MOTIONLAB_* settings with every call, so they use this test's cache.
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "build"))
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")


def _loss(model: nn.Module, x: torch.Tensor, step: int, coeffs: dict) -> dict:
    return {"loss": ((model(x) - x.sum(-1, keepdim=True)) ** 2).mean()}


@dataclass(frozen=True)
class LineRun:
    """A toy run: a linear model of ``width`` inputs fitted to the sum of its inputs."""

    name: str
    width: int
    fail: bool = False

    def _parts(self) -> tuple[dict, TensorBatches]:
        data = torch.randn(32, self.width, generator=torch.Generator().manual_seed(self.width))
        return {"width": self.width}, TensorBatches(data)

    def is_cached(self) -> bool:
        return is_cached(self.name, self._parts()[0], CFG)

    def train(self, progress: bool | None = None) -> tuple[nn.Module, TrainResult]:
        if self.fail:
            raise RuntimeError(f"run {self.name} failed on purpose")
        model_config, batches = self._parts()
        model = build_seeded(lambda: nn.Linear(self.width, 1), CFG.seed)
        return model, train_or_load(self.name, model_config, model, _loss, batches, CFG, progress=False)


def weight_norm(scale: float, name: str, model: nn.Module) -> float:
    """A measurement for ``then``: a scaled norm of the model's weights."""
    return scale * float(model.weight.detach().norm())


RUNS = {"wide": LineRun("line_wide", 6), "narrow": LineRun("line_narrow", 3)}


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


def test_start_training_returns_at_once_and_result_waits() -> None:
    pending = start_training(RUNS, processes=2)
    trained = pending.result()
    assert pending.done()
    assert set(trained) == set(RUNS) and all(t.seconds is not None for t in trained.values())


@pytest.mark.parametrize("processes", [1, 2])
def test_a_failed_run_raises_its_own_error(processes: int) -> None:
    runs = {"ok": LineRun("line_ok", 2), "bad": LineRun("line_bad", 4, fail=True)}
    with pytest.raises(RuntimeError, match="line_bad failed on purpose"):
        train_many(runs, processes=processes)
