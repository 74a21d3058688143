"""Training in worker processes: order, thread count, errors, and weights identical to training in-process."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest
import torch
from torch import nn

from motionlab import config
from motionlab.train import TensorBatches, TrainConfig, build_seeded, is_cached, train_or_load
from motionlab.train.parallel import (
    close_shared_pools,
    run_chains,
    run_in_workers,
    shared_pool,
    worker_pool,
)

CFG = TrainConfig(steps=15, batch_size=8, lr=1e-2, checkpoint_every=None)


@pytest.fixture(autouse=True)
def own_build(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Every call carries the caller's MOTIONLAB_* settings to the worker, so workers share this test's cache
    # directory even when the shared pool started them in an earlier test.
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "build"))
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")


def where_and_threads(tag: str) -> tuple[str, int, int]:
    return tag, os.getpid(), torch.get_num_threads()


def build_dir_and_seeded_draw(tag: str) -> tuple[str, str, float]:
    draw = float(torch.rand(()))  # the global generator, seeded by the call's set-up
    torch.rand(1000)  # moves the worker's generator on: the next call must not see it
    return tag, str(config.build_dir()), draw


def interrupt_handler() -> object:
    return signal.getsignal(signal.SIGINT)


def write_tag(path: str, tag: str) -> str:
    Path(path).write_text(tag)
    return f"wrote {tag}"


def read_tag(path: str) -> str:
    return Path(path).read_text()


def fail(message: str) -> None:
    raise RuntimeError(message)


def add_one_in_place(values: torch.Tensor) -> torch.Tensor:
    values += 1
    return values


def tiny_model() -> nn.Module:
    torch.manual_seed(0)
    return nn.Sequential(nn.Linear(4, 8), nn.Tanh(), nn.Linear(8, 4))


def loss_fn(
    model: nn.Module, batch: torch.Tensor, step: int, coeffs: dict[str, float]
) -> dict[str, torch.Tensor]:
    return {"loss": ((model(batch) - batch) ** 2).mean()}


def batches() -> TensorBatches:
    return TensorBatches((torch.randn(32, 4, generator=torch.Generator().manual_seed(3)),))


def train_tiny(name: str) -> bool:
    return train_or_load(name, {"hidden": 8}, tiny_model(), loss_fn, batches(), CFG).loaded_from_cache


def test_results_come_back_in_order_from_other_processes_on_one_thread() -> None:
    results = run_in_workers(where_and_threads, [("a",), ("b",), ("c",)], processes=2)
    assert [tag for tag, _, _ in results] == ["a", "b", "c"]
    assert all(pid != os.getpid() for _, pid, _ in results)
    assert all(threads == config.DEFAULT_THREADS for _, _, threads in results)


def test_the_shared_pool_is_reused_and_each_call_is_set_up_afresh(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    first = run_in_workers(where_and_threads, [("a",), ("b",)], processes=2)
    assert shared_pool(2) is shared_pool(2)
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "other"))
    rows = run_in_workers(build_dir_and_seeded_draw, [(tag,) for tag in "cdef"], processes=2)
    assert {row[1] for row in rows} == {str(tmp_path / "other")}
    assert len({row[2] for row in rows}) == 1  # every call starts from seed 0, whatever ran before it
    again = run_in_workers(where_and_threads, [("g",), ("h",)], processes=2)
    assert len({pid for _, pid, _ in first + again}) <= 2  # the same two workers (a pool per call: four)


@pytest.mark.parametrize("processes", [1, 2])
def test_chains_run_their_calls_in_order_and_side_by_side(tmp_path: Path, processes: int) -> None:
    chains = [
        [(write_tag, (str(tmp_path / f"{tag}.txt"), tag)), (read_tag, (str(tmp_path / f"{tag}.txt"),))]
        for tag in "abc"
    ] + [[], [(where_and_threads, ("alone",))]]
    results = run_chains(chains, processes=processes)
    assert results[:3] == [
        [f"wrote {tag}", tag] for tag in "abc"
    ]  # each second call saw its first call's file
    assert results[3] == [] and results[4][0][0] == "alone"
    with pytest.raises(RuntimeError, match="broken step"):
        run_chains(
            [[(where_and_threads, ("a",)), (fail, ("broken step",))], [(where_and_threads, ("b",))]],
            processes,
        )
    never = tmp_path / "never.txt"
    with pytest.raises(
        RuntimeError, match="first failure"
    ):  # the first in the order given, and no later step runs
        run_chains(
            [[(fail, ("first failure",)), (write_tag, (str(never), "x"))], [(fail, ("second failure",))]],
            processes,
        )
    assert not never.exists()


def test_idle_workers_ignore_ctrl_c() -> None:
    assert run_in_workers(interrupt_handler, [(), ()], processes=2) == [signal.SIG_IGN, signal.SIG_IGN]


def test_one_process_or_one_call_runs_here() -> None:
    assert run_in_workers(where_and_threads, [("x",)], processes=2)[0][1] == os.getpid()
    assert {pid for _, pid, _ in run_in_workers(where_and_threads, [("x",), ("y",)], processes=1)} == {
        os.getpid()
    }
    assert run_in_workers(where_and_threads, [], processes=2) == []


def test_an_error_in_a_worker_is_raised_here() -> None:
    with pytest.raises(RuntimeError, match="broken run"):
        run_in_workers(fail, [("broken run",), ("another",)], processes=2)


@pytest.mark.parametrize(
    "processes, error", [(0, ValueError), (-1, ValueError), (1.5, TypeError), (True, TypeError)]
)
def test_the_process_count_is_checked(processes, error) -> None:
    with pytest.raises(error, match="run_in_workers: processes must be"):
        run_in_workers(where_and_threads, [("a",), ("b",)], processes=processes)
    with pytest.raises(error, match="worker_pool: processes must be"):
        worker_pool(processes)


def test_a_run_trained_in_a_worker_loads_here_with_the_weights_of_an_in_process_run() -> None:
    assert not is_cached("tiny_worker", {"hidden": 8}, CFG)
    assert run_in_workers(train_tiny, [("tiny_worker",), ("tiny_other",)], processes=2) == [False, False]
    assert is_cached("tiny_worker", {"hidden": 8}, CFG)
    loaded = tiny_model()
    assert train_or_load("tiny_worker", {"hidden": 8}, loaded, loss_fn, batches(), CFG).loaded_from_cache
    config.set_threads()
    here = tiny_model()
    assert not train_or_load("tiny_here", {"hidden": 8}, here, loss_fn, batches(), CFG).loaded_from_cache
    for (key, a), b in zip(loaded.state_dict().items(), here.state_dict().values()):
        assert torch.equal(a, b), key


def test_build_seeded_depends_on_the_seed_alone_and_leaves_the_callers_rng() -> None:
    torch.manual_seed(123)
    before = torch.get_rng_state()
    first = build_seeded(lambda: nn.Linear(3, 2), 7)
    assert torch.equal(torch.get_rng_state(), before)
    torch.randn(100)  # whatever ran before does not matter
    second = build_seeded(lambda: nn.Linear(3, 2), 7)
    assert torch.equal(first.weight, second.weight) and torch.equal(first.bias, second.bias)
    assert not torch.equal(first.weight, build_seeded(lambda: nn.Linear(3, 2), 8).weight)


def test_workers_get_copies_of_tensors_and_return_copies():
    # the pool's own queues would move a tensor's storage into shared memory: a worker writing into its
    # argument would then change the caller's tensor
    first, second = torch.zeros(5), torch.arange(5.0)
    results = run_in_workers(add_one_in_place, [(first,), (second,)])
    assert torch.equal(first, torch.zeros(5)) and torch.equal(second, torch.arange(5.0))
    assert torch.equal(results[0], torch.ones(5)) and torch.equal(results[1], torch.arange(1.0, 6.0))
    assert not results[0].is_shared()


def test_closing_ends_the_shared_workers_and_the_next_use_starts_a_new_pool() -> None:
    # Last in the module: every earlier test shares one pool (a worker costs seconds of a core to start).
    workers = {pid for _, pid, _ in run_in_workers(where_and_threads, [("a",), ("b",)], processes=2)}
    old = shared_pool(2)
    close_shared_pools()
    for pid in workers:  # shutdown waits for the workers: each has exited and been reaped
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)
    new = shared_pool(2)  # started lazily: no worker until the first call
    assert new is not old and new is shared_pool(2)
    close_shared_pools()
