"""A live run is the full run cut short: the same losses step for step, no trace left on the random state."""

from __future__ import annotations

import functools
from dataclasses import replace
from pathlib import Path

import pytest
import torch
from matplotlib.figure import Figure
from torch import nn

from motionlab.train import KLAnneal, PiecewiseLinear, TensorBatches, TrainConfig, build_seeded
from motionlab.train.history import History
from motionlab.train.live import LiveRun, live_figure, live_run, live_summary
from motionlab.train.loop import TrainResult
from motionlab.train.run import Run, given
from motionlab.train.state import rng_state

WIDTH = 5


@pytest.fixture(autouse=True)
def own_build(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "build"))
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")


def _noisy_loss(model: nn.Module, x: torch.Tensor, step: int, coeffs: dict) -> dict:
    """A fit with a random draw inside (like a VAE's) and a scheduled weight."""
    noise = 0.1 * torch.randn(x.shape[0], 1)
    fit = ((model(x) + noise - x.sum(-1, keepdim=True)) ** 2).mean()
    penalty = model.weight.pow(2).sum()
    return {"loss": fit + coeffs["beta"] * penalty, "fit": fit}


def _batches(seed: int, model: nn.Module) -> TensorBatches:
    return TensorBatches(torch.randn(64, WIDTH, generator=torch.Generator().manual_seed(seed)))


def line_run(steps: int = 40, validate: bool = True) -> Run:
    """A linear model fitted with a decaying learning rate and a ramped penalty, validating every 5 steps."""
    cfg = TrainConfig(
        steps=steps,
        batch_size=8,
        lr=1e-2,
        lr_schedule=PiecewiseLinear(((0, 1.0), (steps, 0.1))),
        schedules={"beta": KLAnneal(max_value=0.5, warmup=5, anneal=20)},
        val_every=5 if validate else None,
        checkpoint_every=None,
    )
    return Run(
        "line",
        {"width": WIDTH},
        functools.partial(build_seeded, functools.partial(nn.Linear, WIDTH, 1)),
        given(_noisy_loss),
        functools.partial(_batches, 0),
        cfg,
        val_batches=functools.partial(_batches, 1) if validate else None,
    )


def test_a_live_run_retraces_the_first_steps_of_the_full_run_bit_for_bit() -> None:
    run = line_run()
    full_model, full = run.train(progress=False)
    assert full.history.val_step  # the full run validated; the live run does not
    live = live_run(run, 13)
    assert isinstance(live, LiveRun) and live.steps == 13 and live.total_steps == 40 and live.seconds > 0
    assert live.history.val_step == []
    assert live.history.terms["loss"] == full.history.terms["loss"][:13]
    assert live.history.coeffs["beta"] == full.history.coeffs["beta"][:13]
    assert live.history.lr == full.history.lr[:13]
    assert not live.model.training
    whole = live_run(run, 1000)  # at most the run's own steps
    assert whole.steps == 40
    for key, value in whole.model.state_dict().items():
        assert torch.equal(value, full_model.state_dict()[key]), key


def test_a_live_run_leaves_the_callers_random_state_and_the_cache_alone() -> None:
    run = line_run()
    torch.manual_seed(7)
    before = rng_state()
    live_run(run, 5)
    after = rng_state()
    assert torch.equal(before["torch"], after["torch"])
    assert not run.is_cached()


@pytest.mark.parametrize("steps", [0, -3, 2.5, True, "10"])
def test_live_run_rejects_a_bad_number_of_steps(steps) -> None:
    with pytest.raises(ValueError, match="steps must be a positive integer"):
        live_run(line_run(), steps)


def test_live_run_needs_a_run_measured_in_steps() -> None:
    run = line_run(validate=False)
    by_epochs = replace(run, train_config=replace(run.train_config, steps=None, epochs=2))
    with pytest.raises(ValueError, match="measured in epochs"):
        live_run(by_epochs, 3)


def _reference(history: History) -> TrainResult:
    return TrainResult(history, {"steps": float(len(history))}, loaded_from_cache=True)


def test_live_summary_says_whether_the_steps_both_recorded_agree() -> None:
    run = line_run()
    _, full = run.train(progress=False)
    live = live_run(run, 10)
    same = live_summary(live, full)
    assert "trained here 10 of the run's 40 steps" in same and "to the last bit" in same
    assert "At step 9 " in same  # the last step both recorded
    shifted = History.from_dict(full.history.to_dict())
    shifted.terms["loss"] = [value + 0.25 for value in shifted.terms["loss"]]
    differs = live_summary(live, _reference(shifted))
    assert "differ by 0.25" in differs and "to the last bit" not in differs
    later = History.from_dict(full.history.to_dict())
    for field in ("step", "epoch", "lr", "grad_norm"):
        setattr(later, field, getattr(later, field)[20:])
    later.terms = {name: values[20:] for name, values in later.terms.items()}
    later.coeffs = {name: values[20:] for name, values in later.coeffs.items()}
    assert "no step inside the live run" in live_summary(live, _reference(later))


def test_live_summary_does_not_call_a_match_before_the_first_update_a_retraced_run() -> None:
    run = line_run()
    _, full = run.train(progress=False)
    sparse = History.from_dict(full.history.to_dict())  # the reference's record keeps steps 0, 20 and 39 only
    kept = [0, 20, 39]
    for field in ("step", "epoch", "lr", "grad_norm"):
        setattr(sparse, field, [getattr(sparse, field)[i] for i in kept])
    sparse.terms = {name: [values[i] for i in kept] for name, values in sparse.terms.items()}
    sparse.coeffs = {name: [values[i] for i in kept] for name, values in sparse.coeffs.items()}
    summary = live_summary(live_run(run, 10), _reference(sparse))
    assert "At step 0 " in summary and "before the first update" in summary and "retraced" not in summary
    sparse.terms["loss"][0] += 0.25
    differs = live_summary(live_run(run, 10), _reference(sparse))
    assert "differ by 0.25" in differs and "grows as training goes on" not in differs


def test_live_figure_draws_the_live_steps_over_the_reference_record() -> None:
    run = line_run()
    _, full = run.train(progress=False)
    fig = live_figure(live_run(run, 8), full, title="line")
    assert isinstance(fig, Figure)
    (ax,) = fig.axes
    labels = [line.get_label() for line in ax.get_lines()]
    assert labels == [
        "reference run: loss (recorded steps)",
        "reference run: held-out loss",
        "trained here: loss",
    ]
    assert ax.get_xscale() == "log" and ax.get_title() == "line"
    assert list(ax.get_lines()[2].get_xdata()) == list(range(1, 9))


def test_live_figure_on_a_log_loss_axis_needs_a_positive_loss() -> None:
    run = line_run()
    _, full = run.train(progress=False)
    live = live_run(run, 8)
    (ax,) = live_figure(live, full, logy=True).axes
    assert ax.get_yscale() == "log"
    below = History.from_dict(full.history.to_dict())
    below.terms["loss"] = [value - 1e6 for value in below.terms["loss"]]
    with pytest.raises(ValueError, match="logy needs a positive 'loss'"):
        live_figure(live, _reference(below), logy=True)
