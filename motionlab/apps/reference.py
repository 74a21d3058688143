"""``python -m motionlab.apps.reference export BUILD | verify | seeds [--update [--chapters NN,NN]] SEED=BUILD
...``: the shipped reference models' command.

``export`` copies the full-profile runs a course build trained into ``reference/`` with their manifests and
keeps the reference models it loaded (what ``make reference`` runs after its build); ``verify`` checks every
reference model against its manifest; ``seeds`` records the claims of course builds trained with other base
seeds (:mod:`motionlab.course.seeds`; with ``--update``, of the chapters those builds ran, or of those
``--chapters`` names, the rest kept).
Errors end the command with one line on stderr and exit code 1. The store itself is
:mod:`motionlab.train.reference`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from motionlab.course import seeds as seed_claims
from motionlab.train import reference


def _seed_build(text: str) -> tuple[int, Path]:
    """``SEED=BUILD`` as ``(seed, build folder)``."""
    seed, sep, folder = text.partition("=")
    if not sep or not seed.isdigit() or not folder:
        raise argparse.ArgumentTypeError(f"expected SEED=BUILD (e.g. 1=/tmp/seed1/build), got {text!r}")
    return int(seed), Path(folder)


def _chapter_numbers(text: str) -> tuple[str, ...]:
    """Chapters' two-digit numbers separated by commas, e.g. ``06,09``."""
    numbers = tuple(text.split(","))
    if not all(len(number) == 2 and number.isdigit() for number in numbers):
        raise argparse.ArgumentTypeError(f"expected chapters' two-digit numbers (e.g. 06,09), got {text!r}")
    return numbers


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m motionlab.apps.reference",
        description="Export the full-profile runs of a course build as the shipped reference models.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    exp = sub.add_parser("export", help="copy a build's used runs into reference/ with manifests")
    exp.add_argument("build", type=Path, help="the build folder of a full-profile course (MOTIONLAB_BUILD)")
    exp.add_argument(
        "--partial",
        action="store_true",
        help="the build ran some chapters only: keep the references it did not use",
    )
    exp.add_argument(
        "--replace",
        nargs="+",
        default=(),
        metavar="NAME",
        help="with --partial: runs whose configuration changed; their references the build did not use go",
    )
    sub.add_parser("verify", help="check every reference model against its manifest")
    seeds = sub.add_parser("seeds", help="record the claims of builds trained with base seeds 0, 1, 2, ...")
    seeds.add_argument("builds", nargs="+", type=_seed_build, help="SEED=BUILD, e.g. 1=/tmp/seed1/build")
    seeds.add_argument(
        "--update",
        action="store_true",
        help="replace only the claims of the notebooks these builds ran; keep the rest of the table",
    )
    seeds.add_argument(
        "--chapters",
        default=(),
        type=_chapter_numbers,
        metavar="NN[,NN...]",
        help="take only these chapters' claims (and their appendices') from the builds, e.g. 06,09: "
        "a build folder keeps the results of every chapter it has built",
    )
    args = parser.parse_args(argv)
    if args.command == "export" and args.replace and not args.partial:
        parser.error("export: --replace names runs of a --partial build (a whole build replaces every run)")
    if args.command == "seeds" and args.chapters and not args.update:
        parser.error("seeds: --chapters limits an --update (a table without --update holds every chapter)")
    try:
        if args.command == "export":
            manifests = reference.export(
                args.build.resolve(), partial=args.partial, replace=tuple(args.replace)
            )
            print(f"exported {len(manifests)} reference models to {reference.REFERENCE_DIR}")
        elif args.command == "seeds":
            base = seed_claims.load() if args.update else None
            record = seed_claims.collect(dict(args.builds), base, args.chapters)
            path = seed_claims.save(record)
            print(f"{len(record['claims'])} claims over seeds {', '.join(record['seeds'])} written to {path}")
        else:
            files = sorted(reference.REFERENCE_DIR.glob("*.pt"))
            for path in files:
                reference.verify(path)
            print(f"{len(files)} reference models match their manifests")
    except (reference.ReferenceError, FileNotFoundError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
