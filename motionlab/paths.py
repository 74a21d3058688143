"""Where the course keeps what it writes; imports nothing heavy, so light commands
(:mod:`motionlab.course.logs`) can use it too."""

from __future__ import annotations

import os
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]


def build_dir() -> Path:
    """Root of everything the course writes: ``build/`` in the repository, or ``MOTIONLAB_BUILD``.

    A relative ``MOTIONLAB_BUILD`` is taken from the repository root, so that the course driver (started in
    the repository) and the notebook kernels (started in ``notebooks/``) mean the same directory.
    """
    path = Path(os.environ.get("MOTIONLAB_BUILD", "build"))
    return path if path.is_absolute() else REPO_ROOT / path
