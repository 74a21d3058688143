"""Settings of every pytest run, the unit tests' (``tests/``) and the notebooks' under nbval (``notebooks/``):
the quick profile, each notebook cell's time limit, a second start for a notebook's kernel that dies before it
answers, and how ``pytest -n 3 --dist loadscope`` shares the work between its workers."""

import os
import tempfile
import warnings
from pathlib import Path
from typing import Any

import pytest

os.environ.setdefault("MOTIONLAB_PROFILE", "quick")


def _is_notebook_cell(item: pytest.Item) -> bool:
    return type(item).__name__ == "IPyNbCell"


#: Seconds each scope of ``make test`` keeps one pytest worker busy (quick profile, two workers side by side,
#: measured on the faster of the two machines of the project's kind; the order is what counts). The scheduler
#: hands the scopes out longest first, so the workers end together instead of one running a long chapter
#: alone at the end; a scope not listed counts as a second.
TYPICAL_SECONDS: dict[str, float] = {
    "chapter 11": 30.0,  # with the live JupyterLab test
    "chapter 08": 23.0,
    "chapter 06": 22.0,
    "tests/test_execution.py": 21.0,
    "chapter 07": 18.0,
    "tests/test_train_cli.py": 17.0,
    "chapter 04": 15.0,
    "chapter 03": 13.0,
    "chapter 10": 12.0,
    "chapter 02": 10.0,
    "chapter 05": 10.0,
    "tests/test_worker_lifetime.py": 10.0,
    "chapter 09": 10.0,
    "tests/test_course.py": 7.0,
    "chapter 01": 7.0,
    "tests/test_odmo_sampling.py": 6.0,
    "tests/test_stress.py": 5.5,
    "tests/test_train_parallel.py": 5.0,
    "tests/test_report_browser.py": 4.7,
    "tests/test_arguments.py": 4.0,
    "tests/test_train_many.py": 3.8,
    "tests/test_assets.py": 3.7,
    "tests/test_measurements.py": 3.5,
    "tests/test_widgets_diffusion.py": 3.3,
    "tests/test_trajevae_training.py": 3.3,
}


def _scope(nodeid: str) -> str:
    """The xdist scope of a test: ``chapter NN`` for a chapter, its appendices and the live JupyterLab test
    (which drives chapter 11, so it runs on the worker that ran the chapter, with its models in the build's
    cache), else the test's module."""
    path = nodeid.split("::", 1)[0]
    if path.startswith("notebooks/") and path.endswith(".ipynb"):
        return f"chapter {Path(path).name[:2]}"
    if path == "tests/test_jupyterlab_widgets.py":
        return "chapter 11"
    return path


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The longest scopes first (:data:`TYPICAL_SECONDS`); a scope's tests keep their order."""
    items.sort(key=lambda item: -TYPICAL_SECONDS.get(_scope(item.nodeid), 1.0))


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """``--dist loadscope`` over the scopes of :func:`_scope`, in the order of the collection: a chapter and
    its appendices form one scope, so an appendix runs after its chapter on the same worker and reads the
    models and measurements the chapter left in the build (run apart, both would train and measure the same
    models). xdist's own reordering, by the number of tests in a scope, is turned off: a notebook cell and a
    unit test are not the same amount of work."""
    from xdist.scheduler import LoadScopeScheduling

    class ChapterScopeScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return _scope(nodeid)

    if config.getvalue("dist") != "loadscope":
        return None
    config.option.loadscopereorder = False
    return ChapterScopeScheduling(config, log)


def pytest_runtest_setup(item: pytest.Item) -> None:
    """A notebook cell under nbval may run as long as the course build would let it (three times its
    chapter's quick budget, 60-180 s), not nbval's default of 2,000 s: a kernel that stops answering fails
    the cell within minutes, naming it (nbval then stops the kernel, and the chapter's later cells fail at
    once)."""
    if _is_notebook_cell(item):
        from motionlab.course.run import cell_limits

        item.config.option.nbval_cell_timeout = cell_limits(Path(str(item.fspath)).stem).cell_seconds


def retried_kernel_class() -> type:
    """nbval's ``RunningKernel``, started once more when its kernel dies before it answers (as one whose
    randomly chosen ports another process took in the meantime would): nbval sends a kernel's stderr to
    ``/dev/null``, so this keeps it while the kernel starts and puts it in the warning (one death) or the
    error (two)."""
    from nbval.kernel import RunningKernel, start_new_kernel

    class RetriedKernel(RunningKernel):
        def __init__(self, kernel_name: str, cwd: str | None = None, startup_timeout: float = 60) -> None:
            deaths: list[str] = []
            while True:
                with tempfile.TemporaryFile("w+") as stderr:
                    try:
                        self.km, self.kc = start_new_kernel(
                            startup_timeout=startup_timeout, kernel_name=kernel_name, stderr=stderr, cwd=cwd
                        )
                        break
                    except RuntimeError as exc:
                        stderr.seek(0)
                        deaths.append(f"{exc}; its stderr ended with: {stderr.read()[-1500:]!r}")
                if len(deaths) == 2:
                    raise RuntimeError(f"the kernel in {cwd} died twice before it answered: {deaths}")
            if deaths:
                warnings.warn(
                    f"the kernel in {cwd} died before it answered and was started again: {deaths[0]}",
                    stacklevel=2,
                )
            self._ensure_iopub_up()

    return RetriedKernel


def pytest_configure(config: pytest.Config) -> None:
    if config.pluginmanager.hasplugin("nbval"):
        import nbval.plugin

        nbval.plugin.RunningKernel = retried_kernel_class()
