"""Argument checks shared by the command lines (``python -m motionlab.data.synthetic``, ``python -m
motionlab.bench``).

A bad argument ends a command with a one-line message on stderr and exit status 2, never a traceback:
the ``type=`` functions here make argparse reject bad values while parsing (argparse prints its usage and
``error: argument --x: ...``), and :func:`run` turns the user errors that only show later (a ``ValueError``
from a library check, an ``OSError`` from writing the output, a ``MemoryError`` or ``OverflowError`` from
asking for more data than the machine holds or a float can count) into ``<prog>: error: ...``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

N = TypeVar("N", int, float)

#: The exceptions :func:`run` reports as a user error; anything else is a bug and keeps its traceback.
USER_ERRORS = (ValueError, OSError, MemoryError, OverflowError)


def _at_least(parse: Callable[[str], N], what: str, minimum: N) -> Callable[[str], N]:
    """An argparse ``type=``: ``parse(text)``, finite and at least ``minimum``, else a message naming
    ``what``."""

    def check(text: str) -> N:
        try:
            value: N | None = parse(text)
        except ValueError:
            value = None
        if value is None or (isinstance(value, float) and not math.isfinite(value)) or value < minimum:
            raise argparse.ArgumentTypeError(f"must be {what} of at least {minimum:g}, got {text!r}")
        return value

    return check


def int_at_least(minimum: int) -> Callable[[str], int]:
    """An argparse ``type=`` accepting a whole number of at least ``minimum`` (``"1.5"`` and ``"x"`` are
    refused)."""
    return _at_least(int, "an integer", minimum)


def float_at_least(minimum: float) -> Callable[[str], float]:
    """An argparse ``type=`` accepting a finite number of at least ``minimum`` (``nan`` and ``inf`` are
    refused)."""
    return _at_least(float, "a finite number", minimum)


positive_int = int_at_least(1)
non_negative_int = int_at_least(0)


def output_file(text: str) -> Path:
    """An argparse ``type=`` for a file to write: its directory must exist and be writable, and it must not be
    a directory itself. (Checked before the work starts, so a typo in the path does not cost a long run.)"""
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a directory, expected a file name")
    folder = path.parent
    if not folder.exists():
        raise argparse.ArgumentTypeError(f"directory {str(folder)!r} of {text!r} does not exist")
    if not folder.is_dir():
        raise argparse.ArgumentTypeError(f"{str(folder)!r} in {text!r} is not a directory")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"directory {str(folder)!r} of {text!r} is not writable")
    return path


def existing_directory(text: str) -> Path:
    """An argparse ``type=`` for a directory to read: it must exist and be a directory."""
    path = Path(text)
    if not path.exists():
        raise argparse.ArgumentTypeError(f"directory {text!r} does not exist")
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is not a directory")
    return path


def run(prog: str, command: Callable[[], int]) -> int:
    """``command()``'s exit status; a :data:`USER_ERRORS` exception is printed as one line and gives status
    2."""
    try:
        return command()
    except USER_ERRORS as exc:
        message = " ".join(str(exc).split()) or type(exc).__name__
        print(f"{prog}: error: {message}", file=sys.stderr)
        return 2
