"""``make course``: execute every chapter and build the report in ``build/course/``.

For each ``notebooks/NN_name.ipynb`` in order: execute it headless in a fresh kernel (cwd ``notebooks/``,
widget state stored in the notebook), record its wall time in ``results.json``, and write the executed
notebook and an HTML rendering. Then write ``index.html``: a link to every chapter, its time against its
budget, and the metrics and claims tables of ``results.json``.

A chapter that fails (an error, or a claim that stopped holding in the full profile) does not stop the
build: the remaining chapters still run so the report shows everything, and the command exits non-zero.

Usage: ``python -m motionlab.course [--only 01 03] [--notebooks DIR]``.
"""

from __future__ import annotations

import argparse
import html
import sys
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import nbformat
from nbclient import NotebookClient
from nbconvert import HTMLExporter

from motionlab import config
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
}

CELL_TIMEOUT_SECONDS = 1200


@dataclass(frozen=True)
class ChapterRun:
    """The outcome of executing one chapter."""

    name: str
    seconds: float
    error: str | None


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


def execute_chapter(path: Path, out_dir: Path) -> ChapterRun:
    """Execute one notebook; write ``<name>.ipynb`` and ``<name>.html`` to ``out_dir`` (even on failure)."""
    name = path.stem
    notebook = nbformat.read(path, as_version=4)
    client = NotebookClient(
        notebook,
        timeout=CELL_TIMEOUT_SECONDS,
        kernel_name="python3",
        resources={"metadata": {"path": str(path.parent)}},
        store_widget_state=True,
    )
    error = None
    start = time.perf_counter()
    try:
        client.execute()
    except Exception as exc:  # the report shows what failed; the build's exit code says it failed
        error = f"{type(exc).__name__}: {exc}"
    seconds = time.perf_counter() - start
    update_notebook(name, lambda entry: entry.update(seconds=round(seconds, 2)))
    nbformat.write(notebook, out_dir / f"{name}.ipynb")
    body, _ = HTMLExporter(template_name="lab").from_notebook_node(notebook)
    (out_dir / f"{name}.html").write_text(body, encoding="utf-8")
    return ChapterRun(name, seconds, error)


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
                f"<tr class='{css}'><td>{html.escape(chapter)}</td><td><code>{html.escape(claim_id)}</code></td>"
                f"<td>{html.escape(str(claim.get('text', '')))}</td><td>{claim.get('value', float('nan')):.4g}</td>"
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
            rows.append(f"<tr><td>{html.escape(chapter)}</td><td><code>{html.escape(key)}</code></td><td>{shown}</td></tr>")
    return "\n".join(rows)


def write_index(out_dir: Path, runs: list[ChapterRun]) -> Path:
    """Write ``index.html`` from the runs and ``results.json``."""
    results = load_results()
    chapter_rows = []
    for run in runs:
        budget = budget_seconds(run.name)
        over = budget is not None and run.seconds > budget
        status = "failed: " + html.escape(run.error) if run.error else ("over budget" if over else "ok")
        css = "bad" if run.error or over else "ok"
        chapter_rows.append(
            f"<tr class='{css}'><td><a href='{run.name}.html'>{html.escape(run.name)}</a></td>"
            f"<td>{run.seconds:.1f} s</td><td>{'' if budget is None else f'{budget:.0f} s'}</td><td>{status}</td></tr>"
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
<p>Profile <b>{html.escape(results['profile'])}</b>, Python {html.escape(results['python'])},
torch {html.escape(results['torch'])}. Total chapter time {total / 60:.1f} min.
Raw numbers: <a href="results.json">results.json</a>.</p>
<h2>Chapters</h2>
<table><tr><th>chapter</th><th>time</th><th>budget</th><th>status</th></tr>
{''.join(chapter_rows)}
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


def build(notebook_dir: Path, only: list[str] | None = None) -> list[ChapterRun]:
    """Execute the chapters (all, or those whose number is in ``only``) and write the report."""
    out_dir = config.course_dir()
    out_dir.mkdir(parents=True, exist_ok=True)
    chapters = chapter_notebooks(notebook_dir)
    if only:
        chapters = [p for p in chapters if p.stem[:2] in only]
        if not chapters:
            raise SystemExit(f"no chapter matches --only {only}")
    config.set_threads()
    runs = []
    for path in chapters:
        print(f"[course] {path.stem} ...", flush=True)
        run = execute_chapter(path, out_dir)
        budget = budget_seconds(run.name)
        note = f" (budget {budget:.0f} s)" if budget else ""
        print(f"[course] {run.name}: {run.seconds:.1f} s{note}" + (f" FAILED: {run.error}" if run.error else ""), flush=True)
        runs.append(run)
    index = write_index(out_dir, runs)
    print(f"[course] report: {index}\n[course] results: {results_path()}")
    return runs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--notebooks", type=Path, default=config.REPO_ROOT / "notebooks")
    parser.add_argument("--only", nargs="*", help="chapter numbers to run, e.g. 01 03")
    args = parser.parse_args(argv)
    try:
        runs = build(args.notebooks, args.only)
    except Exception:
        traceback.print_exc()
        return 1
    failed = [run.name for run in runs if run.error]
    if failed:
        print(f"[course] failed chapters: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
