"""The end-of-training figure: loss terms per step, validation points, schedule coefficients on a twin
axis."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from motionlab.train.history import History


def running_mean(values: np.ndarray, window: int) -> np.ndarray:
    """Mean of the last ``window`` values at each index (fewer at the start): ``(n,) -> (n,)``."""
    if window < 1:
        raise ValueError(f"window must be >= 1, got {window}")
    values = np.asarray(values, dtype=float)
    sums = np.cumsum(np.concatenate([[0.0], values]))
    idx = np.arange(1, len(values) + 1)
    start = np.maximum(idx - window, 0)
    return (sums[idx] - sums[start]) / (idx - start)


def plot_history(history: History, logy: bool = False, title: str | None = None) -> Figure:
    """Loss terms against the step (faint: raw, solid: running mean over ~2% of the run), validation means
    as dashed lines with markers, and the coefficients of the schedules (dotted) on a right-hand axis.

    ``logy`` puts the loss axis on a symmetric-log scale (terms may be negative, e.g. a flow's NLL).
    """
    if len(history) == 0:
        raise ValueError("plot_history: the history is empty (no step was recorded)")
    fig = Figure(figsize=(8, 4), layout="constrained")
    ax = fig.add_subplot()
    steps = np.asarray(history.step)
    window = max(1, len(steps) // 50)
    colours = {}
    for name, values in history.terms.items():
        values = np.asarray(values)
        (line,) = ax.plot(steps, running_mean(values, window), lw=1.5, label=name)
        colours[name] = line.get_color()
        ax.plot(steps, values, lw=0.5, alpha=0.3, color=line.get_color())
    for name, values in history.val_terms.items():
        ax.plot(
            history.val_step, values, ls="--", marker="o", ms=3, color=colours.get(name), label=f"val {name}"
        )
    ax.set_xlabel("step")
    ax.set_ylabel("loss terms")
    if logy:
        ax.set_yscale("symlog", linthresh=1e-3)
    handles, labels = ax.get_legend_handles_labels()
    if history.coeffs:
        twin = ax.twinx()
        for index, (name, values) in enumerate(history.coeffs.items()):
            twin.plot(steps, values, ls=":", lw=1.5, color=f"C{(7 + index) % 10}", label=f"coeff {name}")
        twin.set_ylabel("coefficients")
        more_handles, more_labels = twin.get_legend_handles_labels()
        handles, labels = handles + more_handles, labels + more_labels
    ax.legend(handles, labels, fontsize="small", loc="upper right")
    if title:
        ax.set_title(title)
    return fig
