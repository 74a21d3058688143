"""The command lines refuse bad arguments with one line on stderr and exit status 2, never a traceback.

``python -m motionlab.data.synthetic`` and ``python -m motionlab.bench``, through the shared checks of
:mod:`motionlab.arguments`. Most cases call ``main(argv)`` in this process; a few run the real command.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from motionlab import arguments
from motionlab.bench import __main__ as bench
from motionlab.data import synthetic
from motionlab.data.store import MotionSet

SYNTHETIC = "python -m motionlab.data.synthetic"
BENCH = "python -m motionlab.bench"


def refusal(main: Callable[[list[str]], int], argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """Run ``main(argv)``, check it refused with status 2 and one error line; return that line."""
    try:
        status = main(argv)
    except SystemExit as exit_:
        status = exit_.code
    err = capsys.readouterr().err
    assert status == 2, err
    assert "Traceback" not in err
    errors = [line for line in err.splitlines() if "error:" in line]
    assert len(errors) == 1 and errors[0] == err.splitlines()[-1], err
    return errors[0]


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """A directory holding a plain file ``afile`` (a file where a directory is expected)."""
    (tmp_path / "afile").write_text("")
    return tmp_path


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--seed", "0", "--bogus"], "unrecognized arguments: --bogus"),
        (["--seed", "-1"], "argument --seed: must be an integer of at least 0, got '-1'"),
        (["--seed", "1.5"], "argument --seed: must be an integer of at least 0, got '1.5'"),
        (["--seed", "zero"], "argument --seed: must be an integer of at least 0, got 'zero'"),
        (
            ["--seed", "0", "--n-per-mode", "0"],
            "argument --n-per-mode: must be an integer of at least 1, got '0'",
        ),
        (
            ["--seed", "0", "--n-per-mode", "-2"],
            "argument --n-per-mode: must be an integer of at least 1, got '-2'",
        ),
        (["--seed", "0", "--n-per-mode", "ten"], "argument --n-per-mode: must be an integer of at least 1"),
        (
            ["--seed", "0", "--seconds", "0"],
            "argument --seconds: must be a finite number of at least 1, got '0'",
        ),
        (
            ["--seed", "0", "--seconds", "nan"],
            "argument --seconds: must be a finite number of at least 1, got 'nan'",
        ),
        (["--seed", "0", "--fps", "5"], "argument --fps: must be an integer of at least 10, got '5'"),
        (["--seed", "0", "--seconds", "1e308"], "cannot convert float infinity to integer"),
        (["--seed", "0", "--split", "dev"], "argument --split: invalid choice: 'dev'"),
        (["--seed", "0", "--checksums", "{folder}/missing/sums.json"], "argument --checksums: directory"),
    ],
)
def test_synthetic_refuses_bad_values(
    folder: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    out = folder / "x.npz"
    line = refusal(synthetic.main, ["--out", str(out), *(a.format(folder=folder) for a in argv)], capsys)
    assert line.startswith(f"{SYNTHETIC}: error: ") and message in line
    assert not out.exists()


@pytest.mark.parametrize(
    ("out", "message"),
    [
        (
            "missing/x.npz",
            "argument --out: directory '{folder}/missing' of '{folder}/missing/x.npz' does not exist",
        ),
        ("", "argument --out: '{folder}/' is a directory, expected a file name"),
        ("afile/x.npz", "argument --out: '{folder}/afile' in '{folder}/afile/x.npz' is not a directory"),
    ],
)
def test_synthetic_refuses_bad_output_paths(
    folder: Path, capsys: pytest.CaptureFixture[str], out: str, message: str
) -> None:
    line = refusal(synthetic.main, ["--out", f"{folder}/{out}", "--seed", "0"], capsys)
    assert message.format(folder=folder) in line
    assert not (folder / "missing").exists()


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write into a read-only directory")
def test_synthetic_refuses_an_unwritable_directory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    line = refusal(synthetic.main, ["--out", str(locked / "x.npz"), "--seed", "0"], capsys)
    assert f"argument --out: directory '{locked}' of '{locked}/x.npz' is not writable" in line


def test_a_failed_write_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """An error that only shows while writing (e.g. a full disk) still ends in one line, not a traceback."""
    out = tmp_path / "x.npz"

    def full_disk(self: MotionSet, path: Path, compress: bool = False) -> Path:
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(MotionSet, "save", full_disk)
    argv = ["--out", str(out), "--seed", "0", "--n-per-mode", "1", "--seconds", "1", "--fps", "10"]
    line = refusal(synthetic.main, argv, capsys)
    assert line == f"{SYNTHETIC}: error: [Errno 28] No space left on device: '{out}'"


def test_the_synthetic_command_line_still_writes(tmp_path: Path) -> None:
    sums = tmp_path / "sums.json"
    argv = [
        "--out",
        str(tmp_path / "x.npz"),
        "--seed",
        "2",
        "--n-per-mode",
        "1",
        "--seconds",
        "1",
        "--fps",
        "10",
        "--checksums",
        str(sums),
    ]
    assert synthetic.main(argv) == 0
    assert MotionSet.load(tmp_path / "x.npz").n_clips == 12 and json.loads(sums.read_text())["seed"] == 2


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--bogus"], "unrecognized arguments: --bogus"),
        (["nosuch"], "unknown entry 'nosuch' (choose from data, diffusion, geometry,"),
        (["geometry", "nosuch", "other"], "unknown entry 'nosuch', 'other'"),
        (["--out", "{folder}/missing/bench.json"], "argument --out: directory '{folder}/missing'"),
        (["--out", "{folder}"], "argument --out: '{folder}' is a directory"),
        (["geometry", "--out", "{folder}/afile/bench.json"], "argument --out: '{folder}/afile' in"),
    ],
)
def test_bench_refuses_bad_arguments(
    folder: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    argv: list[str],
    message: str,
) -> None:
    monkeypatch.setattr(bench.subprocess, "run", pytest.fail)  # nothing may run
    line = refusal(bench.main, [a.format(folder=folder) for a in argv], capsys)
    assert line.startswith(f"{BENCH}: error: ") and message.format(folder=folder) in line


def test_bench_runs_only_the_named_entries_into_out(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    ran: list[str] = []

    def fake_run(command: list[str], **kwargs: object) -> subprocess.CompletedProcess[str]:
        ran.append(command[-1])
        return subprocess.CompletedProcess(command, 0, stdout='BENCH-JSON {"seconds": 1.0}\n', stderr="")

    monkeypatch.setattr(bench.subprocess, "run", fake_run)
    out = tmp_path / "bench.json"
    assert bench.main(["viz", "geometry", "viz", "--out", str(out)]) == 0
    assert ran == ["viz", "geometry"]
    assert json.loads(out.read_text())["results"] == {"viz": {"seconds": 1.0}, "geometry": {"seconds": 1.0}}


@pytest.mark.parametrize(
    ("module", "argv", "message"),
    [
        (
            "motionlab.data.synthetic",
            ["--out", "x.npz", "--seed", "0", "--n-per-mode", "-2"],
            "argument --n-per-mode",
        ),
        ("motionlab.data.synthetic", ["--out", "missing/x.npz", "--seed", "0"], "argument --out"),
        ("motionlab.bench", ["nosuch"], "unknown entry 'nosuch'"),
    ],
)
def test_the_real_commands_print_one_line(tmp_path: Path, module: str, argv: list[str], message: str) -> None:
    """As a user runs them: ``python -m ...`` in some directory, the error on the last line of stderr."""
    completed = subprocess.run(
        [sys.executable, "-m", module, *argv], cwd=tmp_path, capture_output=True, text=True, timeout=120
    )
    assert completed.returncode == 2 and "Traceback" not in completed.stderr
    assert message in completed.stderr.splitlines()[-1]
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "error",
    [
        ValueError("bad\nvalue"),
        FileNotFoundError(2, "No such file", "f.npz"),
        MemoryError("Unable to allocate 8 TiB"),
        OverflowError("cannot convert float infinity to integer"),
    ],
)
def test_run_reports_user_errors_on_one_line(capsys: pytest.CaptureFixture[str], error: Exception) -> None:
    def command() -> int:
        raise error

    assert arguments.run("prog", command) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("prog: error: ") and "Traceback" not in err


def test_run_lets_bugs_keep_their_traceback() -> None:
    with pytest.raises(KeyError):
        arguments.run("prog", lambda: {}["missing"])
