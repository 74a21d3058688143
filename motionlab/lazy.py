"""Packages whose public names are imported on first use: ``from motionlab.data import generate`` loads the
generator's module alone, not every module the package lists."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from typing import Any


def lazy_exports(
    package: str, exports: dict[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module-level ``__getattr__`` and ``__dir__`` of ``package`` (its ``__name__``), whose public names
    ``exports`` maps each to the module that holds it. A name is imported on first use and kept in the
    package's namespace; any other name raises ``AttributeError`` as usual.

    Use: ``__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)`` and ``__all__ = sorted(_EXPORTS)``.
    """

    def __getattr__(name: str) -> Any:
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(exports[name]), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__
