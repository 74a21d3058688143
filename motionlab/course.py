"""``make course``: execute every chapter and build the report in ``build/course/``.

For each ``notebooks/NN_name.ipynb`` in order: execute it headless in a fresh kernel (cwd ``notebooks/``,
widget state stored in the notebook), record its wall time in ``results.json``, and write the executed
notebook and an HTML rendering. Then write ``index.html``: a link to every chapter, its time against its
budget, and the metrics and claims tables of ``results.json``.

A chapter that fails (an error, or a claim that stopped holding in the full profile) does not stop the
build: the remaining chapters still run so the report shows everything, and the command exits non-zero.

Each cell may run at most :data:`CELL_BUDGET_FACTOR` times its chapter's whole budget
(:func:`cell_limits`); a cell past that fails its chapter. A kernel that stops answering (alive and idle,
but a request never started or a finished cell's reply never came; see :mod:`motionlab.execution`) is
killed within half a minute and the chapter is executed once more in a fresh kernel: trained models are
cached, so a second execution costs little. The retry is recorded in ``results.json`` (the chapter's
``"retries"``) and shown in the report; a second hang fails the chapter with the cell and the diagnosis.

Usage: ``python -m motionlab.course [--only 01 03] [--notebooks DIR]``.
"""

from __future__ import annotations

import argparse
import html
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import nbformat
from nbconvert import HTMLExporter

from motionlab import config
from motionlab.execution import CellLimits, execute_notebook, read_notebook
from motionlab.report_assets import install_assets, localize_page
from motionlab.results import load_results, results_path, update_notebook

#: Wall-clock budgets per chapter in seconds (design notes), as (full, quick).
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
}

#: A cell may take at most this many times its chapter's budget. Some chapters spend most of their time in
#: one training cell (chapter 07: 232 of 262 s on a machine twice as slow as the reference one), so the limit
#: leaves room for a slow machine; a kernel that stops answering is caught much sooner, by
#: :data:`ANSWER_SECONDS`, whatever the limit.
CELL_BUDGET_FACTOR = 3.0

#: Cell limit of a chapter without a budget (e.g. a notebook a user adds), in seconds.
DEFAULT_CELL_SECONDS = 600.0

#: How long a kernel may take to start a request or to send a finished cell's reply (seconds); see
#: :class:`~motionlab.execution.CellLimits`.
ANSWER_SECONDS = 30.0

#: How many times a chapter whose kernel stopped answering is executed again in a fresh kernel.
HANG_RETRIES = 1

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
    """The numbered chapters ``NN_*.ipynb`` in ``directory``, in course order."""
    found = sorted(p for p in directory.glob("[0-9][0-9]_*.ipynb") if p.is_file())
    if not found:
        raise FileNotFoundError(f"no chapters (NN_name.ipynb) found in {directory}")
    return found


def budget_seconds(name: str) -> float | None:
    """The active profile's budget for chapter ``name`` (None for a chapter without one)."""
    pair = BUDGETS.get(name[:2])
    if pair is None:
        return None
    return pair[1] if config.is_quick() else pair[0]


def cell_limits(name: str) -> CellLimits:
    """The time limits for the cells of chapter ``name`` in the active profile (:data:`CELL_BUDGET_FACTOR`
    times its budget)."""
    budget = budget_seconds(name)
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
    ``assets`` of :func:`~motionlab.report_assets.install_assets` (MathJax, require.js, the widget manager,
    Font Awesome) instead of their web addresses."""
    assets = assets or {}
    settings = {key: value for key, value in assets.items() if key.endswith("_url")}
    body, _ = HTMLExporter(template_name="lab", **settings).from_notebook_node(notebook)
    return localize_page(body, assets)


def execute_chapter(path: Path, out_dir: Path, assets: dict[str, str] | None = None) -> ChapterRun:
    """Execute one notebook; write ``<name>.ipynb`` and ``<name>.html`` to ``out_dir`` (even on failure).

    A kernel that stops answering is killed and the chapter executed again (:data:`HANG_RETRIES` times);
    the seconds reported are those of the last execution, the abandoned ones are listed in ``retries``.
    """
    name = path.stem
    retries: list[str] = []
    while True:
        execution = execute_notebook(read_notebook(path), path.parent, cell_limits(name))
        if not execution.hung or len(retries) >= HANG_RETRIES:
            break
        retries.append(
            f"{_describe(execution.error, execution.failed_cell)} (after {execution.seconds:.0f} s)"
        )
        print(
            f"[course] {name}: the kernel stopped answering; executing the chapter again in a fresh kernel "
            f"({retries[-1]})",
            flush=True,
        )
    error = None if execution.error is None else _describe(execution.error, execution.failed_cell)
    seconds = execution.seconds
    update_notebook(name, lambda entry: entry.update(seconds=round(seconds, 2), retries=retries))
    nbformat.write(execution.notebook, out_dir / f"{name}.ipynb")
    (out_dir / f"{name}.html").write_text(export_html(execution.notebook, assets), encoding="utf-8")
    return ChapterRun(name, seconds, error, tuple(retries))


def _claim_rows(results: dict[str, Any]) -> str:
    rows = []
    for chapter, entry in sorted(results.get("notebooks", {}).items()):
        for claim_id, claim in sorted(entry.get("claims", {}).items()):
            if claim.get("holds"):
                verdict, css = "holds", "ok"
            elif not claim.get("expected", True):
                verdict, css = f"known gap: {claim.get('why', '')}", "gap"
            else:
                verdict, css = "FAILS", "bad"
            rows.append(
                f"<tr class='{css}'><td>{html.escape(chapter)}</td><td><code>{html.escape(claim_id)}"
                "</code></td>"
                f"<td>{html.escape(str(claim.get('text', '')))}</td>"
                f"<td>{claim.get('value', float('nan')):.4g}</td>"
                f"<td>{html.escape(str(claim.get('op', '')))} {claim.get('threshold', float('nan')):.4g}</td>"
                f"<td>{html.escape(verdict)}</td></tr>"
            )
    return "\n".join(rows)


def _metric_rows(results: dict[str, Any]) -> str:
    rows = []
    for chapter, entry in sorted(results.get("notebooks", {}).items()):
        metrics = entry.get("metrics", {})
        for key in sorted(k for k in metrics if not k.endswith(".ci95")):
            ci = metrics.get(f"{key}.ci95")
            shown = f"{metrics[key]:.4g}" + (f" ± {ci:.2g}" if ci is not None else "")
            rows.append(
                f"<tr><td>{html.escape(chapter)}</td><td><code>{html.escape(key)}</code></td><td>{shown}</td></tr>"
            )
    return "\n".join(rows)


def write_index(out_dir: Path, runs: list[ChapterRun]) -> Path:
    """Write ``index.html`` from the runs and ``results.json``."""
    results = load_results()
    chapter_rows = []
    for run in runs:
        budget = budget_seconds(run.name)
        over = budget is not None and run.seconds > budget
        status = "failed: " + html.escape(run.error) if run.error else ("over budget" if over else "ok")
        if run.retries:
            status += "".join(f"<br>executed again after: {html.escape(retry)}" for retry in run.retries)
        css = "bad" if run.error or over else "ok"
        chapter_rows.append(
            f"<tr class='{css}'><td><a href='{run.name}.html'>{html.escape(run.name)}</a></td>"
            f"<td>{run.seconds:.1f} s</td><td>{'' if budget is None else f'{budget:.0f} s'}</td>"
            f"<td>{status}</td></tr>"
        )
    total = sum(run.seconds for run in runs)
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>motionlab course report</title>
<style>
body {{ font-family: system-ui, sans-serif; max-width: 70em; margin: 2em auto; padding: 0 1em; }}
table {{ border-collapse: collapse; margin-bottom: 2em; }}
td, th {{ border: 1px solid #ccc; padding: 0.3em 0.6em; text-align: left; vertical-align: top; }}
tr.ok td:last-child {{ color: #176117; }} tr.bad td:last-child {{ color: #a11; font-weight: bold; }}
tr.gap td:last-child {{ color: #8a5a00; }}
</style></head><body>
<h1>motionlab: probabilistic human-motion synthesis</h1>
<p>Profile <b>{html.escape(results["profile"])}</b>, Python {html.escape(results["python"])},
torch {html.escape(results["torch"])}. Total chapter time {total / 60:.1f} min.
Raw numbers: <a href="results.json">results.json</a>.</p>
<h2>Chapters</h2>
<table><tr><th>chapter</th><th>time</th><th>budget</th><th>status</th></tr>
{"".join(chapter_rows)}
</table>
<h2>Claims</h2>
<p>Statements from the papers (and a few of ours) checked on our data. A known gap is a claim that
does not hold here after investigation; the chapter explains why.</p>
<table><tr><th>chapter</th><th>claim</th><th>statement</th><th>value</th><th>threshold</th><th>verdict</th></tr>
{_claim_rows(results)}
</table>
<h2>Metrics</h2>
<table><tr><th>chapter</th><th>metric</th><th>value (± 95% CI half-width)</th></tr>
{_metric_rows(results)}
</table>
</body></html>
"""
    index = out_dir / "index.html"
    index.write_text(page, encoding="utf-8")
    return index


def select_chapters(notebook_dir: Path, only: list[str] | None = None) -> list[Path]:
    """The chapters of ``notebook_dir`` in course order: all, or those whose two-digit number is in ``only``.

    Raises ``ValueError`` for a number that is not two digits or matches no chapter, ``FileNotFoundError``
    when the directory holds no chapter."""
    if not notebook_dir.is_dir():
        raise FileNotFoundError(f"--notebooks {notebook_dir}: no such directory")
    chapters = chapter_notebooks(notebook_dir)
    if not only:
        return chapters
    numbers = {path.stem[:2] for path in chapters}
    for number in only:
        if len(number) != 2 or not number.isdigit():
            raise ValueError(f"--only takes two-digit chapter numbers such as 01 or 07, got {number!r}")
        if number not in numbers:
            raise ValueError(
                f"--only {number}: no chapter {number} in {notebook_dir} (there are "
                f"{', '.join(sorted(numbers))})"
            )
    return [path for path in chapters if path.stem[:2] in only]


def build(notebook_dir: Path, only: list[str] | None = None) -> list[ChapterRun]:
    """Execute the chapters (all, or those whose number is in ``only``) and write the report."""
    chapters = select_chapters(notebook_dir, only)
    out_dir = config.course_dir()
    out_dir.mkdir(parents=True, exist_ok=True)
    config.set_threads()
    assets = install_assets(out_dir)
    runs = []
    for path in chapters:
        print(f"[course] {path.stem} ...", flush=True)
        run = execute_chapter(path, out_dir, assets)
        budget = budget_seconds(run.name)
        note = f" (budget {budget:.0f} s)" if budget else ""
        print(
            f"[course] {run.name}: {run.seconds:.1f} s{note}"
            + (f" FAILED: {run.error}" if run.error else ""),
            flush=True,
        )
        runs.append(run)
    index = write_index(out_dir, runs)
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
        help="directory of the chapters NN_name.ipynb (default: the course's)",
    )
    parser.add_argument("--only", nargs="+", metavar="NN", help="chapter numbers to run, e.g. 01 03")
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


if __name__ == "__main__":
    raise SystemExit(main())
