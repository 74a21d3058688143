"""What a training run records: every step's loss terms, coefficients, learning rate and gradient norm.

A :class:`History` is plain lists of Python numbers, so it goes into a checkpoint as is (see
:meth:`History.to_dict`) and comes back with ``torch.load(..., weights_only=True)``. Per-epoch means are
computed from the per-step records, never stored twice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np


@dataclass
class History:
    """Per-step and validation records of one training run.

    Attributes (``n`` = steps taken, ``v`` = validation passes):
        step: ``n`` 0-based step indices (the ``step`` the loss function saw).
        epoch: ``n`` epoch index of each step.
        terms: loss term name -> ``n`` values (``"loss"`` is the total that was minimised).
        coeffs: schedule name -> ``n`` values the loss function received.
        lr: ``n`` learning rates.
        grad_norm: ``n`` global gradient L2 norms, measured before clipping.
        val_step: ``v`` numbers of steps completed when validation ran.
        val_terms: loss term name -> ``v`` validation means.
    """

    step: list[int] = field(default_factory=list)
    epoch: list[int] = field(default_factory=list)
    terms: dict[str, list[float]] = field(default_factory=dict)
    coeffs: dict[str, list[float]] = field(default_factory=dict)
    lr: list[float] = field(default_factory=list)
    grad_norm: list[float] = field(default_factory=list)
    val_step: list[int] = field(default_factory=list)
    val_terms: dict[str, list[float]] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.step)

    def record_step(
        self,
        step: int,
        epoch: int,
        terms: dict[str, float],
        coeffs: dict[str, float],
        lr: float,
        grad_norm: float,
    ) -> None:
        """Append one optimiser step. The term names must be the same at every step."""
        if self.step and set(terms) != set(self.terms):
            raise ValueError(
                f"loss_fn returned terms {sorted(terms)} at step {step} but {sorted(self.terms)} before"
            )
        self.step.append(int(step))
        self.epoch.append(int(epoch))
        for name, value in terms.items():
            self.terms.setdefault(name, []).append(float(value))
        for name, value in coeffs.items():
            self.coeffs.setdefault(name, []).append(float(value))
        self.lr.append(float(lr))
        self.grad_norm.append(float(grad_norm))

    def record_validation(self, completed_steps: int, terms: dict[str, float]) -> None:
        """Append one validation pass run after ``completed_steps`` steps."""
        if self.val_step and set(terms) != set(self.val_terms):
            raise ValueError(
                f"validation returned terms {sorted(terms)} after {completed_steps} steps "
                f"but {sorted(self.val_terms)} before"
            )
        self.val_step.append(int(completed_steps))
        for name, value in terms.items():
            self.val_terms.setdefault(name, []).append(float(value))

    def epoch_means(self) -> dict[str, np.ndarray]:
        """Mean of each term over the steps of each epoch: name -> array ``(number of epochs seen,)``.

        Epochs are listed in order of appearance; the last one may be partial.
        """
        epochs = np.asarray(self.epoch)
        order = list(dict.fromkeys(self.epoch))
        return {
            name: np.array([np.mean(np.asarray(values)[epochs == e]) for e in order])
            for name, values in self.terms.items()
        }

    def final_means(self) -> dict[str, float]:
        """Mean of each term over the last tenth of the steps (at least one step)."""
        if not self.step:
            raise ValueError("history is empty: no step was recorded")
        window = max(1, len(self.step) // 10)
        return {name: float(np.mean(values[-window:])) for name, values in self.terms.items()}

    def to_dict(self) -> dict[str, Any]:
        """Plain lists and dicts (fits a ``weights_only`` checkpoint)."""
        return {f.name: _copy(getattr(self, f.name)) for f in fields(self)}

    @classmethod
    def from_dict(cls, data: Any) -> History:
        """Inverse of :meth:`to_dict`; raises ``ValueError`` naming the first malformed field."""
        if not isinstance(data, dict):
            raise ValueError(f"history must be a dict, got {type(data).__name__}")
        names = [f.name for f in fields(cls)]
        if set(data) != set(names):
            raise ValueError(f"history fields {sorted(data)} differ from {sorted(names)}")
        history = cls(**{name: _copy(data[name]) for name in names})
        history._check_lengths()
        return history

    def _check_lengths(self) -> None:
        n, v = len(self.step), len(self.val_step)
        per_step = {"epoch": self.epoch, "lr": self.lr, "grad_norm": self.grad_norm}
        per_step.update({f"terms[{k!r}]": x for k, x in self.terms.items()})
        per_step.update({f"coeffs[{k!r}]": x for k, x in self.coeffs.items()})
        for name, values in per_step.items():
            if len(values) != n:
                raise ValueError(f"history.{name} must be a list of {n} values")
        for name, values in self.val_terms.items():
            if len(values) != v:
                raise ValueError(f"history.val_terms[{name!r}] must be a list of {v} values")
        if any(not math.isfinite(x) for values in self.terms.values() for x in values):
            raise ValueError("history.terms holds a non-finite value")


def _copy(value: Any) -> Any:
    """A copy of a history field: a list, or a dict of lists."""
    if isinstance(value, dict):
        return {name: _copy_list(values) for name, values in value.items()}
    return _copy_list(value)


def _copy_list(value: Any) -> list:
    if not isinstance(value, list):
        raise ValueError(f"history field must be a list or a dict of lists, got {type(value).__name__}")
    return list(value)
