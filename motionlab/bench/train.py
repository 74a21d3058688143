"""Training-step throughput through :func:`motionlab.train.train`, on the default thread count.

Two models the size of the course's: a next-frame GRU (2 layers of 128 units; batches of 64 clips x 60
frames x 90 features) and an MLP VAE (3x256 encoder and decoder, 32 latents; batches of 256 poses x 90
features, KL weight annealed). For each: steps and samples per second through the loop (best of a few
repeats), the same for a bare hand-written AdamW loop, and the loop's overhead in percent of the bare time.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import torch
from torch import Tensor, nn

from motionlab import config
from motionlab.train import KLAnneal, TensorBatches, TrainConfig, train

STEPS = 30
REPEATS = 3
FEATURES = 90


class _NextFrameGRU(nn.Module):
    """Predicts frame t+1 from frames up to t: (B, T, F) -> (B, T, F)."""

    def __init__(self) -> None:
        super().__init__()
        self.rnn = nn.GRU(FEATURES, 128, num_layers=2, batch_first=True)
        self.head = nn.Linear(128, FEATURES)

    def forward(self, clips: Tensor) -> Tensor:
        return self.head(self.rnn(clips)[0])


def _gru_loss(model: nn.Module, clips: Tensor, step: int, coeffs: dict[str, float]) -> dict[str, Tensor]:
    loss = nn.functional.mse_loss(model(clips[:, :-1]), clips[:, 1:])
    return {"loss": loss}


def _mlp(sizes: list[int]) -> nn.Sequential:
    layers: list[nn.Module] = []
    for fan_in, fan_out in zip(sizes[:-1], sizes[1:]):
        layers += [nn.Linear(fan_in, fan_out), nn.ReLU()]
    return nn.Sequential(*layers[:-1])


class _PoseVAE(nn.Module):
    """A Gaussian VAE over single poses: encoder 90 -> 3x256 -> (mean, log-variance) of 32 latents."""

    def __init__(self) -> None:
        super().__init__()
        self.encoder = _mlp([FEATURES, 256, 256, 256, 64])
        self.decoder = _mlp([32, 256, 256, 256, FEATURES])


def _vae_loss(model: nn.Module, poses: Tensor, step: int, coeffs: dict[str, float]) -> dict[str, Tensor]:
    mean, log_var = model.encoder(poses).chunk(2, dim=-1)
    z = mean + torch.randn_like(mean) * (0.5 * log_var).exp()
    recon = nn.functional.mse_loss(model.decoder(z), poses)
    kl = 0.5 * (mean**2 + log_var.exp() - 1 - log_var).sum(-1).mean()
    return {"loss": recon + coeffs["beta"] * kl, "recon": recon, "kl": kl}


def _bare_seconds(
    model: nn.Module, loss_fn: Callable[..., dict[str, Tensor]], batch: Tensor, cfg: TrainConfig
) -> float:
    """Seconds for ``STEPS`` plain AdamW steps with clipping on one fixed batch (no loop bookkeeping)."""
    optimiser = torch.optim.AdamW(model.parameters(), lr=cfg.lr)
    coeffs = {name: schedule(0) for name, schedule in cfg.schedules.items()}
    start = time.perf_counter()
    for step in range(STEPS):
        optimiser.zero_grad(set_to_none=True)
        loss_fn(model, batch, step, coeffs)["loss"].backward()
        nn.utils.clip_grad_norm_(model.parameters(), cfg.grad_clip)
        optimiser.step()
    return time.perf_counter() - start


def _measure(
    name: str, build: Callable[[], nn.Module], loss_fn: Any, samples: Tensor, cfg: TrainConfig
) -> dict[str, float]:
    looped, bare = [], []
    for _ in range(REPEATS):
        model = build()
        start = time.perf_counter()
        train(model, loss_fn, TensorBatches(samples), cfg, progress=False)
        looped.append(time.perf_counter() - start)
        bare.append(_bare_seconds(build(), loss_fn, samples[: cfg.batch_size], cfg))
    best_loop, best_bare = min(looped), min(bare)
    return {
        f"{name}.steps_per_s": STEPS / best_loop,
        f"{name}.samples_per_s": STEPS * cfg.batch_size / best_loop,
        f"{name}.bare_steps_per_s": STEPS / best_bare,
        f"{name}.loop_overhead_pct": 100 * (best_loop - best_bare) / best_bare,
    }


def step_throughput() -> dict:
    """Throughput of the training loop on a GRU and an MLP VAE (see the module docstring)."""
    threads = config.set_threads()
    gen = config.seed_everything(0)
    clips = torch.randn(4 * 64, 61, FEATURES, generator=gen)  # 60 input frames, 60 targets
    poses = torch.randn(4 * 256, FEATURES, generator=gen)
    result: dict[str, float] = {"threads": threads, "steps": STEPS}
    result.update(
        _measure(
            "gru2x128_b64_t60",
            _NextFrameGRU,
            _gru_loss,
            clips,
            TrainConfig(steps=STEPS, batch_size=64, checkpoint_every=None),
        )
    )
    vae_cfg = TrainConfig(
        steps=STEPS,
        batch_size=256,
        checkpoint_every=None,
        schedules={"beta": KLAnneal(max_value=1.0, warmup=5, anneal=10)},
    )
    result.update(_measure("mlp_vae3x256_b256", _PoseVAE, _vae_loss, poses, vae_cfg))
    return result
