"""``make test`` and ``make course`` keep their output: every run writes a log, the newest ten are kept."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from motionlab.course import logs


def test_a_run_is_copied_to_the_terminal_and_to_a_log_with_its_exit_code(tmp_path: Path, capfd) -> None:
    code = logs.run_logged(
        "test",
        [sys.executable, "-c", "import sys; print('out'); print('err', file=sys.stderr); sys.exit(3)"],
        tmp_path,
    )
    assert code == 3
    [log] = tmp_path.glob("test-*.log")
    text = log.read_text()
    assert "out\n" in text and "err\n" in text and "# exit code 3" in text
    assert "out" in capfd.readouterr().out


def test_only_the_newest_logs_are_kept(tmp_path: Path) -> None:
    for stamp in range(12):
        (tmp_path / f"course-20260101-0000{stamp:02d}.log").write_text("old")
    (tmp_path / "test-20250101-000000.log").write_text("another name")
    deleted = logs.prune(tmp_path, "course", keep=10)
    assert sorted(p.name for p in deleted) == ["course-20260101-000000.log", "course-20260101-000001.log"]
    assert len(list(tmp_path.glob("course-*.log"))) == 10 and (tmp_path / "test-20250101-000000.log").exists()


def test_a_command_that_cannot_start_is_reported_in_one_line(tmp_path: Path, capsys) -> None:
    assert logs.run_logged("test", ["/no/such/program"], tmp_path) == 127
    assert "cannot run '/no/such/program'" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [[], ["test"], ["test", "echo"], ["bad name", "--", "echo"]])
def test_bad_arguments_get_a_usage_line(argv: list[str], capsys) -> None:
    assert logs.main(argv) == 2
    assert "Traceback" not in capsys.readouterr().err


def test_a_log_folder_that_cannot_be_made_is_reported_in_one_line(
    tmp_path: Path, monkeypatch, capsys
) -> None:
    not_a_folder = tmp_path / "build"
    not_a_folder.write_text("a file")
    monkeypatch.setenv("MOTIONLAB_BUILD", str(not_a_folder))
    assert logs.main(["test", "--", "echo"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("motionlab.course.logs: ") and err.count("\n") == 1
