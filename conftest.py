"""Settings of every pytest run, the unit tests' (``tests/``) and the notebooks' under nbval (``notebooks/``):
the quick profile, each notebook cell's time limit, and how ``pytest -n 2 --dist loadscope`` shares the
work between its workers."""

import os
from pathlib import Path
from typing import Any

import pytest

os.environ.setdefault("MOTIONLAB_PROFILE", "quick")


def _is_notebook_cell(item: pytest.Item) -> bool:
    return type(item).__name__ == "IPyNbCell"


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """``--dist loadscope`` with a chapter and its appendices as one scope: the appendix runs after its
    chapter on the same worker and reads the models and measurements the chapter left in the build (run
    apart, both would train and measure the same models). A test module stays one scope."""
    from xdist.scheduler import LoadScopeScheduling

    class ChapterScopeScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.split("::", 1)[0]
            if path.startswith("notebooks/") and path.endswith(".ipynb"):
                return f"chapter {Path(path).name[:2]}"
            return super()._split_scope(nodeid)

    return ChapterScopeScheduling(config, log) if config.getvalue("dist") == "loadscope" else None


def pytest_runtest_setup(item: pytest.Item) -> None:
    """A notebook cell under nbval may run as long as the course build would let it (three times its
    chapter's quick budget, 60-180 s), not nbval's default of 2,000 s: a kernel that stops answering fails
    the cell within minutes, naming it (nbval then stops the kernel, and the chapter's later cells fail at
    once)."""
    if _is_notebook_cell(item):
        from motionlab.course.run import cell_limits

        item.config.option.nbval_cell_timeout = cell_limits(Path(str(item.fspath)).stem).cell_seconds
