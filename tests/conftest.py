"""Settings of the unit tests: one torch thread, property tests that do not depend on the
machine's speed, and the shared fixtures (the notebooks' settings: ``conftest.py`` at the top)."""

import dataclasses
import os
from collections.abc import Callable

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


@pytest.fixture
def check_validation_leaves_weights() -> Callable[..., None]:
    """``check(run, validated)``: train :class:`~motionlab.train.run.Run` ``run`` again without validation and
    assert that ``validated``, the model its validating ``run.train()`` gave, has bit for bit the same weights
    (a validation pass must leave the training alone)."""

    def check(run, validated: torch.nn.Module) -> None:
        plain_run = dataclasses.replace(
            run, train_config=dataclasses.replace(run.train_config, val_every=None), val_batches=None
        )
        plain, plain_result = plain_run.train(progress=False)
        assert plain_result.history.val_step == []
        for key, value in validated.state_dict().items():
            assert torch.equal(value, plain.state_dict()[key]), key

    return check
