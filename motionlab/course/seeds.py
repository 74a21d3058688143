"""Claims over training seeds: every claim's value in full-profile course builds whose models were trained
with base seeds 0, 1 and 2 (``MOTIONLAB_SEED``), kept in ``reference/seeds/claims.json`` and shown in
each chapter's "Paper vs. us" section (:func:`chapter_table`).

A verdict that holds for one training seed only is a fact about that run, not about the method; the table
shows which of the course's claims hold for all three. It is recorded from the builds' ``results.json``
files by ``python -m motionlab.apps.reference seeds 0=BUILD 1=BUILD 2=BUILD`` (:func:`collect`,
:func:`save`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from motionlab.course.results import _OPS
from motionlab.paths import REPO_ROOT

#: Where the table is kept.
SEED_CLAIMS_PATH = REPO_ROOT / "reference" / "seeds" / "claims.json"


def collect(
    builds: dict[int, Path], base: dict[str, Any] | None = None, chapters: tuple[str, ...] = ()
) -> dict[str, Any]:
    """The claims of the full-profile course builds ``{seed: build folder}``: ``{"seeds": {seed: the build's
    models, numerical path and torch}, "claims": {name: {"op", "threshold", "expected", "text", "values":
    {seed: value}}}}``.

    With ``base`` (a record of this shape, e.g. the shipped table), the builds update it: each replaces its
    seed's values of the claims of the notebooks it ran (a claim such a notebook no longer makes loses that
    seed's value, and goes when no seed has one), and the other notebooks' claims stay as recorded. A model
    family that changed is then measured again in the chapters that use it alone. ``chapters`` (e.g.
    ``("06",)``), when given, limits what the builds bring to those chapters and their appendices: a build
    folder's ``results.json`` keeps every chapter it has ever built, also those an earlier build left there.

    Raises ``FileNotFoundError`` naming a build without ``course/results.json`` and ``ValueError`` for a
    build whose recorded base seed is not the one given, or that is not a full-profile build.
    """
    seeds: dict[str, Any] = dict((base or {}).get("seeds", {}))
    claims: dict[str, dict[str, Any]] = {
        name: {**claim, "values": dict(claim["values"])}
        for name, claim in (base or {}).get("claims", {}).items()
    }
    for seed, folder in sorted(builds.items()):
        path = Path(folder) / "course" / "results.json"
        if not path.is_file():
            raise FileNotFoundError(f"seed {seed}: {path} does not exist (build the course there first)")
        results = json.loads(path.read_text(encoding="utf-8"))
        if results.get("base_seed") != seed:
            raise ValueError(f"seed {seed}: {path} was built with base seed {results.get('base_seed')}")
        if results.get("profile") != "full":
            raise ValueError(
                f"seed {seed}: {path} is a {results.get('profile')!r} build, not a full-profile one"
            )
        seeds[str(seed)] = {key: results.get(key) for key in ("models", "numerics", "torch")}
        notebooks = {
            stem: notebook
            for stem, notebook in results.get("notebooks", {}).items()
            if not chapters or stem[:2] in chapters
        }
        ran = {stem.split("_", 1)[0] for stem in notebooks}  # "04", "04a"
        for name, claim in claims.items():
            if name.split(".", 1)[0] in ran:  # measured again by this build (or no longer claimed)
                claim["values"].pop(str(seed), None)
        for notebook in notebooks.values():
            for name, claim in notebook.get("claims", {}).items():
                entry = claims.setdefault(name, {"values": {}})
                entry.update({key: claim.get(key) for key in ("op", "threshold", "expected", "text")})
                entry["values"][str(seed)] = claim["value"]
    kept = {name: claim for name, claim in claims.items() if claim["values"]}
    return {"seeds": dict(sorted(seeds.items())), "claims": dict(sorted(kept.items()))}


def load(path: Path | None = None) -> dict[str, Any]:
    """The recorded table at ``path`` (default :data:`SEED_CLAIMS_PATH`); ``FileNotFoundError`` when it is
    missing."""
    path = SEED_CLAIMS_PATH if path is None else path
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing: python -m motionlab.apps.reference seeds records it")
    return json.loads(path.read_text(encoding="utf-8"))


def save(record: dict[str, Any], path: Path | None = None) -> Path:
    """Write ``record`` (:func:`collect`) as indented JSON to ``path`` (default :data:`SEED_CLAIMS_PATH`)."""
    path = SEED_CLAIMS_PATH if path is None else path
    path.write_text(json.dumps(record, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return path


def _number(value: float) -> str:
    return f"{value:.3g}" if math.isfinite(value) else str(value)


def chapter_table(number: str, path: Path | None = None) -> str:
    """A Markdown table of the claims of chapter ``number`` (``"04"``: ``04.*`` and its appendices'
    ``04a.*``) over the recorded seeds: the rule, each seed's value (✗ where it does not hold, – where that
    build did not run the chapter) and the verdict: holds on every seed measured, fails, or a known gap.
    Read from ``path`` (default :data:`SEED_CLAIMS_PATH`); raises ``FileNotFoundError`` when it is
    missing."""
    record = load(path)
    seeds = sorted(record["seeds"], key=int)
    rows = []
    for name, claim in record["claims"].items():
        if name.split(".", 1)[0].rstrip("abcdefghijklmnopqrstuvwxyz") != number:
            continue
        cells, held, measured = [], 0, 0
        for seed in seeds:
            value = claim["values"].get(seed)
            if value is None:
                cells.append("–")
                continue
            holds = _OPS[claim["op"]](value, claim["threshold"])
            held, measured = held + holds, measured + 1
            cells.append(_number(value) + ("" if holds else " ✗"))
        if claim["expected"] is False:
            verdict = "known gap"
        elif held < measured:
            verdict = "**fails**"
        else:
            verdict = "holds" if measured == len(seeds) else f"holds on the {measured} seeds measured"
        rule = f"{claim['op']} {_number(claim['threshold'])}"
        rows.append(f"| `{name}` | {rule} | " + " | ".join(cells) + f" | {verdict} |")
    if not rows:
        return f"No claim of chapter {number} is recorded over training seeds."
    header = "| claim | rule | " + " | ".join(f"seed {seed}" for seed in seeds) + " | verdict |"
    return "\n".join([header, "|---" * (len(seeds) + 3) + "|", *rows])
