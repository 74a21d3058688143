"""The checkpoint cache: trained models under ``build/checkpoints/``, keyed by their configuration.

A cache entry is a file ``<name>-<hash>.pt`` holding a plain dictionary (tensors, numbers, strings,
lists, dicts only, so it loads with ``torch.load(..., weights_only=True)``)::

    {"format": 1, "name": ..., "config": {...}, "state_dict": {...}, "extra": {...}}

The hash covers the name, the configuration (a dataclass or a dict) and the profile, so changing a
hyper-parameter trains a new model instead of loading a stale one. :func:`load_checkpoint` returns
``None`` (and the caller retrains) for a missing, corrupt or mismatched entry, e.g. one written by an older
version of the model's code; it never half-loads a model, and warns in one line why it ignored an entry.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import tempfile
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import torch
from torch import nn

from motionlab import config

FORMAT = 1


def config_dict(cfg: Any) -> dict[str, Any]:
    """A JSON-ready dictionary of a config dataclass (or a dict), with tuples turned into lists."""
    if dataclasses.is_dataclass(cfg) and not isinstance(cfg, type):
        raw = dataclasses.asdict(cfg)
    elif isinstance(cfg, dict):
        raw = dict(cfg)
    else:
        raise TypeError(f"config must be a dataclass instance or a dict, got {type(cfg).__name__}")
    return json.loads(json.dumps(raw, sort_keys=True, default=_jsonable))


def _jsonable(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return dataclasses.asdict(value)
    if isinstance(value, (set, frozenset)):
        return sorted(value)
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"cannot put {type(value).__name__} into a checkpoint config")


def config_hash(name: str, cfg: Any) -> str:
    """Twelve hex digits identifying (name, config, profile)."""
    payload = json.dumps(
        {"name": name, "config": config_dict(cfg), "profile": config.profile()}, sort_keys=True
    )
    return hashlib.sha256(payload.encode()).hexdigest()[:12]


def checkpoint_path(name: str, cfg: Any) -> Path:
    """Where the cache entry for (name, config) lives."""
    if not name or any(ch in name for ch in "/\\ "):
        raise ValueError(f"checkpoint name must be a simple identifier, got {name!r}")
    return config.checkpoint_dir() / f"{name}-{config_hash(name, cfg)}.pt"


def save_checkpoint(name: str, cfg: Any, model: nn.Module, extra: dict[str, Any] | None = None) -> Path:
    """Store ``model``'s state dict with its config (atomically: a crash never leaves half a file)."""
    path = checkpoint_path(name, cfg)
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = {
        "format": FORMAT,
        "name": name,
        "config": config_dict(cfg),
        "state_dict": {k: v.detach().cpu() for k, v in model.state_dict().items()},
        "extra": extra or {},
    }
    with tempfile.NamedTemporaryFile(dir=path.parent, delete=False, suffix=".tmp") as handle:
        tmp = handle.name
    torch.save(payload, tmp)
    os.replace(tmp, path)
    return path


def _listing(names: Iterable[Any], limit: int = 4) -> str:
    """Sorted names, quoted and comma-separated; past ``limit`` of them, a count of the rest."""
    ordered = sorted(names, key=str)
    shown = ", ".join(repr(name) for name in ordered[:limit])
    return shown if len(ordered) <= limit else f"{shown} and {len(ordered) - limit} more"


def state_dict_mismatch(saved: Any, current: dict[str, Any]) -> str | None:
    """Why the tensors ``saved`` cannot go into a model whose state dict is ``current``; ``None`` when they
    fit.

    They fit when they have the same names and each has the model's shape (``load_state_dict`` casts dtypes).
    """
    if not isinstance(saved, dict):
        return f"the state dict is a {type(saved).__name__}, not a dict"
    names: list[str] = []
    if missing := current.keys() - saved.keys():
        names.append(f"lacks {_listing(missing)}")
    if unexpected := saved.keys() - current.keys():
        names.append(f"has unexpected {_listing(unexpected)}")
    problems = [f"the state dict {' and '.join(names)}"] if names else []
    for key in sorted(current.keys() & saved.keys()):
        old, new = saved[key], current[key]
        if isinstance(new, torch.Tensor) and not isinstance(old, torch.Tensor):
            problems.append(f"{key!r} is a {type(old).__name__}, not a tensor")
        elif isinstance(new, torch.Tensor) and old.shape != new.shape:
            problems.append(f"{key!r} has shape {tuple(old.shape)}, the model's {tuple(new.shape)}")
    return "; ".join(problems) or None


def _flat(value: Any, prefix: str = "") -> dict[str, Any]:
    """A nested config as ``{"model.hidden": 16, ...}``: dictionaries are opened, anything else is a leaf."""
    if not isinstance(value, dict) or not value:
        return {prefix: value}
    flat: dict[str, Any] = {}
    for key, item in value.items():
        flat.update(_flat(item, f"{prefix}.{key}" if prefix else str(key)))
    return flat


def _config_mismatch(saved: Any, current: dict[str, Any]) -> str | None:
    """How a stored config differs from the current one (keys gone, keys new, values changed); ``None`` if
    equal."""
    if saved == current:
        return None
    old, new = _flat(saved), _flat(current)
    problems: list[str] = []
    if gone := old.keys() - new.keys():
        problems.append(f"has keys the code no longer has ({_listing(gone)})")
    if added := new.keys() - old.keys():
        problems.append(f"lacks {_listing(added)}")
    if changed := {key for key in old.keys() & new.keys() if old[key] != new[key]}:
        problems.append(f"differs at {_listing(changed)}")
    return "its config " + ("; ".join(problems) or "differs")


def _entry_mismatch(payload: Any, name: str, cfg: Any, model: nn.Module) -> str | None:
    """Why a loaded cache entry does not fit (name, config, model); ``None`` when it does."""
    if not isinstance(payload, dict):
        return f"it holds a {type(payload).__name__}, not a checkpoint dictionary"
    if payload.get("format") != FORMAT:
        return f"its format is {payload.get('format')!r}, this code reads {FORMAT}"
    if payload.get("name") != name:
        return f"it was written for {payload.get('name')!r}"
    if not isinstance(payload.get("extra") or {}, dict):
        return f"its extra is a {type(payload['extra']).__name__}, not a dict"
    return _config_mismatch(payload.get("config"), config_dict(cfg)) or state_dict_mismatch(
        payload.get("state_dict"), model.state_dict()
    )


class CheckpointRefused(ValueError):
    """A checkpoint that must fit and does not: a reference model (``load_checkpoint(refuse=True)``)."""


def load_checkpoint(
    name: str, cfg: Any, model: nn.Module, path: Path | None = None, refuse: bool = False
) -> dict[str, Any] | None:
    """Load the cached weights for (name, config) into ``model``; return the entry's ``extra`` dict.

    Returns ``None`` and leaves ``model`` untouched when there is no entry, and also (with a one-line
    warning saying why) when the entry cannot be read, has another format, name or config, or its
    tensors do not match the model's (names or shapes): when it was written by other code. ``path`` reads
    another file than the cache entry (a reference model); with ``refuse=True`` an entry that cannot be read
    or does not fit raises :class:`CheckpointRefused` instead (the caller must not quietly retrain).
    """
    path = checkpoint_path(name, cfg) if path is None else path
    if not path.exists():
        return None
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # corrupt or foreign file: the caller retrains
        if refuse:
            raise CheckpointRefused(f"cannot read {path}: {exc}") from None
        warnings.warn(f"ignoring unreadable checkpoint {path.name}: {exc}", stacklevel=2)
        return None
    problem = _entry_mismatch(payload, name, cfg, model)
    if problem is not None:
        if refuse:
            raise CheckpointRefused(f"refusing {path}: {problem}")
        warnings.warn(f"ignoring checkpoint {path.name}: {problem}", stacklevel=2)
        return None
    model.load_state_dict(payload["state_dict"], strict=True)
    return dict(payload.get("extra") or {})
