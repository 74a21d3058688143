"""The stress harness counts executions, hangs, stalls and failures, and writes its summary as it goes."""

from __future__ import annotations

import json
from pathlib import Path

import nbformat
import pytest

from motionlab.course import stress
from motionlab.course.kernel import CellLimits


def test_the_pattern_notebook_repeats_the_chapters_cell_patterns() -> None:
    notebook = stress.pattern_notebook(3)
    sources = [cell.source for cell in notebook.cells]
    assert len(sources) == 1 + 3 * len(stress._BLOCK)
    assert (
        sum("interactive_output" in s for s in sources) == 3
        and sum("run_in_workers(noisy_work" in s for s in sources) == 3
    )
    with pytest.raises(ValueError, match="blocks"):
        stress.pattern_notebook(0)


def test_the_worker_side_of_a_pattern_cell_reports_its_updates(capsys) -> None:
    assert stress.noisy_work(0.1) == 5
    assert "5 updates" in capsys.readouterr().out


@pytest.mark.parametrize("stock", [False, True])
def test_a_session_counts_executions_and_failures_and_writes_its_summary(tmp_path: Path, stock: bool) -> None:
    ok, broken = nbformat.v4.new_notebook(), nbformat.v4.new_notebook()
    ok.cells = [nbformat.v4.new_code_cell("1 + 1")]
    broken.cells = [nbformat.v4.new_code_cell("1 / 0")]
    limits = CellLimits(cell_seconds=60)
    out = tmp_path / "summary.json"
    summary = stress.run_stress(
        [("ok", ok, tmp_path, limits), ("broken", broken, tmp_path, limits)], 2, "test", out, stock=stock
    )
    assert (summary.executions, summary.cells, len(summary.hangs), len(summary.failures)) == (4, 4, 0, 2)
    written = json.loads(out.read_text())
    assert written["executions"] == 4 and written["failures"][0]["notebook"] == "broken"
    assert written["versions"]["ipykernel"] and written["client"] == (
        "nbclient (stock)" if stock else "WatchedClient"
    )


@pytest.mark.parametrize(
    ("argv", "message"),
    [(["--runs", "0"], "--runs"), (["--only", "99"], "no chapter 99"), (["--patterns", "x"], "--patterns")],
)
def test_bad_arguments_get_one_line(argv: list[str], message: str, capsys) -> None:
    with pytest.raises(SystemExit) as exit_info:
        stress.main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
