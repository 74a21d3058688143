"""Run every benchmark module of :mod:`motionlab.bench` and write ``build/bench.json``.

Each module runs in its own process, with torch on one thread unless the module says otherwise,
so that one area's peak memory (``ru_maxrss``) does not leak into another's.
"""

from __future__ import annotations

import json
import pkgutil
import platform
import subprocess
import sys
import time

import motionlab.bench
from motionlab import config

_CHILD = """
import json, resource, sys, time
import importlib
module = importlib.import_module("motionlab.bench." + sys.argv[1])
start = time.perf_counter()
result = module.run()
result["bench_seconds"] = time.perf_counter() - start
result["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print("BENCH-JSON " + json.dumps(result))
"""


def main() -> None:
    names = sorted(m.name for m in pkgutil.iter_modules(motionlab.bench.__path__) if not m.name.startswith("_"))
    report: dict = {"python": platform.python_version(), "machine": platform.machine(), "results": {}}
    for name in names:
        print(f"bench: {name} ...", flush=True)
        start = time.perf_counter()
        proc = subprocess.run([sys.executable, "-c", _CHILD, name], capture_output=True, text=True)
        if proc.returncode != 0:
            sys.stderr.write(proc.stderr)
            raise SystemExit(f"bench module {name} failed (exit {proc.returncode})")
        line = next(line for line in proc.stdout.splitlines() if line.startswith("BENCH-JSON "))
        report["results"][name] = json.loads(line[len("BENCH-JSON "):])
        print(f"bench: {name} done in {time.perf_counter() - start:.1f} s", flush=True)
    out = config.build_dir() / "bench.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=2, sort_keys=True))
    print(json.dumps(report, indent=2, sort_keys=True))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
