"""Two-dimensional toy densities and a small flow that learns them.

A point ``(x, y)`` is handled as a sequence of one frame with two channels, ``(batch, 2, 1)``, so the toy
flow is made of exactly the layers the motion models use (ActNorm, 1x1 convolution, affine coupling with
a per-frame network). In 2D its density can be drawn on a grid and integrated, which checks the
change-of-variables bookkeeping as a whole: a correct flow's density integrates to 1.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import torch
from torch import Tensor, nn

from motionlab import config
from motionlab.models.flows.base import FlowSequence
from motionlab.models.flows.glow import GlowStep
from motionlab.models.flows.prior import StandardNormal, check_temperature
from motionlab.train import (
    TensorBatches,
    TrainConfig,
    TrainResult,
    build_seeded,
    train_or_load,
    validation_every,
)
from motionlab.validation import Checked, check_scalar, check_tensor, integer

#: Centre and scale that bring the two moons of :func:`two_moons` to roughly zero mean and unit spread.
MOONS_CENTER = (0.5, 0.25)
MOONS_SCALE = (0.85, 0.5)


def two_moons(n: int, noise: float = 0.06, seed: int = 0) -> Tensor:
    """``n`` points ``(n, 2)`` float32 from two interleaved half circles with Gaussian noise, standardised.

    The upper moon is the unit half circle ``(cos a, sin a)``, the lower one ``(1 - cos a, 0.5 - sin a)``,
    ``a ~ U(0, pi)``, each point on either with probability 1/2; then ``noise`` (std, in moon units) is added
    and the points are shifted by :data:`MOONS_CENTER` and divided by :data:`MOONS_SCALE`.
    """
    check_scalar(n, "n", "two_moons", kind=numbers.Integral, minimum=1)
    check_scalar(noise, "noise", "two_moons", minimum=0)
    rng = np.random.default_rng(seed)
    angle = rng.uniform(0.0, math.pi, n)
    lower = rng.random(n) < 0.5
    x = np.where(lower, 1.0 - np.cos(angle), np.cos(angle))
    y = np.where(lower, 0.5 - np.sin(angle), np.sin(angle))
    points = np.stack([x, y], axis=1) + noise * rng.standard_normal((n, 2))
    return torch.from_numpy((points - MOONS_CENTER) / MOONS_SCALE).float()


@dataclass(frozen=True)
class ToyFlowConfig(Checked):
    """A 2D flow: ``steps`` Glow steps (ActNorm, 1x1 conv, affine coupling) with per-point networks."""

    steps: int = integer(8, minimum=1)
    hidden: int = integer(64, minimum=1)


class ToyFlow(nn.Module):
    """A density on the plane: a :class:`FlowSequence` of Glow steps over ``(n, 2, 1)`` plus ``N(0, I)``."""

    def __init__(self, cfg: ToyFlowConfig) -> None:
        super().__init__()
        self.cfg = cfg
        self.flow = FlowSequence(GlowStep(2, 0, cfg.hidden, kernel_size=1) for _ in range(cfg.steps))
        self.prior = StandardNormal()

    def log_prob(self, points: Tensor) -> Tensor:
        """``log p(points)`` ``(n,)`` for points ``(n, 2)``, in nats."""
        check_tensor(points, "points", "ToyFlow.log_prob", ndim=2, trailing=(2,))
        z, logdet = self.flow(points[:, :, None])
        return self.prior.log_prob(z) + logdet

    @torch.no_grad()
    def sample(self, n: int, temperature: float = 1.0, generator: torch.Generator | None = None) -> Tensor:
        """``n`` points ``(n, 2)`` drawn at ``temperature``."""
        temperature = check_temperature(temperature, "ToyFlow.sample")
        check_scalar(n, "n", "ToyFlow.sample", kind=numbers.Integral, minimum=1)
        z = self.prior.sample((n, 2, 1), temperature, generator, next(self.parameters()).dtype)
        return self.flow.inverse(z)[:, :, 0]


def toy_nll_loss(model: ToyFlow, batch: Tensor, step: int, coeffs: dict[str, float]) -> dict[str, Tensor]:
    """Training loss for :func:`motionlab.train.train_or_load`: mean negative log-likelihood in nats per
    point."""
    nll = -model.log_prob(batch).mean()
    return {"loss": nll, "nll": nll.detach()}


#: The training points of :func:`train_toy_flow`: ``two_moons(TOY_POINTS, seed=0)``.
TOY_POINTS = 4096

#: The validation points of :func:`train_toy_flow` (its held-out curve): ``two_moons(TOY_VAL_POINTS,
#: seed=2)``, a fresh draw from the training points' distribution (seed 1 is chapter 05's test set).
TOY_VAL_POINTS = 1024


def train_toy_flow(hidden: int | None = None, steps: int | None = None) -> tuple[ToyFlow, TrainResult]:
    """Chapter 05's toy flow (6 Glow steps, coupling networks of ``hidden`` units) trained for ``steps``
    Adam steps on :data:`TOY_POINTS` two-moons points, or loaded from the cache. ``None`` takes the active
    profile's size (quick: 16 units, 40 steps; full: 64 units, 600 steps). The initial weights depend on the
    training seed alone (:func:`~motionlab.train.build_seeded`), not on what ran before. It validates
    up to 40 times (:func:`~motionlab.train.validation_every`) on :data:`TOY_VAL_POINTS` other points, all of
    them in their order (a pass leaves the weights as they are). Returns the model (in ``eval()`` mode) and
    its training result."""
    hidden = config.choose(quick=16, full=64) if hidden is None else hidden
    steps = config.choose(quick=40, full=600) if steps is None else steps
    cfg = ToyFlowConfig(steps=6, hidden=hidden)
    train_cfg = TrainConfig(
        steps=steps, batch_size=256, lr=5e-3, grad_clip=5.0, val_every=validation_every(steps)
    )
    toy = build_seeded(lambda: ToyFlow(cfg), train_cfg.seed)
    result = train_or_load(
        "toy_flow_moons",
        cfg,
        toy,
        toy_nll_loss,
        TensorBatches((two_moons(TOY_POINTS, seed=0),)),
        train_cfg,
        data_config={"data": "two_moons", "n": TOY_POINTS, "noise": 0.06, "seed": 0},
        val_data=TensorBatches((two_moons(TOY_VAL_POINTS, seed=2),), shuffle=False, drop_last=False),
    )
    return toy, result


class GridDensity(NamedTuple):
    """A density evaluated on a square grid: cell centres ``x``, ``y`` ``(R,)`` and ``density`` ``(R, R)``
    (rows follow ``y``), the cell area and the Riemann sum of the density (the integral over the grid)."""

    x: np.ndarray
    y: np.ndarray
    density: np.ndarray
    cell_area: float
    integral: float


@torch.no_grad()
def grid_density(
    model: ToyFlow, extent: float = 4.0, resolution: int = 300, chunk: int = 20_000
) -> GridDensity:
    """Evaluate ``model``'s density at the centres of ``resolution**2`` cells covering ``[-extent,
    extent]**2``."""
    check_scalar(extent, "extent", "grid_density", minimum=0, include_minimum=False)
    check_scalar(resolution, "resolution", "grid_density", kind=numbers.Integral, minimum=2)
    step = 2.0 * extent / resolution
    centres = -extent + step * (np.arange(resolution) + 0.5)
    gx, gy = np.meshgrid(centres, centres)
    points = torch.from_numpy(np.stack([gx.ravel(), gy.ravel()], axis=1)).to(next(model.parameters()).dtype)
    log_p = torch.cat([model.log_prob(part) for part in points.split(chunk)])
    density = log_p.double().exp().reshape(resolution, resolution).numpy()
    return GridDensity(centres, centres, density, step * step, float(density.sum() * step * step))
