"""Run a command and keep its output: ``python -m motionlab.course.logs NAME -- COMMAND [ARGS...]``.

``make test`` and ``make course`` go through this, so that a failure seen once can be read afterwards. The
command's standard output and error go, merged and line by line, both to the terminal and to
``build/logs/NAME-<YYYYmmdd-HHMMSS>.log``, framed by a header (the command, the start time, the git commit)
and a footer (the exit code, the wall time). The newest :data:`KEEP` logs of each NAME are kept; older ones
are deleted. The exit code is the command's.

This module imports nothing heavy (no torch), so it adds no start-up time to the command it wraps.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

from motionlab.paths import REPO_ROOT, build_dir

#: How many logs of each name are kept.
KEEP = 10

_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")


def log_dir() -> Path:
    """``build/logs`` (under ``MOTIONLAB_BUILD`` when it is set, like every other build output)."""
    return build_dir() / "logs"


def _git_commit() -> str:
    try:
        out = subprocess.run(
            ["git", "-C", str(REPO_ROOT), "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
        )
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return out.stdout.strip() or "unknown"


def prune(directory: Path, name: str, keep: int = KEEP) -> list[Path]:
    """Delete all but the newest ``keep`` logs ``name-*.log`` in ``directory``; returns the deleted ones."""
    logs = sorted(directory.glob(f"{name}-*.log"))  # the time stamp in the name sorts by age
    old = logs[:-keep] if keep > 0 else logs
    for path in old:
        path.unlink(missing_ok=True)
    return old


def run_logged(name: str, command: list[str], directory: Path | None = None, keep: int = KEEP) -> int:
    """Run ``command``, copying its merged output to the terminal and to a new log; returns its exit code."""
    if not _NAME.fullmatch(name):
        raise ValueError(f"log name must be letters, digits, '.', '_' or '-', got {name!r}")
    if not command:
        raise ValueError("no command to run")
    directory = log_dir() if directory is None else directory
    directory.mkdir(parents=True, exist_ok=True)
    stamp = time.strftime("%Y%m%d-%H%M%S")
    path = directory / f"{name}-{stamp}.log"
    suffix = 1
    while path.exists():  # two runs in the same second
        path = directory / f"{name}-{stamp}.{suffix}.log"
        suffix += 1
    start = time.monotonic()
    with path.open("w", encoding="utf-8", errors="replace") as log:
        log.write(
            f"# {' '.join(command)}\n# started {time.strftime('%Y-%m-%d %H:%M:%S %Z')}, "
            f"commit {_git_commit()}, profile {os.environ.get('MOTIONLAB_PROFILE', 'full')}\n"
        )
        log.flush()
        try:
            process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, bufsize=0)
        except OSError as exc:
            message = f"cannot run {command[0]!r}: {exc.strerror or exc}"
            log.write(message + "\n")
            print(f"motionlab.course.logs: {message}", file=sys.stderr)
            return 127
        assert process.stdout is not None
        try:
            for line in iter(process.stdout.readline, b""):
                sys.stdout.buffer.write(line)
                sys.stdout.flush()
                log.write(line.decode("utf-8", errors="replace"))
                log.flush()
        except KeyboardInterrupt:  # Ctrl-C reaches the command too (same process group); wait for it
            pass
        code = process.wait()
        log.write(f"# exit code {code} after {time.monotonic() - start:.0f} s\n")
    prune(directory, name, keep)
    print(f"[log] {path}", flush=True)
    return code


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) < 3 or argv[1] != "--":
        print("usage: python -m motionlab.course.logs NAME -- COMMAND [ARGS...]", file=sys.stderr)
        return 2
    try:
        return run_logged(argv[0], argv[2:])
    except (ValueError, OSError) as exc:  # a bad name, or a log folder that cannot be made
        print(f"motionlab.course.logs: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
