"""Shared test settings: quick profile, one torch thread, and each notebook cell's time limit under nbval."""

import os
from pathlib import Path

import pytest
import torch

os.environ.setdefault("MOTIONLAB_PROFILE", "quick")

from motionlab import config  # noqa: E402

config.set_threads()


def pytest_runtest_setup(item) -> None:
    """A notebook cell under nbval may run as long as the course build would let it (three times its
    chapter's quick budget, 60-120 s), not nbval's default of 2,000 s: a kernel that stops answering fails
    the cell within two minutes, naming it (nbval then stops the kernel, and the chapter's later cells fail
    at once)."""
    if type(item).__name__ == "IPyNbCell":
        from motionlab.course.run import cell_limits

        item.config.option.nbval_cell_timeout = cell_limits(Path(str(item.fspath)).stem).cell_seconds


@pytest.fixture
def tiny_model() -> torch.nn.Module:
    """A Motion Cell of the smallest size, built from ``test_motion_cell_common.TINY`` with seed 0."""
    from test_motion_cell_common import motion_cell

    return motion_cell()


@pytest.fixture
def tiny_batch():
    """A two-clip :class:`WindowBatch` of the tiny Motion Cell's codec."""
    from test_motion_cell_common import batch

    return batch()
