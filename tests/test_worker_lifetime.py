"""No worker process outlives the process that started it: after a chapter, after its kernel is killed."""

from __future__ import annotations

import json
import time
from pathlib import Path

import nbformat

from motionlab.course.kernel import CellLimits, execute_notebook

#: Starts the shared pool's workers and prints their pids and that of multiprocessing's resource tracker.
_START_WORKERS = """\
import json, multiprocessing.resource_tracker as tracker, os
from motionlab.train.parallel import run_in_workers, shared_pool
run_in_workers(os.getpid, [(), (), (), ()])
pids = sorted(shared_pool(2)._processes)
print(json.dumps({"workers": pids, "tracker": tracker._resource_tracker._pid, "me": os.getpid()}), flush=True)
"""


#: Seconds the workers may take to end: half a second here; the limit leaves room for a busy machine, and a
#: passing run does not wait for it.
ENDED_SECONDS = 60.0


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"  # a zombie has ended; only its entry waits for its parent


def _gone_within(pids: list[int], seconds: float) -> list[int]:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline and any(_alive(pid) for pid in pids):
        time.sleep(0.1)
    return [pid for pid in pids if _alive(pid)]


def _children(report: dict) -> list[int]:
    return report["workers"] + ([report["tracker"]] if report["tracker"] else [])


def _notebook(*sources: str) -> nbformat.NotebookNode:
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell(source) for source in sources]
    return notebook


def _report(execution) -> dict:
    text = "".join(out.get("text", "") for out in execution.notebook.cells[0].outputs)
    return json.loads(text.splitlines()[0])


def test_no_worker_outlives_its_chapter(tmp_path: Path) -> None:
    execution = execute_notebook(_notebook(_START_WORKERS), tmp_path, CellLimits(cell_seconds=120))
    assert execution.error is None
    report = _report(execution)
    assert not _alive(report["me"])
    assert _gone_within(_children(report), ENDED_SECONDS) == []


def test_an_interrupt_leaves_the_workers_and_a_killed_kernel_takes_them_along(tmp_path: Path) -> None:
    """Ctrl-C in the notebook (SIGINT to the kernel's process group) stops the cell, not the idle workers: the
    next cell finds the same two. A kernel that is killed runs no clean-up, and its workers still end."""
    interrupt = (
        "import os, signal, time\ntry:\n    os.killpg(os.getpgid(0), signal.SIGINT)\n    time.sleep(60)\n"
        "except KeyboardInterrupt:\n    print('interrupted')"
    )
    again = "run_in_workers(os.getpid, [(), ()])\nprint(sorted(shared_pool(2)._processes))"
    kill = "os.kill(os.getpid(), signal.SIGKILL)"
    execution = execute_notebook(
        _notebook(_START_WORKERS, interrupt, again, kill), tmp_path, CellLimits(cell_seconds=120)
    )
    assert execution.failed_cell == 3 and "died" in str(execution.error).lower()
    report = _report(execution)
    assert "interrupted" in execution.notebook.cells[1].outputs[0]["text"]
    assert execution.notebook.cells[2].outputs[0]["text"].strip() == str(report["workers"])
    assert _gone_within([report["me"], *_children(report)], ENDED_SECONDS) == []
