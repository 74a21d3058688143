"""How many torch threads the course's small models should use: one training step on 1 vs. 2 threads.

Four models the size of the course's (a 2-layer GRU(128) on 64 clips x 60 frames x 90 features, an MLP
3x256 on a batch of 256, a 1-layer LSTM(64) on the same clips, a 1D conv net over them), each trained with
AdamW. Thread counts are interleaved in short blocks (a warm-up step, then timed steps) so that background
load on the shared machine hits both counts alike; the reported time is the median per step.
:func:`thread_scaling` returns, for each model, the median milliseconds on 1 and on 2 threads and their ratio
(``speedup_2_threads`` above 1 means two threads are faster), plus the load average while measuring.
"""

from __future__ import annotations

import os
import statistics
import time
from collections.abc import Callable

import torch
from torch import Tensor, nn

from motionlab import config

THREAD_COUNTS = (1, 2)
BLOCKS = 8
STEPS_PER_BLOCK = 5
BATCH_CLIPS, FRAMES, FEATURES = 64, 60, 90
MLP_BATCH = 256


class _Recurrent(nn.Module):
    """A recurrent net predicting each frame's features from its hidden state: (B, T, F) -> (B, T, F)."""

    def __init__(self, cell: type[nn.GRU] | type[nn.LSTM], hidden: int, layers: int) -> None:
        super().__init__()
        self.rnn = cell(FEATURES, hidden, num_layers=layers, batch_first=True)
        self.head = nn.Linear(hidden, FEATURES)

    def forward(self, x: Tensor) -> Tensor:
        return self.head(self.rnn(x)[0])


class _Conv(nn.Module):
    """Three 1D convolutions (kernel 5, 128 channels) over time: (B, T, F) -> (B, T, F)."""

    def __init__(self) -> None:
        super().__init__()
        self.net = nn.Sequential(
            nn.Conv1d(FEATURES, 128, 5, padding=2),
            nn.ReLU(),
            nn.Conv1d(128, 128, 5, padding=2),
            nn.ReLU(),
            nn.Conv1d(128, FEATURES, 5, padding=2),
        )

    def forward(self, x: Tensor) -> Tensor:
        return self.net(x.transpose(1, 2)).transpose(1, 2)


def _models() -> dict[str, tuple[nn.Module, Tensor]]:
    """Each benchmark model with its input batch (the target is the input itself)."""
    gen = torch.Generator().manual_seed(0)
    clips = torch.randn(BATCH_CLIPS, FRAMES, FEATURES, generator=gen)
    mlp = nn.Sequential(
        nn.Linear(FEATURES, 256),
        nn.ReLU(),
        nn.Linear(256, 256),
        nn.ReLU(),
        nn.Linear(256, 256),
        nn.ReLU(),
        nn.Linear(256, FEATURES),
    )
    return {
        "gru2x128": (_Recurrent(nn.GRU, 128, 2), clips),
        "mlp3x256": (mlp, torch.randn(MLP_BATCH, FEATURES, generator=gen)),
        "lstm1x64": (_Recurrent(nn.LSTM, 64, 1), clips),
        "conv1d3x128": (_Conv(), clips),
    }


def _step_function(model: nn.Module, x: Tensor) -> Callable[[], None]:
    """One AdamW training step of ``model`` on the reconstruction of ``x``."""
    optimiser = torch.optim.AdamW(model.parameters(), lr=1e-4)

    def step() -> None:
        optimiser.zero_grad(set_to_none=True)
        loss = nn.functional.mse_loss(model(x), x)
        loss.backward()
        optimiser.step()

    return step


def _median_step_ms(step: Callable[[], None]) -> dict[int, float]:
    """Median wall-clock milliseconds of ``step`` per thread count, blocks interleaved."""
    times: dict[int, list[float]] = {n: [] for n in THREAD_COUNTS}
    for _ in range(BLOCKS):
        for n in THREAD_COUNTS:
            torch.set_num_threads(n)
            step()  # warm-up after the switch
            for _ in range(STEPS_PER_BLOCK):
                start = time.perf_counter()
                step()
                times[n].append((time.perf_counter() - start) * 1e3)
    return {n: statistics.median(values) for n, values in times.items()}


def thread_scaling() -> dict:
    """Median training-step milliseconds per model on 1 and 2 threads (see the module docstring)."""
    config.seed_everything(0)
    result: dict = {"cpu_count": os.cpu_count(), "load_average_before": os.getloadavg()[0]}
    for name, (model, x) in _models().items():
        medians = _median_step_ms(_step_function(model, x))
        for n, ms in medians.items():
            result[f"{name}.step_ms_{n}_thread{'s' if n > 1 else ''}"] = ms
        result[f"{name}.speedup_2_threads"] = medians[1] / medians[2]
    result["load_average_after"] = os.getloadavg()[0]
    config.set_threads()
    return result
