"""Shared test settings: quick profile, one torch thread, property tests that do not depend on the machine's
speed, and each notebook cell's time limit under nbval."""

import os
from pathlib import Path

import pytest
import torch
from hypothesis import HealthCheck, settings

os.environ.setdefault("MOTIONLAB_PROFILE", "quick")

from motionlab import config  # noqa: E402

config.set_threads()

# Hypothesis times each example (its deadline) and the drawing of the first ones (the too_slow health check)
# by the wall clock, so a busy machine could fail a property that holds. Every test's own settings start
# from this profile.
settings.register_profile("motionlab", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("motionlab")


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
