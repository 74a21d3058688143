"""Stress harness: execute notebooks many times in a row and count the kernels that stop answering.

A hang that strikes one cell in a few hundred is invisible in one build and costs a whole build when it
strikes. This harness makes it measurable::

    python -m motionlab.course.stress --runs 30              # every chapter and appendix, 30 times
    python -m motionlab.course.stress --runs 200 --patterns  # a notebook of the chapters' cell patterns

Every execution goes through :func:`motionlab.course.kernel.execute_notebook` with the limits the course build
uses, so a kernel that stops answering is detected within
:attr:`~motionlab.course.kernel.CellLimits.answer_seconds` and counted, with its diagnosis. One line per
execution goes to the terminal; a JSON summary (versions of the kernel stack, executions, hangs, other
failures, each hang's cell and diagnosis) goes to ``build/stress/<time>.json``. The exit code is 1 when any
execution hung or failed.

The pattern notebook (:func:`pattern_notebook`) holds what the chapters do between their computations, many
times over: short cells with text output, ipywidgets with their comm traffic (sliders moved from the kernel,
``interactive_output``), tqdm progress bars, matplotlib figures, stick-figure animations (outputs of several
hundred kB), and calls into the shared worker pool, some of which write progress bars to the kernel's
standard error while the cell waits for them (as training runs in workers do in the full profile).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import os
import platform
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import nbformat
from nbclient.exceptions import CellTimeoutError
from nbformat import NotebookNode

from motionlab import config
from motionlab.arguments import positive_int
from motionlab.course.kernel import CellLimits, execute_notebook, read_notebook
from motionlab.course.run import cell_limits, notebook_number, select_chapters

#: Packages whose versions decide how a kernel talks to its client (recorded in every summary).
KERNEL_STACK = ("ipykernel", "jupyter_client", "pyzmq", "tornado", "nbclient", "ipywidgets", "comm")

_SETUP = """\
import math
import matplotlib.pyplot as plt
import numpy as np
import ipywidgets as widgets
from IPython.display import display
from tqdm.auto import tqdm
from motionlab import config
from motionlab.skeleton import average_skeleton
from motionlab.course.stress import noisy_work
from motionlab.train.parallel import run_in_workers
from motionlab.viz.animation import animate
config.setup(0)
skeleton = average_skeleton()
rng = np.random.default_rng(0)"""

#: One block of the pattern notebook: each string is one cell; ``{i}`` is the block's number.
_BLOCK = (
    "print('block {i}', math.factorial({i} % 20))",
    "slider = widgets.IntSlider(value={i}, min=0, max=1000)\n"
    "out = widgets.interactive_output(lambda v: print('value', v), {{'v': slider}})\n"
    "display(widgets.VBox([slider, out]))\n"
    "for v in range(5):\n    slider.value = {i} + v",
    "total = 0\nfor k in tqdm(range(200), desc='block {i}'):\n    total += k\ntotal",
    "fig, ax = plt.subplots(figsize=(3, 2))\nax.plot(np.cumsum(rng.normal(size=200)))\nplt.show()",
    "positions = np.cumsum(rng.normal(scale=0.01, size=(20, len(skeleton.parents), 3)), axis=0)\n"
    "animate(positions, skeleton.parents, fps=10, dpi=30, panel_size=2.0)",
    "run_in_workers(math.factorial, [({i} % 30,), ({i} % 30 + 1,)])[0] > 0",
    "run_in_workers(noisy_work, [(1.5,), (1.5,)])",
    "{i} * 2",
)


def noisy_work(seconds: float) -> int:
    """Worker side of a pattern cell: a plain-text tqdm bar on standard error, updated every 20 ms for
    ``seconds``, and a line on standard output; returns the number of updates."""
    from tqdm import tqdm

    steps = max(1, int(seconds / 0.02))
    with tqdm(total=steps, mininterval=0.05, file=sys.stderr) as bar:
        for _ in range(steps):
            time.sleep(0.02)
            bar.update()
    print(f"worker {os.getpid()}: {steps} updates", flush=True)
    return steps


def pattern_notebook(blocks: int) -> NotebookNode:
    """A notebook of a set-up cell and ``blocks`` repetitions of the chapters' cell patterns (``_BLOCK``)."""
    if isinstance(blocks, bool) or not isinstance(blocks, int) or blocks < 1:
        raise ValueError(f"blocks must be a positive integer, got {blocks!r}")
    notebook = nbformat.v4.new_notebook()
    cells = [_SETUP] + [cell.format(i=i) for i in range(blocks) for cell in _BLOCK]
    notebook.cells = [nbformat.v4.new_code_cell(source) for source in cells]
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    return notebook


@dataclass
class StressSummary:
    """Counts and details of one stress session (written as JSON)."""

    what: str
    profile: str
    versions: dict[str, str]
    client: str
    executions: int = 0
    cells: int = 0
    #: Cells whose reply came long after the kernel said idle (:class:`~motionlab.course.kernel.TimedClient`).
    stalls: list[dict[str, Any]] = field(default_factory=list)
    hangs: list[dict[str, Any]] = field(default_factory=list)
    failures: list[dict[str, Any]] = field(default_factory=list)
    seconds: float = 0.0


def kernel_stack_versions() -> dict[str, str]:
    """Python and the versions of :data:`KERNEL_STACK` installed here."""
    versions = {"python": platform.python_version()}
    for name in KERNEL_STACK:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


def run_stress(
    targets: Sequence[tuple[str, NotebookNode, Path, CellLimits]],
    runs: int,
    what: str,
    out: Path,
    stock: bool = False,
) -> StressSummary:
    """Execute every target (name, notebook, working directory, limits) ``runs`` times, in order, and
    write the summary to ``out`` after every execution (so a stopped session keeps its counts).

    With ``stock``, nbclient's own client executes (``execute_notebook(..., stock=True)``) and a cell past its
    limit counts as a hang: no cell of the quick profile or of the pattern notebook comes near its limit when
    it runs.
    """
    summary = StressSummary(
        what=what,
        profile=config.profile(),
        versions=kernel_stack_versions(),
        client="nbclient (stock)" if stock else "WatchedClient",
    )
    start = time.perf_counter()
    out.parent.mkdir(parents=True, exist_ok=True)
    for run in range(1, runs + 1):
        for name, notebook, cwd, limits in targets:
            execution = execute_notebook(nbformat.from_dict(notebook), cwd, limits, stock=stock)
            summary.executions += 1
            summary.cells += sum(1 for cell in execution.notebook.cells if cell.cell_type == "code")
            record = {
                "run": run,
                "notebook": name,
                "cell": execution.failed_cell,
                "seconds": round(execution.seconds, 1),
                "error": str(execution.error)[:2000],
            }
            if execution.hung or (stock and isinstance(execution.error, CellTimeoutError)):
                summary.hangs.append(record)
                verdict = f"HANG at cell {execution.failed_cell}: {execution.error}"
            elif execution.error is not None:
                summary.failures.append(record)
                verdict = (
                    f"FAILED at cell {execution.failed_cell}: {type(execution.error).__name__}: "
                    + str(execution.error).splitlines()[0][:300]
                )
            else:
                verdict = "ok"
            if execution.notes:
                summary.stalls.extend(
                    {"run": run, "notebook": name, "note": note} for note in execution.notes
                )
                verdict += "; stalls: " + "; ".join(execution.notes)
            summary.seconds = round(time.perf_counter() - start, 1)
            print(f"[stress] run {run}/{runs} {name}: {execution.seconds:.1f} s {verdict}", flush=True)
            out.write_text(json.dumps(asdict(summary), indent=1), encoding="utf-8")
    return summary


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m motionlab.course.stress",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--runs", type=positive_int, default=30, help="how many times to execute each notebook"
    )
    parser.add_argument(
        "--patterns",
        type=positive_int,
        metavar="BLOCKS",
        default=None,
        help="execute a generated notebook of BLOCKS repetitions of the chapters' cell patterns "
        "instead of the chapters",
    )
    parser.add_argument(
        "--only",
        nargs="+",
        metavar="NN",
        help="chapter numbers to execute (each with its appendix), e.g. 02 07",
    )
    parser.add_argument("--notebooks", type=Path, default=config.REPO_ROOT / "notebooks")
    parser.add_argument(
        "--stock-client",
        action="store_true",
        help="execute with nbclient's own client instead of the course's WatchedClient",
    )
    args = parser.parse_args(argv)
    os.environ.setdefault("MOTIONLAB_PROFILE", "quick")

    stamp = time.strftime("%Y%m%d-%H%M%S")
    out = config.build_dir() / "stress" / f"{stamp}.json"
    if args.patterns is not None:
        notebook = pattern_notebook(args.patterns)
        targets = [("patterns", notebook, config.REPO_ROOT, CellLimits(cell_seconds=60.0))]
        what = f"pattern notebook, {args.patterns} blocks ({len(notebook.cells)} cells)"
    else:
        try:
            paths = select_chapters(args.notebooks, args.only)
        except (OSError, ValueError) as exc:
            parser.error(str(exc))
        targets = [(p.stem, read_notebook(p), p.parent, cell_limits(p.stem)) for p in paths]
        what = f"course chapters {', '.join(notebook_number(p.stem) for p in paths)}"
    client = "nbclient's own client" if args.stock_client else "WatchedClient"
    print(
        f"[stress] {what}, {args.runs} runs, profile {config.profile()}, {client}; summary: {out}", flush=True
    )
    summary = run_stress(targets, args.runs, what, out, stock=args.stock_client)
    print(
        f"[stress] {summary.executions} executions ({summary.cells} cells) in {summary.seconds / 60:.1f} "
        "min: "
        f"{len(summary.hangs)} hangs, {len(summary.stalls)} stalls, {len(summary.failures)} other failures; "
        f"versions {summary.versions}"
    )
    return 1 if summary.hangs or summary.failures else 0


if __name__ == "__main__":
    sys.exit(main())
