"""Executing notebooks: a cell over its limit fails, a kernel that stops answering is caught within seconds,
named and killed, and the course build executes such a chapter once more in a fresh kernel, as it does one
whose kernel died before it answered."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import nbformat
import pytest

from motionlab.course import run as course
from motionlab.course.kernel import CellLimits, KernelNotAnswering, execute_notebook

#: Makes the kernel drop the reply of every execute request from this one on (as a lost reply would look).
DROP_REPLIES = """\
kernel = get_ipython().kernel
send = kernel.session.send
def send_but_execute_replies(stream, msg_or_type, *args, **kwargs):
    kind = msg_or_type if isinstance(msg_or_type, str) else msg_or_type["header"]["msg_type"]
    if kind == "execute_reply":
        return {"content": {"status": "ok"}}
    return send(stream, msg_or_type, *args, **kwargs)
kernel.session.send = send_but_execute_replies"""

#: Makes the kernel ignore every later shell request (as a request that is never read would look).
IGNORE_REQUESTS = """\
kernel = get_ipython().kernel
async def ignore(*args, **kwargs):
    return None
kernel.dispatch_shell = ignore"""


#: The answer limit of these tests' kernels: a kernel that is not broken answers within milliseconds, on a
#: busy machine too; a broken one is found after it, and the tests wait for nothing longer.
ANSWER_SECONDS = 2.0


def _notebook(*sources: str) -> nbformat.NotebookNode:
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell(source) for source in sources]
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    return notebook


@pytest.mark.parametrize(
    ("breaker", "missing", "cell"),
    [(DROP_REPLIES, "reply never came", 1), (IGNORE_REQUESTS, "never started", 2)],
)
def test_a_kernel_that_stops_answering_is_named_diagnosed_and_killed(
    tmp_path: Path, breaker: str, missing: str, cell: int
):
    limits = CellLimits(cell_seconds=120, answer_seconds=ANSWER_SECONDS)
    execution = execute_notebook(
        _notebook("print('fine')", breaker, "print('never answered')"), tmp_path, limits
    )
    assert execution.hung and execution.failed_cell == cell
    error = execution.error
    assert isinstance(error, KernelNotAnswering) and missing in error.missing
    # Caught by the answer limit (seconds after it), long before the cell's limit, on a busy machine too.
    assert limits.answer_seconds <= error.waited < limits.cell_seconds / 4
    assert error.diagnosis["control_answers"] is True  # the control channel still answers
    assert execution.notebook.cells[0].outputs[0]["text"] == "fine\n"
    assert execution.seconds < limits.cell_seconds


def test_a_cell_past_its_limit_fails_with_the_limit_in_the_message(tmp_path: Path):
    execution = execute_notebook(
        _notebook("1", "import time\ntime.sleep(600)"), tmp_path, CellLimits(cell_seconds=2)
    )
    assert not execution.hung and execution.failed_cell == 1
    assert "timed out (limit 2 s)" in str(execution.error)
    assert execution.seconds < 300  # the sleep was cut short (the kernel's start and end included)


def test_cell_limits_come_from_the_chapter_budget(monkeypatch):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    monkeypatch.delenv("MOTIONLAB_RETRAIN", raising=False)
    monkeypatch.delenv("MOTIONLAB_SEED", raising=False)
    assert course.cell_limits("04_motion_cell").cell_seconds == course.CELL_BUDGET_FACTOR * 240
    assert course.cell_limits("99_extra").cell_seconds == course.DEFAULT_CELL_SECONDS
    # a build that trains its models (another base seed, RETRAIN) is not held to the loading budgets
    monkeypatch.setenv("MOTIONLAB_SEED", "1")
    assert course.cell_limits("06_moglow").cell_seconds == course.TRAINING_CELL_SECONDS
    monkeypatch.delenv("MOTIONLAB_SEED")
    monkeypatch.setenv("MOTIONLAB_RETRAIN", "1")
    assert course.cell_limits("06_moglow").cell_seconds == course.TRAINING_CELL_SECONDS
    monkeypatch.delenv("MOTIONLAB_RETRAIN")
    # nor is `make reference ALL=0`, which trains the runs whose configuration changed
    monkeypatch.setenv("MOTIONLAB_REFERENCE_BUILD", "1")
    assert course.cell_limits("06_moglow").cell_seconds == course.TRAINING_CELL_SECONDS
    monkeypatch.delenv("MOTIONLAB_PARALLEL", raising=False)
    assert course.parallel() == 1
    monkeypatch.setenv("MOTIONLAB_REFERENCE_BUILD", "yes")
    with pytest.raises(ValueError, match="MOTIONLAB_REFERENCE_BUILD must be 1 or 0, got 'yes'"):
        course.loads_references()
    monkeypatch.delenv("MOTIONLAB_REFERENCE_BUILD")
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    assert course.cell_limits("01_rotation_geometry").cell_seconds == course.CELL_BUDGET_FACTOR * 20
    with pytest.raises(ValueError, match="CellLimits: cell_seconds must be greater than 0, got 0"):
        CellLimits(cell_seconds=0)
    with pytest.raises(ValueError, match="CellLimits: answer_seconds must be a finite number, got inf"):
        CellLimits(cell_seconds=1, answer_seconds=float("inf"))
    with pytest.raises(TypeError, match=r"CellLimits: cell_seconds must be a real number, got '60' \(str\)"):
        CellLimits(cell_seconds="60")


def _chapter(tmp_path: Path, name: str, *sources: str) -> Path:
    path = tmp_path / "notebooks" / f"{name}.ipynb"
    path.parent.mkdir(exist_ok=True)
    nbformat.write(_notebook(*sources), path)
    return path


@pytest.fixture
def build(monkeypatch, tmp_path: Path) -> Path:
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "build"))
    monkeypatch.setattr(course, "ANSWER_SECONDS", ANSWER_SECONDS)
    return tmp_path / "build" / "course-quick"


def test_a_kernel_that_hangs_once_is_executed_again_and_one_that_hangs_twice_fails_naming_the_cell(
    tmp_path: Path, build, monkeypatch
):
    """Both chapters in one build, side by side (two notebooks at a time), so their waits overlap."""
    monkeypatch.setenv("MOTIONLAB_PARALLEL", "2")
    marker = tmp_path / "hung-once"
    hang_first_time = f"import pathlib\nif not pathlib.Path({str(marker)!r}).exists():\n" + "".join(
        "    " + line + "\n"
        for line in [f"pathlib.Path({str(marker)!r}).touch()", *DROP_REPLIES.splitlines()]
    )
    _chapter(tmp_path, "01_flaky", hang_first_time, "print('done')")
    _chapter(tmp_path, "02_stuck", DROP_REPLIES, "print('never answered')")
    flaky, stuck = sorted(course.build(tmp_path / "notebooks"), key=lambda run: run.name)
    assert flaky.error is None and len(flaky.retries) == 1 and "cell 0" in flaky.retries[0]
    assert stuck.error.startswith("cell 0: KernelNotAnswering") and len(stuck.retries) == 1
    results = json.loads((build / "results.json").read_text())
    assert results["notebooks"]["01_flaky"]["retries"] == list(flaky.retries)
    assert "executed again after" in (build / "index.html").read_text()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--only", "7"], "chapter numbers such as 01"),
        (["--only", "42"], "no chapter 42"),
        (["--notebooks", "/no/such/dir"], "no such directory"),
        (["--bogus"], "unrecognized arguments"),
    ],
)
def test_the_command_refuses_bad_arguments_in_one_line(tmp_path: Path, build, capsys, argv, message):
    _chapter(tmp_path, "01_ok", "1")
    with pytest.raises(SystemExit) as exit_info:
        course.main(["--notebooks", str(tmp_path / "notebooks"), *argv])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_the_command_refuses_an_unknown_profile(tmp_path: Path, build, capsys, monkeypatch):
    _chapter(tmp_path, "01_ok", "1")
    monkeypatch.setenv("MOTIONLAB_PROFILE", "fast")
    with pytest.raises(SystemExit):
        course.main(["--notebooks", str(tmp_path / "notebooks")])
    assert "MOTIONLAB_PROFILE" in capsys.readouterr().err


def _kernel_that_dies(tmp_path: Path, monkeypatch, times: int) -> None:
    """Make the ``python3`` kernel die at start-up (as one that cannot bind its ports would) the first
    ``times`` times it is started, then start as usual."""
    count = tmp_path / "deaths"
    start = (
        f"import pathlib, sys\ncount = pathlib.Path({str(count)!r})\n"
        "deaths = len(count.read_text()) if count.exists() else 0\n"
        f"if deaths < {times}:\n    count.write_text('x' * (deaths + 1))\n    sys.exit('died at start-up')\n"
        "from ipykernel import kernelapp\nkernelapp.launch_new_instance()\n"
    )
    spec = tmp_path / "jupyter" / "kernels" / "python3"
    spec.mkdir(parents=True)
    (spec / "kernel.json").write_text(
        json.dumps(
            {"argv": [sys.executable, "-c", start, "-f", "{connection_file}"], "display_name": "Python 3"}
        )
    )
    monkeypatch.setenv("JUPYTER_PATH", str(tmp_path / "jupyter"))  # its "python3" before the installed one


def test_a_chapter_whose_kernel_dies_before_it_answers_is_started_again(tmp_path: Path, build, monkeypatch):
    """The chapter runs in a second kernel, and the report names the first attempt."""
    _kernel_that_dies(tmp_path, monkeypatch, times=1)
    _chapter(tmp_path, "01_late", "print('done')")
    (late,) = course.build(tmp_path / "notebooks")
    assert late.error is None
    assert len(late.retries) == 1 and "Kernel died before replying" in late.retries[0], late.retries
    assert "done" in (build / "01_late.html").read_text()


@pytest.mark.parametrize("times", [1, 2])
def test_nbvals_kernel_that_dies_before_it_answers_is_started_again_once(tmp_path: Path, monkeypatch, times):
    """The notebooks' kernel under nbval (the root ``conftest.py``): a second start after a death, with the
    first kernel's stderr in the warning; two deaths are an error that shows both."""
    spec = importlib.util.spec_from_file_location("root_conftest", Path(__file__).parents[1] / "conftest.py")
    root_conftest = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(root_conftest)
    _kernel_that_dies(tmp_path, monkeypatch, times)
    kernel_class = root_conftest.retried_kernel_class()
    if times == 2:
        with pytest.raises(
            RuntimeError, match="died twice before it answered.*died at start-up.*died at start-up"
        ):
            kernel_class("python3", cwd=str(tmp_path))
        return
    with pytest.warns(UserWarning, match="died before it answered and was started again.*died at start-up"):
        kernel = kernel_class("python3", cwd=str(tmp_path))
    try:
        assert kernel.is_alive()
    finally:
        kernel.stop()
