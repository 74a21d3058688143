"""The model families the training command knows: each family's name and its chapter's experiment module.

Every experiment module has the same few names, which the command (:mod:`motionlab.apps.training`) uses as
the chapter does:

* ``CHAPTER`` and ``DEFAULT_RUN`` (the run trained when ``--run`` is not given);
* ``ExperimentConfig`` with ``quick()``, ``full()`` and the longer ``long()``;
* ``load_data(cfg)``: what the runs train on and are measured with (``READS_FOLDER = True`` and
  ``load_data(cfg, folder)`` for a family that reads a folder of clips given as ``--data PATH``);
* ``runs(cfg, data)``: ``{name: Run}``, each a :class:`~motionlab.train.run.Run` (its ``train_config``
  carries the seed that ``--seed`` sets);
* ``measure(cfg, data, name, model)``: the chapter's measurements of a trained model;
* ``with_steps(cfg, name, steps)``: ``cfg`` with run ``name`` trained for ``steps`` optimiser steps.

Modules are imported only when a family is used, so ``--help`` is quick. Adding a family (or a data set,
as ``moglow_cmu``, ``odmo_cmu`` and ``diffusion_cmu`` are MoGlow, ODMO and MDM on the CMU clips of chapter
10) is one entry here and a module of that shape.
"""

from __future__ import annotations

import dataclasses
import importlib
from types import ModuleType
from typing import Any

#: ``{family name: experiment module}``.
FAMILIES: dict[str, str] = {
    "vae": "motionlab.models.vae.experiment",
    "motion_cell": "motionlab.models.motion_cell.experiment",
    "moglow": "motionlab.models.moglow.experiment",
    "moglow_cmu": "motionlab.models.moglow.real_experiment",
    "trajevae": "motionlab.models.trajevae.experiment",
    "odmo": "motionlab.models.odmo.experiment",
    "odmo_cmu": "motionlab.models.odmo.real_experiment",
    "diffusion": "motionlab.models.diffusion.experiment",
    "diffusion_cmu": "motionlab.models.diffusion.real_experiment",
}


def family(name: str) -> ModuleType:
    """The experiment module of family ``name`` (a key of :data:`FAMILIES`)."""
    if name not in FAMILIES:
        raise ValueError(f"family: unknown family {name!r}; one of {', '.join(FAMILIES)}")
    return importlib.import_module(FAMILIES[name])


def jsonable(value: Any) -> Any:
    """``value`` as plain JSON types: intervals as ``{"mean", "ci95"}``, tensors and arrays as lists,
    dataclasses and named tuples as dicts, dict keys as strings."""
    if hasattr(value, "half_width") and hasattr(value, "mean"):  # motionlab.metrics.Interval
        return {"mean": float(value.mean), "ci95": float(value.half_width)}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, tuple) and hasattr(value, "_asdict"):
        return {key: jsonable(item) for key, item in value._asdict().items()}
    if isinstance(value, dict):
        return {str(key): jsonable(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(item) for item in value]
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return repr(value)
