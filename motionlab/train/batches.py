"""Batch sources for the training loop, and the seeded, reproducible order in which they are read.

A batch source is either

* a callable ``batches(epoch, generator, batch_size) -> Iterable[batch]`` that draws its randomness
  (shuffling, augmentation) from ``generator``, e.g. :class:`TensorBatches` (drawing from the global RNG
  is reproducible too, but ties the data to the model's random draws); or
* a ``torch.utils.data.DataLoader`` whose ``batch_size`` equals the training config's; when it shuffles it
  must have been given ``generator=torch.Generator()``, which the loop reseeds every epoch.

Each epoch's generator is seeded from ``(seed, epoch)`` alone, so epoch ``e`` yields the same batches
whether training ran straight through or resumed in the middle of it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from torch import Tensor
from torch.utils.data import DataLoader, RandomSampler, SubsetRandomSampler, WeightedRandomSampler

from motionlab.validation import Checked, flag

BatchSource = DataLoader | Callable[[int, torch.Generator, int], Iterable[Any]]

_RANDOM_SAMPLERS = (RandomSampler, SubsetRandomSampler, WeightedRandomSampler)


def epoch_seed(seed: int, epoch: int, stream: int = 0) -> int:
    """A 63-bit seed for ``(seed, epoch)`` of one stream (0: training batches, 1: validation batches)."""
    state = np.random.SeedSequence([int(seed), int(stream), int(epoch)]).generate_state(2, dtype=np.uint32)
    return int(state[0]) << 31 | int(state[1]) >> 1


def check_source(source: Any, batch_size: int, what: str = "data") -> None:
    """Raise a clear error when ``source`` cannot give reproducible batches of ``batch_size``."""
    if isinstance(source, DataLoader):
        if source.batch_size != batch_size:
            raise ValueError(
                f"{what}: DataLoader batch_size {source.batch_size} differs from TrainConfig.batch_size "
                f"{batch_size}"
            )
        sampler = source.batch_sampler.sampler if source.batch_sampler is not None else source.sampler
        if isinstance(sampler, _RANDOM_SAMPLERS) and sampler.generator is None:
            raise ValueError(
                f"{what}: the DataLoader shuffles without a generator; build it with "
                "generator=torch.Generator() so the loop can seed every epoch"
            )
    elif not callable(source):
        raise TypeError(
            f"{what} must be a DataLoader or a callable batches(epoch, generator, batch_size), "
            f"got {type(source).__name__}"
        )


def epoch_batches(
    source: BatchSource, seed: int, epoch: int, batch_size: int, stream: int = 0
) -> Iterator[Any]:
    """An iterator over the batches of ``epoch``, in the order fixed by ``(seed, epoch, stream)``."""
    generator_seed = epoch_seed(seed, epoch, stream)
    if isinstance(source, DataLoader):
        sampler = source.batch_sampler.sampler if source.batch_sampler is not None else source.sampler
        for generator in {id(g): g for g in (source.generator, getattr(sampler, "generator", None))}.values():
            if generator is not None:
                generator.manual_seed(generator_seed)
        return iter(source)
    return iter(source(epoch, torch.Generator().manual_seed(generator_seed), batch_size))


@dataclass(frozen=True, eq=False)
class TensorBatches(Checked):
    """In-memory tensors sharing a first dimension, served as shuffled minibatches.

    Called by the loop as ``batches(epoch, generator, batch_size)``; yields one tensor per batch when built
    from one tensor, else a tuple. ``drop_last`` drops the final short batch (the default, so every step
    sees ``batch_size`` samples); ``shuffle=False`` keeps the stored order (validation).
    """

    tensors: tuple[Tensor, ...]
    drop_last: bool = flag(True)
    shuffle: bool = flag(True)

    def __post_init__(self) -> None:
        super().__post_init__()
        tensors = (self.tensors,) if isinstance(self.tensors, Tensor) else tuple(self.tensors)
        if not all(isinstance(t, Tensor) for t in tensors):
            raise TypeError(
                f"TensorBatches: tensors must be tensors, got {[type(t).__name__ for t in tensors]}"
            )
        if not tensors:
            raise ValueError("TensorBatches needs one or more tensors, got none")
        sizes = {t.shape[0] if t.dim() else None for t in tensors}
        if len(sizes) != 1 or None in sizes:
            raise ValueError(
                "TensorBatches: tensors must share their first dimension, got sizes "
                f"{sorted(map(str, sizes))}"
            )
        object.__setattr__(self, "tensors", tensors)

    def __len__(self) -> int:
        """Number of samples."""
        return int(self.tensors[0].shape[0])

    def __call__(
        self, epoch: int, generator: torch.Generator, batch_size: int
    ) -> Iterator[Tensor | tuple[Tensor, ...]]:
        if batch_size < 1:
            raise ValueError(f"batch_size must be >= 1, got {batch_size}")
        n = len(self)
        if self.drop_last and n < batch_size:
            raise ValueError(
                f"TensorBatches: {n} samples cannot fill one batch of {batch_size} with drop_last=True"
            )
        order = torch.randperm(n, generator=generator) if self.shuffle else torch.arange(n)
        stop = n - n % batch_size if self.drop_last else n
        for begin in range(0, stop, batch_size):
            index = order[begin : begin + batch_size]
            batch = tuple(t[index] for t in self.tensors)
            yield batch[0] if len(batch) == 1 else batch
