"""Run the entries of the benchmark registry (:data:`motionlab.bench.ENTRIES`) and write ``build/bench.json``.

Usage: ``python -m motionlab.bench [ENTRY ...] [--out FILE]``: every entry of the registry by default, or only
the named ones; ``--out`` replaces ``build/bench.json``. Each entry runs in its own process, with torch on
one thread unless the module says otherwise, so that one area's peak memory (``ru_maxrss``) does not leak into
another's.
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import time
from pathlib import Path

from motionlab import arguments, config
from motionlab.bench import ENTRIES

PROG = "python -m motionlab.bench"

_CHILD = """
import json, resource, sys, time
from motionlab.bench import ENTRIES
measure = ENTRIES[sys.argv[1]].load()
start = time.perf_counter()
result = measure()
result["bench_seconds"] = time.perf_counter() - start
result["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print("BENCH-JSON " + json.dumps(result))
"""


def entry_names() -> list[str]:
    """The benchmark entries of the registry (:data:`motionlab.bench.ENTRIES`), in its order."""
    return list(ENTRIES)


def _run_entries(names: list[str], out: Path | None) -> int:
    """Run the entries ``names`` (each in a fresh process) and write the merged report to ``out``; returns
    0."""
    if out is None:
        out = config.build_dir() / "bench.json"
        out.parent.mkdir(parents=True, exist_ok=True)
    report: dict = {"python": platform.python_version(), "machine": platform.machine(), "results": {}}
    for name in names:
        print(f"bench: {name} ...", flush=True)
        start = time.perf_counter()
        proc = subprocess.run([sys.executable, "-c", _CHILD, name], capture_output=True, text=True)
        if proc.returncode != 0:
            sys.stderr.write(proc.stderr)
            raise SystemExit(f"bench module {name} failed (exit {proc.returncode})")
        line = next(line for line in proc.stdout.splitlines() if line.startswith("BENCH-JSON "))
        report["results"][name] = json.loads(line[len("BENCH-JSON ") :])
        print(f"bench: {name} done in {time.perf_counter() - start:.1f} s", flush=True)
    out.write_text(json.dumps(report, indent=2, sort_keys=True))
    print(json.dumps(report, indent=2, sort_keys=True))
    print(f"wrote {out}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """The command line; returns the exit status (2, with a one-line message, for a bad argument)."""
    names = entry_names()
    parser = argparse.ArgumentParser(prog=PROG, description="Measure speed and memory; write a JSON report.")
    parser.add_argument(
        "entries", nargs="*", metavar="ENTRY", help=f"entries to run (default: all): {', '.join(names)}"
    )
    parser.add_argument(
        "--out",
        type=arguments.output_file,
        metavar="FILE",
        help="report file (default build/bench.json); its directory must exist",
    )
    args = parser.parse_args(argv)
    unknown = [entry for entry in args.entries if entry not in names]
    if unknown:  # not choices=names: Python 3.11 checks an empty nargs="*" list against the choices too
        parser.error(f"unknown entry {', '.join(map(repr, unknown))} (choose from {', '.join(names)})")
    selected = list(dict.fromkeys(args.entries)) or names
    return arguments.run(PROG, lambda: _run_entries(selected, args.out))


if __name__ == "__main__":
    sys.exit(main())
