"""The one training loop of the course: AdamW, schedules, clipping, NaN guard, validation, resumable state.

The caller supplies the model, a loss function and a batch source (see :mod:`motionlab.train.batches`)::

    def loss_fn(model, batch, step, coeffs) -> dict[str, Tensor]:
        recon, kl = ...
        return {"loss": recon + coeffs["beta"] * kl, "recon": recon, "kl": kl}

``"loss"`` is the total that is minimised; every other entry is a named term, logged but not optimised.
Each entry must be a one-element tensor. ``coeffs`` holds the schedules' values at ``step`` (0-based).

What one step does, in order: set the learning rate, evaluate the schedules, call ``loss_fn``, stop with
:class:`NonFiniteLossError` if any term is NaN or infinite (before touching the weights), back-propagate,
measure the global gradient norm (stop if it is not finite), clip it to ``grad_clip``, take the AdamW step,
record the history. After the step: validation (every ``val_every`` steps), the resumable state (every
``checkpoint_every`` steps), the callbacks ``callback(completed_steps, model, history)``.

Determinism: the global RNGs are seeded from ``TrainConfig.seed`` when training starts and the batches of
epoch ``e`` come from a generator seeded by ``(seed, e)``, so the same seed gives bitwise-identical weights.
Training runs in a bubble: the caller's global RNG states are restored when it returns (or raises), so
the code after it behaves the same whether a model was trained or loaded. Validation is isolated too: it
never changes the random numbers training sees.

Resuming: with a :class:`~motionlab.train.state.ResumeFile` the state (model, optimiser, position in the
data, history, RNG states, elapsed time) is written atomically every ``checkpoint_every`` steps and when
training stops at a step boundary: on Ctrl-C (held until the current step ends, see
:class:`~motionlab.train.state.DeferredInterrupt`) and on an exception from a callback or from validation.
The next call with the same run identity continues from it and ends with the same weights, bitwise, as an
uninterrupted run. An exception inside a step (for instance from ``loss_fn``) leaves the last periodic state.

Where it runs: the :class:`~motionlab.train.runtime.Execution` in effect (set by the training command with
:func:`~motionlab.train.runtime.executing`) chooses the device, mixed precision on CUDA and data-parallel
processes; only the first process shows progress and writes the resumable state. The default, one CPU process,
leaves every step exactly as described above.
"""

from __future__ import annotations

import itertools
import math
import time
import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import torch
from torch import Tensor, nn
from torch.nn.utils import clip_grads_with_norm_, get_total_norm
from torch.utils.data import DataLoader
from tqdm.auto import tqdm

from motionlab import config
from motionlab.checkpoints import state_dict_mismatch
from motionlab.train.batches import BatchSource, check_source, epoch_batches, epoch_seed
from motionlab.train.history import History
from motionlab.train.runtime import Execution, data_parallel, local_batch, mean_over_processes
from motionlab.train.runtime import current as current_execution
from motionlab.train.state import DeferredInterrupt, ResumeFile, rng_isolated, rng_state, set_rng_state
from motionlab.train.train_config import TrainConfig

LossFn = Callable[[nn.Module, Any, int, dict[str, float]], dict[str, Tensor]]
Callback = Callable[[int, nn.Module, History], None]

TRAIN_STREAM, VALIDATION_STREAM = 0, 1

#: The seed stream of the data-parallel processes after the first (their own random draws in the loss).
PROCESS_STREAM = 2


class NonFiniteLossError(RuntimeError):
    """A loss term (or the gradient norm) became NaN or infinite; ``term`` and ``step`` say which and when."""

    def __init__(
        self, term: str, step: int, value: float, terms: dict[str, float], during: str = "training"
    ) -> None:
        listing = ", ".join(f"{name}={number:.6g}" for name, number in terms.items())
        what = "the gradient norm" if term == "grad_norm" else f"loss term {term!r}"
        consequence = "; stopped before the weights were updated" if during == "training" else ""
        super().__init__(f"{during}: {what} is {value} at step {step} ({listing}){consequence}")
        self.term = term
        self.step = step
        self.value = value


@dataclass(frozen=True)
class TrainResult:
    """What training (or loading a trained model) gives back; the model itself is updated in place.

    Attributes:
        history: the per-step records (:class:`History`).
        metrics: ``steps``, ``train_seconds`` (summed over resumed sessions), ``train.<term>`` (means over the
            last tenth of the steps) and ``val.<term>`` (the last validation pass, when there was one).
        loaded_from_cache: True when the weights came from the checkpoint cache instead of training.
        path: the cache entry (``None`` for :func:`train` without a cache).
        resumed_from_step: the step training resumed from, ``None`` when it started afresh (or was loaded).
    """

    history: History
    metrics: dict[str, float]
    loaded_from_cache: bool
    path: Path | None = None
    resumed_from_step: int | None = None


def loss_terms(out: Any, step: int, during: str = "training") -> dict[str, float]:
    """Check the loss function's output and return its terms as floats (in the order given).

    Raises ``TypeError`` for a malformed output and :class:`NonFiniteLossError` naming the first non-finite
    term (named terms are checked before the total, so a NaN in ``"kl"`` is reported as ``"kl"``).
    """
    if not isinstance(out, dict) or "loss" not in out:
        raise TypeError(
            f"{during}: loss_fn must return a dict with a 'loss' entry, got {type(out).__name__} "
            f"{list(out) if isinstance(out, dict) else ''}"
        )
    for name, value in out.items():
        if not isinstance(value, Tensor) or value.numel() != 1:
            shape = tuple(value.shape) if isinstance(value, Tensor) else type(value).__name__
            raise TypeError(
                f"{during}: loss term {name!r} at step {step} must be a one-element tensor, got {shape}"
            )
    names = list(out)
    values = torch.stack([out[name].detach().reshape(()).double() for name in names]).tolist()
    terms = dict(zip(names, values))
    for name in sorted(names, key=lambda n: n == "loss"):
        if not math.isfinite(terms[name]):
            raise NonFiniteLossError(name, step, terms[name], terms, during)
    return terms


@dataclass
class _Position:
    """Where training is: steps completed, current epoch, batches of that epoch already used."""

    step: int = 0
    epoch: int = 0
    batch_index: int = 0


@dataclass
class _Trainer:
    """One training run's moving parts; :func:`train` builds it and calls :meth:`run` once."""

    model: nn.Module
    loss_fn: LossFn
    data: BatchSource
    cfg: TrainConfig
    val_data: BatchSource | None
    callbacks: tuple[Callback, ...]
    resume: ResumeFile | None
    execution: Execution = field(default_factory=Execution)
    position: _Position = field(default_factory=_Position)
    history: History = field(default_factory=History)
    seconds_before: float = 0.0
    started: float = 0.0
    saved_step: int = -1
    params: list[nn.Parameter] = field(init=False)
    optimizer: torch.optim.AdamW = field(init=False)
    parallel_loss: nn.Module | None = field(init=False, default=None)

    def __post_init__(self) -> None:
        if self.execution.device.type != "cpu":
            self.model.to(self.execution.device)
        self.params = [p for p in self.model.parameters() if p.requires_grad]
        if not self.params:
            raise ValueError("the model has no trainable parameters")
        self.optimizer = self._new_optimizer()
        if self.execution.distributed:
            self.parallel_loss = data_parallel(self.model, self.loss_fn, self.execution)

    def _new_optimizer(self) -> torch.optim.AdamW:
        return torch.optim.AdamW(
            self.params, lr=self.cfg.lr, betas=tuple(self.cfg.betas), weight_decay=self.cfg.weight_decay
        )

    # --- state -----------------------------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        return {
            "step": self.position.step,
            "epoch": self.position.epoch,
            "batch_index": self.position.batch_index,
            "model": {k: v.detach().clone() for k, v in self.model.state_dict().items()},
            "optimizer": self.optimizer.state_dict(),
            "history": self.history.to_dict(),
            "rng": rng_state(),
            "seconds": self.seconds_before + time.perf_counter() - self.started,
        }

    def restore(self, state: dict[str, Any]) -> bool:
        """Continue from a saved state; False (with a warning, nothing changed) when it does not fit."""
        name = self.resume.path.name if self.resume else "state"
        try:
            position = _Position(int(state["step"]), int(state["epoch"]), int(state["batch_index"]))
            history = History.from_dict(state["history"])
            seconds = float(state["seconds"])
            weights, current = state["model"], self.model.state_dict()
            if len(history) != position.step:
                raise ValueError(f"history has {len(history)} steps, state says {position.step}")
            if (problem := state_dict_mismatch(weights, current)) is not None:
                raise ValueError(problem)
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            warnings.warn(f"ignoring {name}: {exc}", stacklevel=3)
            return False
        backup = {k: v.detach().clone() for k, v in self.model.state_dict().items()}
        try:
            self.model.load_state_dict(weights)
            self.optimizer.load_state_dict(state["optimizer"])
            set_rng_state(state["rng"])
        except Exception as exc:  # optimiser or RNG state from other code: start over, cleanly
            self.model.load_state_dict(backup)
            self.optimizer = self._new_optimizer()
            warnings.warn(f"ignoring {name}: {exc}", stacklevel=3)
            return False
        self.position, self.history, self.seconds_before = position, history, seconds
        return True

    def save(self) -> None:
        if self.resume is not None and self.execution.is_main and self.saved_step != self.position.step:
            self.resume.save(self.state())
            self.saved_step = self.position.step

    # --- the loop --------------------------------------------------------------------------------------
    def finished(self) -> bool:
        if self.cfg.steps is not None:
            return self.position.step >= self.cfg.steps
        return self.position.epoch >= self.cfg.epochs

    def coefficients(self, step: int) -> dict[str, float]:
        return {name: float(schedule(step)) for name, schedule in self.cfg.schedules.items()}

    def train_step(self, batch: Any) -> None:
        step = self.position.step
        lr = self.cfg.lr * (float(self.cfg.lr_schedule(step)) if self.cfg.lr_schedule is not None else 1.0)
        for group in self.optimizer.param_groups:
            group["lr"] = lr
        coeffs = self.coefficients(step)
        self.optimizer.zero_grad(set_to_none=True)
        batch = local_batch(batch, self.execution)
        with self.execution.autocast:
            if self.parallel_loss is not None:
                out = self.parallel_loss(batch, step, coeffs)
            else:
                out = self.loss_fn(self.model, batch, step, coeffs)
        terms = loss_terms(out, step)
        if not out["loss"].requires_grad:
            raise ValueError(f"loss at step {step} does not depend on any trainable parameter")
        out["loss"].backward()
        grads = [p.grad for p in self.params if p.grad is not None]
        if not grads:
            raise ValueError(f"loss at step {step} gave no gradient to any parameter")
        total_norm = get_total_norm(grads)
        grad_norm = float(total_norm)
        if not math.isfinite(grad_norm):
            raise NonFiniteLossError("grad_norm", step, grad_norm, terms)
        if self.cfg.grad_clip is not None:
            clip_grads_with_norm_(self.params, self.cfg.grad_clip, total_norm)
        self.optimizer.step()
        if self.execution.distributed:  # the history holds the global batch's terms
            terms = dict(zip(terms, mean_over_processes(list(terms.values()), self.execution)))
        self.history.record_step(step, self.position.epoch, terms, coeffs, lr, grad_norm)
        self.position.step += 1
        self.position.batch_index += 1

    def validate(self) -> None:
        step = self.position.step
        # the objective the run ends with (its schedules' last values: KL weight, teacher forcing, ...), so
        # that the held-out curve moves with the weights only (a run of unknown length: the current values)
        last = self.total_steps()
        coeffs = self.coefficients(step if last is None else last - 1)
        sums: dict[str, float] = {}
        count = 0
        with rng_isolated(), torch.no_grad():
            # every pass draws the same noise (a VAE's latent, a diffusion step): passes differ by the weights
            torch.manual_seed(epoch_seed(self.cfg.seed, 0, VALIDATION_STREAM))
            self.model.eval()
            try:
                for batch in epoch_batches(
                    self.val_data, self.cfg.seed, 0, self.cfg.batch_size, VALIDATION_STREAM
                ):
                    batch = local_batch(batch, replace(self.execution, rank=0, world_size=1))
                    for name, value in loss_terms(
                        self.loss_fn(self.model, batch, step, coeffs), step, "validation"
                    ).items():
                        sums[name] = sums.get(name, 0.0) + value
                    count += 1
            finally:
                self.model.train()
        if count == 0:
            raise ValueError("validation data yielded no batches")
        self.history.record_validation(step, {name: total / count for name, total in sums.items()})

    def after_step(self, bar: tqdm, interrupt: DeferredInterrupt) -> None:
        step = self.position.step
        bar.update(1)
        if step % self.cfg.log_every == 0:
            window = min(self.cfg.log_every, len(self.history))
            bar.set_postfix(
                {k: f"{sum(v[-window:]) / window:.4g}" for k, v in self.history.terms.items()}, refresh=False
            )
        try:
            if self.val_data is not None and self.cfg.val_every and step % self.cfg.val_every == 0:
                self.validate()
            if self.cfg.checkpoint_every and step % self.cfg.checkpoint_every == 0:
                self.save()
            for callback in self.callbacks:
                callback(step, self.model, self.history)
        except BaseException:
            self.save()
            raise
        if interrupt.requested:
            self.save()
            where = (
                f"state saved to {self.resume.path}; call again to resume"
                if self.resume
                else "no resume file"
            )
            raise KeyboardInterrupt(f"training interrupted after step {step} ({where})")

    def run_epochs(self, bar: tqdm, interrupt: DeferredInterrupt) -> None:
        while not self.finished():
            pos = self.position
            # Building the epoch's iterator and skipping the batches a saved state already used must not move
            # the global RNGs, so that a resumed run draws exactly what an uninterrupted one draws.
            with rng_isolated():
                batches = epoch_batches(
                    self.data, self.cfg.seed, pos.epoch, self.cfg.batch_size, TRAIN_STREAM
                )
                skipped = sum(1 for _ in itertools.islice(batches, pos.batch_index))
            if skipped < pos.batch_index:
                raise ValueError(
                    f"the batch source gave {skipped} batches in epoch {pos.epoch}, but the saved "
                    f"state had used {pos.batch_index}: it is not deterministic"
                )
            for batch in batches:
                self.train_step(batch)
                self.after_step(bar, interrupt)
                if self.finished():
                    return
            if pos.batch_index == 0:
                raise ValueError(f"the batch source yielded no batches in epoch {pos.epoch}")
            pos.epoch += 1
            pos.batch_index = 0

    def run(self, progress: bool, desc: str) -> TrainResult:
        with rng_isolated(), DeferredInterrupt() as interrupt:
            self.started = time.perf_counter()
            saved = self.resume.load() if self.resume is not None and self.execution.resume else None
            resumed = saved is not None and self.restore(saved)
            if not resumed:
                config.seed_everything(self.cfg.seed)
            if self.execution.rank > 0:  # its own draws in the loss (noise), reproducible per step
                torch.manual_seed(
                    epoch_seed(self.cfg.seed, self.position.step, PROCESS_STREAM + self.execution.rank)
                )
            self.saved_step = self.position.step if resumed else -1
            resumed_from = self.position.step if resumed else None
            self.model.train()
            with tqdm(
                total=self.total_steps(),
                initial=self.position.step,
                disable=not progress,
                desc=desc,
                mininterval=1.0,
                dynamic_ncols=True,
            ) as bar:
                self.run_epochs(bar, interrupt)
            if self.val_data is not None and (
                not self.history.val_step or self.history.val_step[-1] != self.position.step
            ):
                self.validate()
        self.model.eval()
        if self.execution.device.type != "cpu":
            self.model.to("cpu")
        metrics: dict[str, float] = {
            "steps": float(self.position.step),
            "train_seconds": self.seconds_before + time.perf_counter() - self.started,
        }
        metrics.update({f"train.{name}": value for name, value in self.history.final_means().items()})
        metrics.update({f"val.{name}": values[-1] for name, values in self.history.val_terms.items()})
        return TrainResult(self.history, metrics, loaded_from_cache=False, resumed_from_step=resumed_from)

    def total_steps(self) -> int | None:
        """The progress bar's total: known in steps, or in epochs of a DataLoader over a sized data set."""
        if self.cfg.steps is not None:
            return self.cfg.steps
        try:
            return self.cfg.epochs * len(self.data) if isinstance(self.data, DataLoader) else None
        except TypeError:  # an iterable-style data set has no length
            return None


def train(
    model: nn.Module,
    loss_fn: LossFn,
    data: BatchSource,
    cfg: TrainConfig,
    *,
    val_data: BatchSource | None = None,
    progress: bool | None = None,
    callbacks: Iterable[Callback] = (),
    resume: ResumeFile | None = None,
    desc: str = "train",
) -> TrainResult:
    """Train ``model`` in place with AdamW; return its history and final metrics (see the module docstring).

    Args:
        model: any ``nn.Module``; left in ``eval()`` mode at the end.
        loss_fn: ``loss_fn(model, batch, step, coeffs) -> {"loss": total, name: term, ...}``.
        data: the training batch source (a DataLoader or ``batches(epoch, generator, batch_size)``).
        cfg: the :class:`TrainConfig`.
        val_data: optional validation batch source; each pass averages the terms over its batches.
        progress: show a ``tqdm.auto`` progress bar; ``None`` means on in the full profile, off in the quick
            profile (tests and nbval), so headless runs stay quiet.
        callbacks: called as ``callback(completed_steps, model, history)`` after every step.
        resume: where to keep the resumable state (``train_or_load`` passes one); ``None`` for none.
        desc: the progress bar's label.
    """
    if not isinstance(model, nn.Module):
        raise TypeError(f"model must be an nn.Module, got {type(model).__name__}")
    if not isinstance(cfg, TrainConfig):
        raise TypeError(f"cfg must be a TrainConfig, got {type(cfg).__name__}")
    if not callable(loss_fn):
        raise TypeError("loss_fn must be callable as loss_fn(model, batch, step, coeffs)")
    check_source(data, cfg.batch_size, "data")
    if val_data is not None:
        check_source(val_data, cfg.batch_size, "val_data")
    execution = current_execution()
    if execution.checkpoint_every is not None:
        cfg = replace(cfg, checkpoint_every=execution.checkpoint_every)
    callbacks = (*callbacks, *execution.callbacks)
    trainer = _Trainer(model, loss_fn, data, cfg, val_data, tuple(callbacks), resume, execution)
    show = not config.is_quick() if progress is None else bool(progress)
    return trainer.run(progress=show and execution.is_main, desc=desc)
