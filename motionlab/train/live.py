"""A run's first steps, trained in front of the reader, beside the reference model that trained all of them.

A chapter loads its main model (the reference model in the full profile) and also trains the same
:class:`~motionlab.train.run.Run` here for a few steps, so that the reader sees the package's model learn::

    live = live_run(runs["mcell"], steps=40)      # the same model, data, seed and schedules, stopped early
    live_figure(live, trained["mcell"].result)    # its loss on top of the reference's whole curve
    print(live_summary(live, trained["mcell"].result))

The live run is the full run cut short, not a smaller model: its schedules are functions of the step
(:mod:`~motionlab.train.schedules`), its batches of epoch ``e`` come from ``(seed, e)`` and its weights from
``seed``, and validation never changes what training sees, so its ``k`` steps are the reference run's first
``k``. On the numerical path the reference model was trained on they agree to the last bit; on another CPU
they differ by that CPU's rounding. The live run is never cached and leaves the caller's random state as it
was (:func:`~motionlab.train.loop.train` trains in a bubble).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
from matplotlib.figure import Figure
from torch import nn

from motionlab.train.history import History
from motionlab.train.loop import TrainResult, train
from motionlab.train.run import Run


@dataclass(frozen=True, eq=False)
class LiveRun:
    """The first steps of a run, trained here.

    Attributes:
        name: the run's name (its checkpoint cache name).
        model: the model after those steps, in eval mode.
        history: the per-step records of those steps.
        seconds: wall time of the live run here, its set-up (batches, initialisation) included.
        total_steps: the whole run's number of steps (what the reference model trained).
    """

    name: str
    model: nn.Module
    history: History
    seconds: float
    total_steps: int

    @property
    def steps(self) -> int:
        """The number of steps trained here."""
        return len(self.history)


def live_run(run: Run, steps: int) -> LiveRun:
    """Train the first ``steps`` steps of ``run`` here (at most the run's own steps), without validation,
    without the cache and without a progress bar; return the model and its per-step history.

    Raises ``ValueError`` when ``steps`` is not a positive integer or the run is measured in epochs (its
    length in steps is then not part of its configuration).
    """
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ValueError(f"live_run: steps must be a positive integer, got {steps!r}")
    total = run.train_config.steps
    if total is None:
        raise ValueError(
            f"live_run: run {run.name!r} is measured in epochs ({run.train_config.epochs}); "
            "a live run needs a run measured in steps"
        )
    cfg = replace(run.train_config, steps=min(steps, total), val_every=None, checkpoint_every=None)
    start = time.perf_counter()
    model = run.build(cfg.seed)
    if run.initialize is not None:
        run.initialize(model)
    result = train(model, run.loss(), run.batches(model), cfg, progress=False, desc=f"{run.name} (live)")
    return LiveRun(run.name, model, result.history, time.perf_counter() - start, total)


def _last_shared_step(live: LiveRun, reference: History) -> int | None:
    """Index into ``reference`` of its last recorded step that the live run also took (``None``: none)."""
    inside = [i for i, step in enumerate(reference.step) if step < live.steps]
    return inside[-1] if inside else None


def live_summary(live: LiveRun, reference: TrainResult, term: str = "loss") -> str:
    """What the live run did and how it compares with the reference run at the last step both recorded.

    The reference's history keeps its per-step records at evenly spaced steps (the shipped reference models
    keep 120), so the comparison is made where the reference has a record inside the live run's steps.
    """
    values = live.history.terms[term]
    first, last = values[0], float(np.mean(values[-max(1, len(values) // 10) :]))
    text = (
        f"{live.name}: trained here {live.steps:,} of the run's {live.total_steps:,} steps in "
        f"{live.seconds:.1f} s; {term} {first:.4g} at the first step, {last:.4g} over its last tenth."
    )
    shared = _last_shared_step(live, reference.history)
    if shared is None:
        return text + " The reference's record has no step inside the live run to compare with."
    step = reference.history.step[shared]
    ours, theirs = values[step], reference.history.terms[term][shared]
    if ours == theirs and step == 0:  # before any update: it says nothing yet about the steps that follow
        verdict = (
            "the same value to the last bit, before the first update (the same initial weights and first "
            "batch; the reference's record has no later step inside the live run to tell whether the updates "
            "agree)"
        )
    elif ours == theirs:
        verdict = "the same value to the last bit: this machine retraced the reference run exactly"
    else:
        verdict = (
            f"they differ by {abs(ours - theirs):.2g}: the same computation rounded differently (another "
            "CPU's kernels, or inputs that differ in their last bits)"
        )
        if step > 0:
            verdict += ", which grows as training goes on"
    compared = f"At step {step:,} the reference run's {term} was {theirs:.6g}, this run's {ours:.6g}"
    return f"{text} {compared}: {verdict}."


def live_figure(
    live: LiveRun, reference: TrainResult, term: str = "loss", title: str | None = None, logy: bool = False
) -> Figure:
    """The live run's ``term`` at every step over the reference run's recorded steps and held-out curve,
    against the number of steps taken on a log axis (the live run is the reference curve's first part).

    ``logy`` puts the loss on a log axis too (for a loss that stays positive and falls by orders of
    magnitude); the axis spans the values but the highest 2 %, so one early spike does not flatten the rest.
    """
    fig = Figure(figsize=(8, 3.6), layout="constrained")
    ax = fig.add_subplot()
    history = reference.history
    ax.plot(
        np.asarray(history.step) + 1,
        history.terms[term],
        ".-",
        ms=2,
        lw=0.8,
        color="0.6",
        label=f"reference run: {term} (recorded steps)",
    )
    if term in history.val_terms:
        ax.plot(
            history.val_step,
            history.val_terms[term],
            "o--",
            ms=3,
            color="0.3",
            label=f"reference run: held-out {term}",
        )
    values = np.asarray(live.history.terms[term])
    ax.plot(np.asarray(live.history.step) + 1, values, lw=1.2, color="C3", label=f"trained here: {term}")
    ax.set_xscale("log")
    shown = np.concatenate([history.terms[term], history.val_terms.get(term, []), values])
    low, high = np.percentile(shown, [0, 98])
    if logy and low <= 0:
        raise ValueError(f"live_figure: logy needs a positive {term!r}, its lowest value is {low:.4g}")
    if logy:
        ax.set_yscale("log")
        ax.set_ylim(low / 1.2, high * 1.2)
    else:
        pad = 0.05 * (high - low or 1.0)
        ax.set_ylim(low - pad, high + pad)
    ax.set(
        xlabel="steps taken (log scale)",
        ylabel=term,
        title=title or f"{live.name}: the first {live.steps} steps, here",
    )
    ax.legend(fontsize="small")
    return fig
