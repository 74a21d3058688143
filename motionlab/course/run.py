"""``make course``: execute every chapter and build the report in ``build/course/``.

For each ``notebooks/NN_name.ipynb``, and its appendix ``NNa_name.ipynb`` if it has one (the chapter's audits,
ablations, extra measurements and primers; built exactly like a chapter, with its own budget, page, results
and card), two at a time (:data:`PARALLEL`, the longest first): execute it headless in a fresh kernel (cwd
``notebooks/``, widget state stored in the notebook), record its wall time in ``results.json``, and write the
executed notebook and an HTML rendering. Then write the front page ``index.html``
(:mod:`motionlab.course.report`): what the course is, the claims at a glance, chapter 09's comparison of the
five generators, one card per chapter (summary, key figure, time against budget, claims) and every metric.

A chapter that fails (an error, or a claim that stopped holding in the full profile) does not stop the
build: the remaining chapters still run so the report shows everything, and the command exits non-zero.

Each cell may run at most :data:`CELL_BUDGET_FACTOR` times its chapter's whole budget
(:func:`cell_limits`); a cell past that fails its chapter. A kernel that stops answering (alive and idle,
but a request never started or a finished cell's reply never came; see :mod:`motionlab.course.kernel`) is
killed within half a minute and the chapter is executed once more in a fresh kernel: trained models are
cached, so a second execution costs little. The retry is recorded in ``results.json`` (the chapter's
``"retries"``) and shown in the report; a second hang fails the chapter with the cell and the diagnosis.

Usage: ``python -m motionlab.course [--only 01 03] [--notebooks DIR]``; ``--only 04`` runs chapter 04 and its
appendix, ``--only 04a`` the appendix alone.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path

import nbformat
from nbconvert import HTMLExporter

from motionlab import config
from motionlab.course.assets import install_assets, localize_page
from motionlab.course.chapters import NUMBER, is_appendix, notebook_number, numbered_notebooks
from motionlab.course.kernel import CellLimits, execute_notebook, read_notebook
from motionlab.course.report import ChapterStatus, write_front_page
from motionlab.course.results import (
    failing_claims,
    fcntl,
    load_results,
    record_wall_time,
    results_path,
    update_notebook,
)
from motionlab.train import reference

#: Wall-clock budgets per notebook in seconds (design notes), as (full, quick), keyed by the notebook's number
#: (:func:`notebook_number`: ``"04"`` for a chapter, ``"04a"`` for its appendix).
BUDGETS: dict[str, tuple[float, float]] = {
    "01": (30, 20),
    "02": (60, 30),
    "03": (120, 40),
    "04": (240, 40),
    "05": (120, 40),
    "06": (180, 40),
    "07": (180, 40),
    "08": (180, 40),
    "09": (180, 40),
    "10": (240, 40),
    "11": (180, 40),
    "04a": (240, 60),
    "06a": (180, 40),
    "07a": (180, 40),
    "08a": (240, 60),
}

#: Budget of an appendix not listed in :data:`BUDGETS`, as (full, quick).
APPENDIX_BUDGET: tuple[float, float] = (120, 40)

#: Seconds each notebook took in a clean full-profile build on the course machine (reference models, two
#: notebooks at a time): how a build that has no ``results.json`` yet orders its notebooks
#: (:func:`longest_first`). Budgets are ceilings, not estimates: ordered by them, chapter 11 and its
#: appendix would start last and finish alone.
TYPICAL_SECONDS: dict[str, float] = {
    "01": 7, "01a": 4, "02": 11, "02a": 7, "03": 28, "03a": 11, "04": 54, "04a": 31, "05": 42, "05a": 5,
    "06": 32, "06a": 23, "07": 45, "07a": 17, "08": 47, "08a": 54, "09": 60, "10": 80, "11": 85, "11a": 41,
}  # fmt: skip

#: A cell may take at most this many times its chapter's budget. Some chapters spend most of their time in
#: one training cell (chapter 07: 232 of 262 s on a machine twice as slow as the reference one), so the limit
#: leaves room for a slow machine; a kernel that stops answering is caught much sooner, by
#: :data:`ANSWER_SECONDS`, whatever the limit.
CELL_BUDGET_FACTOR = 3.0

#: Cell limit of a chapter without a budget (e.g. a notebook a user adds), in seconds.
DEFAULT_CELL_SECONDS = 600.0

#: Cell limit of a full-profile build that trains its models (``RETRAIN``, another base seed), in seconds: the
#: chapters' budgets are for loading the reference models, and one cell may train a whole family (chapter 06's
#: four MoGlows of 20,000 steps, two at a time, take about half an hour on two cores).
TRAINING_CELL_SECONDS = 4 * 3600.0

#: How long a kernel may take to start a request or to send a finished cell's reply (seconds); see
#: :class:`~motionlab.course.kernel.CellLimits`.
ANSWER_SECONDS = 30.0

#: How many times a chapter whose kernel stopped answering, or died before it answered, is executed again in a
#: fresh kernel.
KERNEL_RETRIES = 1

#: Notebooks executed at once when the reference models are loaded (:func:`parallel`), each in its own kernel
#: on one torch thread: on the course's 2-core machine two side by side take about half the time of one after
#: the other (the chapters are independent: every model they share comes from the reference models).
PARALLEL = 2

_ANSI_CODES = re.compile(r"\x1b\[[0-9;]*m")


@dataclass(frozen=True)
class ChapterRun:
    """The outcome of executing one chapter."""

    name: str
    seconds: float
    error: str | None
    #: One line per execution that was abandoned because the kernel stopped answering.
    retries: tuple[str, ...] = ()


def chapter_notebooks(directory: Path) -> list[Path]:
    """:func:`numbered_notebooks` of ``directory``; ``FileNotFoundError`` when it holds no chapter."""
    found = numbered_notebooks(directory)
    if all(is_appendix(p.stem) for p in found):
        raise FileNotFoundError(f"no chapters (NN_name.ipynb) found in {directory}")
    return found


def budget_seconds(name: str) -> float | None:
    """The active profile's budget for notebook ``name``: its entry in :data:`BUDGETS`, else
    :data:`APPENDIX_BUDGET` for an appendix, else None (a chapter without a budget)."""
    pair = BUDGETS.get(notebook_number(name), APPENDIX_BUDGET if is_appendix(name) else None)
    if pair is None:
        return None
    return pair[1] if config.is_quick() else pair[0]


#: Set to 1 by ``make reference``: the build makes reference models, so it may train any of them (with
#: ``ALL=0`` those whose configuration changed), which :func:`loads_references` must not count on.
REFERENCE_BUILD_VARIABLE = "MOTIONLAB_REFERENCE_BUILD"


def loads_references() -> bool:
    """Whether the build loads the shipped reference models rather than training: the full profile with base
    seed 0, no ``RETRAIN``, and not a build of the reference models (:data:`REFERENCE_BUILD_VARIABLE`)."""
    text = os.environ.get(REFERENCE_BUILD_VARIABLE, "0").strip() or "0"
    if text not in ("0", "1"):
        raise ValueError(f"{REFERENCE_BUILD_VARIABLE} must be 1 or 0, got {text!r}")
    return reference.in_use() and config.base_seed() == 0 and text == "0"


def cell_limits(name: str) -> CellLimits:
    """The time limits for the cells of chapter ``name`` in the active profile (:data:`CELL_BUDGET_FACTOR`
    times its budget), or :data:`TRAINING_CELL_SECONDS` in a full-profile build that trains its models."""
    budget = budget_seconds(name)
    if not config.is_quick() and not loads_references():
        cell_seconds = TRAINING_CELL_SECONDS
    else:
        cell_seconds = DEFAULT_CELL_SECONDS if budget is None else CELL_BUDGET_FACTOR * budget
    return CellLimits(cell_seconds=cell_seconds, answer_seconds=ANSWER_SECONDS)


def _describe(error: BaseException, cell: int | None) -> str:
    """One line for the report: the cell, the error's type and the last line of its message (the executed
    chapter keeps the whole traceback), without terminal colour codes."""
    where = "" if cell is None else f"cell {cell}: "
    text = _ANSI_CODES.sub("", str(error)).strip()
    return where + f"{type(error).__name__}: {text.splitlines()[-1] if text else ''}"[:2000]


def export_html(notebook: nbformat.NotebookNode, assets: dict[str, str] | None = None) -> str:
    """The HTML page of an executed notebook (nbconvert's JupyterLab template), pointing at the local
    ``assets`` of :func:`~motionlab.course.assets.install_assets` (MathJax, require.js, the widget manager,
    Font Awesome) instead of their web addresses."""
    assets = assets or {}
    settings = {key: value for key, value in assets.items() if key.endswith("_url")}
    body, _ = HTMLExporter(template_name="lab", **settings).from_notebook_node(notebook)
    return localize_page(body, assets)


def execute_chapter(path: Path, out_dir: Path, assets: dict[str, str] | None = None) -> ChapterRun:
    """Execute one notebook; write ``<name>.ipynb`` and ``<name>.html`` to ``out_dir`` (even on failure).

    A kernel that stops answering is killed and the chapter executed again (:data:`KERNEL_RETRIES` times), as
    is one that died before it answered; the seconds reported are those of the last execution, the abandoned
    ones are listed in ``retries``.
    """
    name = path.stem
    retries: list[str] = []
    while True:
        execution = execute_notebook(read_notebook(path), path.parent, cell_limits(name))
        if not (execution.hung or execution.never_started) or len(retries) >= KERNEL_RETRIES:
            break
        retries.append(
            f"{_describe(execution.error, execution.failed_cell)} (after {execution.seconds:.0f} s)"
        )
        what = "did not start" if execution.never_started else "stopped answering"
        print(
            f"[course] {name}: the kernel {what}; executing the chapter again in a fresh kernel "
            f"({retries[-1]})",
            flush=True,
        )
    error = None if execution.error is None else _describe(execution.error, execution.failed_cell)
    unheld = [] if config.is_quick() else failing_claims(name)
    if error is None and unheld:  # recorded, not raised (MOTIONLAB_CLAIMS=record)
        error = f"claims that do not hold: {', '.join(unheld)}"
    seconds = execution.seconds
    update_notebook(name, lambda entry: entry.update(seconds=round(seconds, 2), retries=retries))
    nbformat.write(execution.notebook, out_dir / f"{name}.ipynb")
    (out_dir / f"{name}.html").write_text(export_html(execution.notebook, assets), encoding="utf-8")
    return ChapterRun(name, seconds, error, tuple(retries))


def write_index(out_dir: Path, runs: list[ChapterRun]) -> Path:
    """Write the report's front page ``index.html`` (:mod:`motionlab.course.report`) from ``results.json``.

    It shows the chapters and appendices that ran now (``runs``) and, from earlier builds of the same
    profile, every other one whose executed notebook is in ``out_dir`` (its time from ``results.json``).
    """
    results = load_results()
    ran = {run.name: run for run in runs}
    earlier = {path.stem for path in numbered_notebooks(out_dir)} - set(ran)
    chapters = [
        ChapterStatus(run.name, run.seconds, run.error, run.retries)
        if (run := ran.get(name)) is not None
        else ChapterStatus(name, results.get("notebooks", {}).get(name, {}).get("seconds"), current=False)
        for name in sorted(set(ran) | earlier, key=notebook_number)
    ]
    budgets = {chapter.name: budget_seconds(chapter.name) for chapter in chapters}
    return write_front_page(out_dir, results, chapters, budgets)


def select_chapters(notebook_dir: Path, only: list[str] | None = None) -> list[Path]:
    """The chapters and appendices of ``notebook_dir`` in course order: all, or those ``only`` names. A
    chapter's number (``04``) selects the chapter and its appendices, an appendix's (``04a``) that appendix.

    Raises ``ValueError`` for a number that is not ``NN`` or ``NNa`` or matches no notebook,
    ``FileNotFoundError`` when the directory holds no chapter."""
    if not notebook_dir.is_dir():
        raise FileNotFoundError(f"--notebooks {notebook_dir}: no such directory")
    chapters = chapter_notebooks(notebook_dir)
    if not only:
        return chapters
    numbers = [notebook_number(path.stem) for path in chapters]
    for number in only:
        if not NUMBER.fullmatch(number):
            raise ValueError(
                "--only takes chapter numbers such as 01 or 07, or appendix numbers such as 04a, "
                f"got {number!r}"
            )
        if number not in numbers:
            raise ValueError(
                f"--only {number}: no chapter {number} in {notebook_dir} (there are {', '.join(numbers)})"
            )
    return [path for path, number in zip(chapters, numbers, strict=True) if {number, number[:2]} & set(only)]


def parallel() -> int:
    """How many notebooks run at once: ``MOTIONLAB_PARALLEL`` if set, else :data:`PARALLEL` when the full
    profile loads the reference models (base seed 0, no ``RETRAIN``), else one: a build that trains would
    run two notebooks' trainings, each on both cores, side by side (and train a model two chapters share
    twice). One, too, where ``results.json`` cannot be locked (no POSIX file locks)."""
    if fcntl is None:
        return 1
    text = os.environ.get("MOTIONLAB_PARALLEL", "").strip()
    if not text:
        return PARALLEL if loads_references() else 1
    if not text.isdigit() or int(text) < 1:
        raise ValueError(f"MOTIONLAB_PARALLEL must be an integer >= 1, got {text!r}")
    return int(text)


def longest_first(chapters: list[Path]) -> list[Path]:
    """The notebooks in the order they start, the longest chain first: a chapter with the seconds it and
    its appendices take one after the other (an appendix waits for its chapter, see :func:`execute_all`),
    an appendix with its own. Seconds are the last build's in ``results.json``, else
    :data:`TYPICAL_SECONDS` (the full profile's, a fair guide to the quick profile's order too), else the
    budget. So the chapter that ends the longest chain starts first, its appendix as soon as it is done, and
    the last notebook to finish is a short one."""
    seconds = load_results().get("notebooks", {})

    def expected(path: Path) -> float:
        last = seconds.get(path.stem, {}).get("seconds")
        if last is not None:
            return float(last)
        typical = TYPICAL_SECONDS.get(notebook_number(path.stem))
        return float(typical if typical is not None else budget_seconds(path.stem) or 0.0)

    def chain(path: Path) -> float:
        if is_appendix(path.stem):
            return expected(path)
        number = notebook_number(path.stem)
        return sum(expected(other) for other in chapters if notebook_number(other.stem)[:2] == number)

    return sorted(chapters, key=lambda path: -chain(path))


def execute_all(
    chapters: list[Path], execute: Callable[[Path], ChapterRun], workers: int
) -> dict[str, ChapterRun]:
    """Run ``execute`` on every notebook, ``workers`` at a time, in :func:`longest_first` order; an appendix
    starts only once its chapter (when it is among ``chapters``) has finished: it loads what the chapter
    trained. Returns ``{name: run}``."""
    stems = {notebook_number(path.stem): path.stem for path in chapters}
    waiting, done, running = longest_first(chapters), {}, {}

    def is_ready(path: Path) -> bool:  # a chapter, or an appendix whose chapter is done or not run
        chapter = stems.get(notebook_number(path.stem)[:2]) if is_appendix(path.stem) else None
        return chapter is None or chapter in done

    with ThreadPoolExecutor(max_workers=workers) as pool:
        while waiting or running:
            ready = [path for path in waiting if is_ready(path)]
            while ready and len(running) < workers:
                path = ready.pop(0)
                waiting.remove(path)
                running[pool.submit(execute, path)] = path
            finished, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in finished:
                run = future.result()
                done[run.name] = run
                del running[future]
    return done


def build(notebook_dir: Path, only: list[str] | None = None) -> list[ChapterRun]:
    """Execute the chapters (all, or those whose number is in ``only``) and write the report."""
    chapters = select_chapters(notebook_dir, only)
    out_dir = config.course_dir()
    out_dir.mkdir(parents=True, exist_ok=True)
    config.set_threads()
    assets = install_assets(out_dir)

    def execute(path: Path) -> ChapterRun:
        print(f"[course] {path.stem} ...", flush=True)
        run = execute_chapter(path, out_dir, assets)
        budget = budget_seconds(run.name)
        note = f" (budget {budget:.0f} s)" if budget else ""
        print(
            f"[course] {run.name}: {run.seconds:.1f} s{note}"
            + (f" FAILED: {run.error}" if run.error else ""),
            flush=True,
        )
        return run

    reference.trained_log().unlink(missing_ok=True)
    started = time.perf_counter()
    done = execute_all(chapters, execute, parallel())
    runs = [done[path.stem] for path in chapters]
    trained = reference.trained_here()
    record_wall_time(time.perf_counter() - started, len(runs), trained)
    index = write_index(out_dir, runs)
    if trained:
        print(f"[course] trained here, no reference model of their configuration: {', '.join(trained)}")
    print(f"[course] report: {index}\n[course] results: {results_path()}")
    return runs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m motionlab.course",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--notebooks",
        type=Path,
        default=config.REPO_ROOT / "notebooks",
        help="directory of the chapters NN_name.ipynb and appendices NNa_name.ipynb (default: the course's)",
    )
    parser.add_argument(
        "--only",
        nargs="+",
        metavar="NN",
        help="chapter numbers to run, e.g. 01 03 (each with its appendix), or appendix numbers, e.g. 04a",
    )
    args = parser.parse_args(argv)
    try:
        config.profile()
        select_chapters(args.notebooks, args.only)
    except (OSError, ValueError) as exc:  # a bad argument or setting: one line, no traceback
        parser.error(str(exc))
    runs = build(args.notebooks, args.only)
    failed = [run.name for run in runs if run.error]
    if failed:
        print(f"[course] failed chapters: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0
