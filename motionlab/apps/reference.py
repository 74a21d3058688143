"""``python -m motionlab.apps.reference export BUILD | verify``: the shipped reference models' command.

``export`` copies the full-profile runs a course build used into ``reference/`` with their manifests (what
``make reference`` runs after its retraining build); ``verify`` checks every reference model against its
manifest. Errors end the command with one line on stderr and exit code 1. The store itself is
:mod:`motionlab.train.reference`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from motionlab.train import reference


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m motionlab.apps.reference",
        description="Export the full-profile runs of a course build as the shipped reference models.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    exp = sub.add_parser("export", help="copy a build's used runs into reference/ with manifests")
    exp.add_argument("build", type=Path, help="the build folder of a full-profile course (MOTIONLAB_BUILD)")
    sub.add_parser("verify", help="check every reference model against its manifest")
    args = parser.parse_args(argv)
    try:
        if args.command == "export":
            manifests = reference.export(args.build.resolve())
            print(f"exported {len(manifests)} reference models to {reference.REFERENCE_DIR}")
        else:
            files = sorted(reference.REFERENCE_DIR.glob("*.pt"))
            for path in files:
                reference.verify(path)
            print(f"{len(files)} reference models match their manifests")
    except reference.ReferenceError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
