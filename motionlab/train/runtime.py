"""Where and how the training loop runs: device, mixed precision, data-parallel processes, extra callbacks.

The chapters never set any of this: the default :class:`Execution` is one CPU process in full precision,
and the loop then does exactly what it always did (bitwise the same weights). The training command
(``python -m motionlab.apps.training``) sets it around a run's ``train()`` call::

    with executing(Execution(device=torch.device("cuda"), mixed_precision=True)):
        model, result = run.train()

Data-parallel training (under ``torchrun``): every process draws the same global batch (the loop's seeded
order) and keeps its share of it, the interleaved indices ``rank, rank + N, ...`` that
:class:`~torch.utils.data.DistributedSampler` gives; the model runs inside
:class:`~torch.nn.parallel.DistributedDataParallel`, which averages the gradients over the processes. For a
loss that is a mean over the samples of a batch, with no random draws, one optimiser step then equals the
single-process step on the global batch up to float rounding. Random draws inside the loss (a VAE's
reparameterisation noise) come from a per-process stream, so they differ from a single process's; a loss
that couples the samples of a batch (a contrastive term, BatchNorm statistics) is computed per share, as
in any data-parallel training.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import torch
import torch.distributed as dist
from torch import Tensor, nn
from torch.utils.data import DistributedSampler


@dataclass(frozen=True)
class Execution:
    """How a training run executes (none of it enters the checkpoint cache key).

    Attributes:
        device: where the model and its batches live during training (the model returns to the CPU after).
        mixed_precision: bf16 autocast around the loss (CUDA only; ignored on the CPU).
        rank, world_size: this process and the number of data-parallel processes (1: no data parallelism).
        callbacks: extra ``callback(completed_steps, model, history)`` calls after every step.
        checkpoint_every: write the resumable state every this many steps (``None``: the run's own setting).
        resume: continue from a resumable state left by an interrupted run of the same configuration;
            ``False`` discards such a state and starts afresh.
    """

    device: torch.device = torch.device("cpu")
    mixed_precision: bool = False
    rank: int = 0
    world_size: int = 1
    callbacks: tuple[Callable[..., None], ...] = ()
    checkpoint_every: int | None = None
    resume: bool = True

    @property
    def distributed(self) -> bool:
        """Whether several processes train the model together."""
        return self.world_size > 1

    @property
    def is_main(self) -> bool:
        """Whether this process logs and writes checkpoints (rank 0)."""
        return self.rank == 0

    @property
    def autocast(self) -> contextlib.AbstractContextManager:
        """The loss's precision context: bf16 autocast on CUDA when asked for, else nothing at all."""
        if self.mixed_precision and self.device.type == "cuda":
            return torch.autocast("cuda", dtype=torch.bfloat16)
        return contextlib.nullcontext()


_current = Execution()


def current() -> Execution:
    """The execution set by the innermost :func:`executing` (the default: one CPU process)."""
    return _current


@contextlib.contextmanager
def executing(execution: Execution) -> Iterator[Execution]:
    """Train with ``execution`` inside the block."""
    global _current
    if not isinstance(execution, Execution):
        raise TypeError(f"executing: expected an Execution, got {type(execution).__name__}")
    previous, _current = _current, execution
    try:
        yield execution
    finally:
        _current = previous


def batch_size_of(batch: Any) -> int | None:
    """The first dimension of the first tensor found in ``batch`` (tensor, tuple, list, dict, dataclass)."""
    if isinstance(batch, Tensor):
        return int(batch.shape[0]) if batch.dim() else None
    if dataclasses.is_dataclass(batch) and not isinstance(batch, type):
        batch = [getattr(batch, f.name) for f in dataclasses.fields(batch)]
    if isinstance(batch, dict):
        batch = list(batch.values())
    if isinstance(batch, (tuple, list)):
        for item in batch:
            if (size := batch_size_of(item)) is not None:
                return size
    return None


def map_batch(batch: Any, function: Callable[[Tensor], Tensor]) -> Any:
    """``batch`` with ``function`` applied to every tensor in it (tuples, lists, dicts and dataclasses are
    rebuilt; anything else is kept)."""
    if isinstance(batch, Tensor):
        return function(batch)
    if isinstance(batch, tuple) and hasattr(batch, "_fields"):  # a NamedTuple
        return type(batch)(*(map_batch(item, function) for item in batch))
    if isinstance(batch, (tuple, list)):
        return type(batch)(map_batch(item, function) for item in batch)
    if isinstance(batch, dict):
        return {key: map_batch(item, function) for key, item in batch.items()}
    if dataclasses.is_dataclass(batch) and not isinstance(batch, type):
        changes = {f.name: map_batch(getattr(batch, f.name), function) for f in dataclasses.fields(batch)}
        return dataclasses.replace(batch, **{k: v for k, v in changes.items() if _is_init_field(batch, k)})
    return batch


def _is_init_field(batch: Any, name: str) -> bool:
    """Whether the dataclass field ``name`` of ``batch`` is an ``__init__`` argument (``replace`` takes only
    those)."""
    return next(f for f in dataclasses.fields(batch) if f.name == name).init


def shard_indices(size: int, rank: int, world_size: int) -> Tensor:
    """The samples of a global batch of ``size`` that process ``rank`` of ``world_size`` keeps:
    :class:`~torch.utils.data.DistributedSampler`'s interleaving ``rank, rank + world_size, ...``."""
    if size % world_size:
        raise ValueError(
            f"a batch of {size} samples does not split evenly over {world_size} processes; choose a batch "
            "size that is a multiple of the number of processes"
        )
    sampler = DistributedSampler(range(size), num_replicas=world_size, rank=rank, shuffle=False)
    return torch.tensor(list(sampler), dtype=torch.long)


def local_batch(batch: Any, execution: Execution) -> Any:
    """This process's share of the global ``batch`` (every tensor whose first dimension is the batch size),
    moved to the execution's device. With one CPU process: ``batch`` itself."""
    if not execution.distributed and execution.device.type == "cpu":
        return batch
    if execution.distributed:
        size = batch_size_of(batch)
        if size is None:
            raise TypeError(f"cannot split a batch of type {type(batch).__name__} over processes: no tensor")
        index = shard_indices(size, execution.rank, execution.world_size)
        batch = map_batch(batch, lambda t: t[index] if t.dim() and t.shape[0] == size else t)
    return map_batch(batch, lambda t: t.to(execution.device, non_blocking=True))


class LossModule(nn.Module):
    """``loss_fn(model, batch, step, coeffs)`` as a module, so that DistributedDataParallel sees the whole
    computation of the loss (a family's loss may call any of its model's methods, not only ``forward``)."""

    def __init__(self, model: nn.Module, loss_fn: Callable[..., dict[str, Tensor]]) -> None:
        super().__init__()
        self.model = model
        self.loss_fn = loss_fn

    def forward(self, batch: Any, step: int, coeffs: dict[str, float]) -> dict[str, Tensor]:
        return self.loss_fn(self.model, batch, step, coeffs)


def data_parallel(
    model: nn.Module, loss_fn: Callable[..., dict[str, Tensor]], execution: Execution
) -> nn.Module:
    """The loss of ``model`` wrapped in DistributedDataParallel (the process group must be initialised)."""
    if not dist.is_initialized():
        raise RuntimeError("data-parallel training needs torch.distributed initialised (run under torchrun)")
    device_ids = [execution.device.index or 0] if execution.device.type == "cuda" else None
    return nn.parallel.DistributedDataParallel(
        LossModule(model, loss_fn), device_ids=device_ids, find_unused_parameters=True
    )


def mean_over_processes(values: list[float], execution: Execution) -> list[float]:
    """``values`` averaged over the data-parallel processes (what one process logs for the global batch)."""
    if not execution.distributed:
        return values
    total = torch.tensor(values, dtype=torch.float64, device=execution.device)
    dist.all_reduce(total)
    return (total / execution.world_size).tolist()
