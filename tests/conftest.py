"""Settings of the unit tests: one torch thread, property tests that do not depend on the
machine's speed, and the shared fixtures (the notebooks' settings: ``conftest.py`` at the top)."""

import os

import pytest
import torch
from hypothesis import HealthCheck, settings

from motionlab import config
from motionlab.course.assets import VENDOR_VARIABLE, vendor_dir

config.set_threads()

# The report's npm packages are fetched and unpacked once for every course build of the tests (each in its
# own temporary MOTIONLAB_BUILD), not once per build.
os.environ.setdefault(VENDOR_VARIABLE, str(vendor_dir().resolve()))

# Hypothesis times each example (its deadline) and the drawing of the first ones (the too_slow health check)
# by the wall clock, so a busy machine could fail a property that holds. Every test's own settings start
# from this profile.
settings.register_profile("motionlab", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("motionlab")


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
