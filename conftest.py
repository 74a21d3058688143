"""Settings of every pytest run, the unit tests' (``tests/``) and the notebooks' under nbval (``notebooks/``):
the quick profile, each notebook cell's time limit, and how ``pytest -n 2 --dist loadgroup`` shares the
work between its workers."""

import os
from pathlib import Path

import pytest

os.environ.setdefault("MOTIONLAB_PROFILE", "quick")


def _is_notebook_cell(item: pytest.Item) -> bool:
    return type(item).__name__ == "IPyNbCell"


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """One xdist group per test module, and one per chapter for a chapter and its appendices: the appendix
    runs after its chapter on the same worker and reads the models and measurements the chapter left in the
    build (run apart, both would train and measure the same models)."""
    for item in items:
        path = Path(str(item.fspath))
        group = f"chapter-{path.stem[:2]}" if _is_notebook_cell(item) else str(path)
        item.add_marker(pytest.mark.xdist_group(group))


def pytest_runtest_setup(item: pytest.Item) -> None:
    """A notebook cell under nbval may run as long as the course build would let it (three times its
    chapter's quick budget, 60-180 s), not nbval's default of 2,000 s: a kernel that stops answering fails
    the cell within minutes, naming it (nbval then stops the kernel, and the chapter's later cells fail at
    once)."""
    if _is_notebook_cell(item):
        from motionlab.course.run import cell_limits

        item.config.option.nbval_cell_timeout = cell_limits(Path(str(item.fspath)).stem).cell_seconds
