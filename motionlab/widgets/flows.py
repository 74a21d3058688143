"""Chapter 05's widget: samples of the 2D toy flow at a chosen temperature, over its learned density."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import torch
from matplotlib.figure import Figure

from motionlab.models.flows.toy import GridDensity, ToyFlow


def show_toy_temperature(
    flow: ToyFlow, grid: GridDensity, temperature: float, n: int = 1500, seed: int = 0
) -> Figure:
    """Widget callback: ``n`` samples of ``flow`` at ``temperature`` (seeded) on top of its density ``grid``.

    Returns the figure (inside a widget's output area the inline backend shows it).
    """
    samples = flow.sample(n, temperature, torch.Generator().manual_seed(seed)).numpy()
    fig, ax = plt.subplots(figsize=(5.0, 4.2))
    extent = (grid.x[0], grid.x[-1], grid.y[0], grid.y[-1])
    ax.imshow(grid.density, origin="lower", extent=extent, cmap="Blues", aspect="equal")
    ax.scatter(
        samples[:, 0],
        samples[:, 1],
        s=3,
        color="tab:orange",
        alpha=0.6,
        label=rf"samples, $\tau$ = {temperature:.2f}",
    )
    inside = np.abs(samples).max(axis=1) <= max(abs(grid.x[0]), abs(grid.x[-1]))
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_title(f"temperature {temperature:.2f}: {inside.mean():.0%} of samples inside the view")
    ax.legend(loc="upper right", fontsize=8)
    return fig
