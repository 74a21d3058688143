"""The checkpoint cache: trained models under ``build/checkpoints/``, keyed by their configuration.

A cache entry is a file ``<name>-<hash>.pt`` holding a plain dictionary (tensors, numbers, strings,
lists, dicts only, so it loads with ``torch.load(..., weights_only=True)``)::

    {"format": 1, "name": ..., "config": {...}, "state_dict": {...}, "extra": {...}}

The hash covers the name, the configuration (a dataclass or a dict) and the profile, so changing a
hyper-parameter trains a new model instead of loading a stale one. :func:`load_checkpoint` returns
``None`` (and the caller retrains) for a missing, corrupt or mismatched entry; it never half-loads a model.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import tempfile
import warnings
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
    payload = json.dumps({"name": name, "config": config_dict(cfg), "profile": config.profile()}, sort_keys=True)
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


def load_checkpoint(name: str, cfg: Any, model: nn.Module) -> dict[str, Any] | None:
    """Load the cached weights for (name, config) into ``model``; return the entry's ``extra`` dict.

    Returns ``None`` and leaves ``model`` untouched when there is no entry, when it cannot be read,
    when its config differs, or when its tensors do not match the model's parameters (names or shapes),
    i.e. when the code changed since the entry was written.
    """
    path = checkpoint_path(name, cfg)
    if not path.exists():
        return None
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # corrupt or foreign file: the caller retrains
        warnings.warn(f"ignoring unreadable checkpoint {path.name}: {exc}", stacklevel=2)
        return None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        return None
    if payload.get("config") != config_dict(cfg) or payload.get("name") != name:
        return None
    state = payload.get("state_dict")
    current = model.state_dict()
    if not isinstance(state, dict) or state.keys() != current.keys():
        return None
    if any(tuple(state[k].shape) != tuple(current[k].shape) for k in current):
        return None
    model.load_state_dict(state, strict=True)
    return dict(payload.get("extra") or {})
