"""The report's front page, ``index.html``: what the course is, the headline comparison, every chapter.

Built by :mod:`motionlab.course` after the chapters ran, from ``results.json`` and the executed notebooks in
the report directory. From top to bottom:

1. what the course is, the profile and the total time against the 20-minute budget;
2. the claims at a glance: how many hold, and every known gap and failure in plain sight;
3. the headline comparison of chapter 09 (the five generators on one benchmark): its table, read from the
   chapter's recorded metrics ``common.<method>.<column>``, and its key figure;
4. one card per chapter: its opening paragraph, its key figure, its time against its budget, its claims
   (holds / known gap / fails, in colour) and a link to the executed chapter; a chapter's appendix
   (``NNa_*``, :mod:`motionlab.course.chapters`) has a card of its own, indented under its chapter's;
5. every recorded metric, in a collapsed table.

A chapter's *key figure* is the first PNG output of a cell tagged ``key-figure`` in the executed notebook, or
else its first PNG figure; it is written to ``figures/<chapter>.png`` beside the page. The page is
self-contained (inline style, local images, no script), so it works offline from the file system.
"""

from __future__ import annotations

import base64
import html
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import nbformat

from motionlab.course.chapters import is_appendix, notebook_number

#: The chapter whose metrics give the headline comparison, and the prefix of those metrics.
COMPARISON_CHAPTER = "09_evaluating_and_comparing"
COMPARISON_PREFIX = "common."

#: The headline table's columns: (metric name after ``common.<method>.``, header, digits).
HEADLINE_COLUMNS: tuple[tuple[str, str, int], ...] = (
    ("accuracy", "accuracy ↑", 3),
    ("fid", "FID ↓", 3),
    ("diversity", "diversity → real", 3),
    ("multimodality", "multimodality → real", 3),
    ("apd", "APD (m)", 3),
    ("skating", "skating (m/s) → real", 2),
    ("jerk", "jerk (m/s³) → real", 3),
    ("real-time_factor", "real-time factor, batch 1", 3),
    ("frames/s", "frames/s batched", 3),
    ("parameters", "parameters", 3),
    ("training_s", "training (s)", 3),
)

#: The methods' order in the headline table (the course's); others follow in the order recorded.
METHOD_ORDER = ("real", "Motion Cell", "MoGlow", "MoGlow p=0", "TrajeVAE", "ODMO")

#: Budget of the whole ``make course`` (design notes: 10 minutes with set-up, on the slower machines), in
#: seconds: the notebooks' wall time, set-up aside.
COURSE_BUDGET_SECONDS = 10 * 60

INTRO = (
    "A notebook-first course on probabilistic human-motion synthesis. Chapters 01–03 build the tools "
    "(rotations, skeletons and motion data, variational autoencoders); chapters 04–08 reproduce four papers "
    "on one synthetic motion-capture benchmark — the Motion Cell (Ghorbani et al. 2020), MoGlow (Henter et "
    "al. 2019), TrajeVAE (Kania et al. 2021) and ODMO (Lu et al. 2022) — and check their claims on our data; "
    "chapter 09 teaches how such models are judged and puts all four on one benchmark; chapter 10 carries "
    "ODMO and MoGlow over to real motion capture (CMU, ODMO's Table 2 protocol). Every number below was "
    "measured by this build."
)

_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 72em; margin: 2em auto; padding: 0 1em; color: #222; }
h1 { margin-bottom: 0.2em; } .lead { font-size: 1.05em; max-width: 60em; }
table { border-collapse: collapse; margin: 0.5em 0 1.5em; font-size: 0.92em; }
td, th { border: 1px solid #ccc; padding: 0.3em 0.55em; text-align: left; vertical-align: top; }
th { background: #f4f4f4; }
.ok { color: #176117; } .gap { color: #8a5a00; } .bad { color: #a11; font-weight: bold; }
.pill { display: inline-block; padding: 0.05em 0.5em; border-radius: 0.8em; font-size: 0.85em; color: #fff; }
.pill.ok { background: #2e7d32; } .pill.gap { background: #b7791f; } .pill.bad { background: #c62828; }
.card { border: 1px solid #ddd; border-radius: 6px; padding: 0.8em 1em; margin: 1em 0; display: flow-root; }
.card img { float: right; max-width: 42%; margin: 0 0 0.5em 1em; border: 1px solid #eee; }
.card h3 { margin-top: 0.1em; } .summary { max-width: 60em; }
.card.appendix { margin-left: 2.5em; background: #fafafa; }
figure { margin: 0.5em 0; } figure img { max-width: 100%; } .muted { color: #666; font-size: 0.9em; }
ul.claims { padding-left: 1.2em; } ul.claims li { margin: 0.25em 0; }
"""


@dataclass(frozen=True)
class ChapterStatus:
    """One chapter's line on the front page: ``seconds`` of its last execution, ``error`` if it failed,
    ``retries`` (abandoned executions), and whether it ran in this build (``current``)."""

    name: str
    seconds: float | None
    error: str | None = None
    retries: tuple[str, ...] = ()
    current: bool = True


def claim_verdict(claim: Mapping[str, Any]) -> tuple[str, str]:
    """``(text, css class)`` of a recorded claim: holds, known gap (with its why) or FAILS."""
    if claim.get("holds"):
        return "holds", "ok"
    if not claim.get("expected", True):
        return f"known gap: {claim.get('why', '')}", "gap"
    return "FAILS", "bad"


def _inline_markdown(text: str) -> str:
    """A paragraph of the notebooks' Markdown as HTML: escaped, with bold, italics, code and inline math kept
    readable without a typesetter (``$x$`` shows as an italic ``x`` with its LaTeX commands dropped)."""

    def math(match: re.Match) -> str:
        body = re.sub(r"\\(mathcal|mathbf|mathrm|operatorname|text)\b", "", match.group(1))
        body = re.sub(r"\\([a-zA-Z]+)", r"\1", body).replace("{", "").replace("}", "")
        return f"<i>{body}</i>"

    escaped = html.escape(text, quote=False)
    escaped = re.sub(r"\$([^$]+)\$", math, escaped)
    escaped = re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", escaped)
    escaped = re.sub(r"(?<![\w*])\*([^*\n]+)\*(?!\w)", r"<i>\1</i>", escaped)
    return re.sub(r"`([^`]+)`", r"<code>\1</code>", escaped)


def chapter_intro(notebook: nbformat.NotebookNode) -> tuple[str, str]:
    """``(title, first paragraph)`` of a chapter from its first Markdown cell (``# title`` then prose)."""
    for cell in notebook.cells:
        if cell.cell_type != "markdown":
            continue
        lines = cell.source.strip().splitlines()
        title = lines[0].lstrip("#").strip() if lines and lines[0].startswith("#") else ""
        body = "\n".join(lines[1:] if title else lines).strip()
        paragraph = " ".join(body.split("\n\n")[0].split())
        return title, paragraph
    return "", ""


def key_figure(notebook: nbformat.NotebookNode) -> bytes | None:
    """The PNG bytes of the chapter's key figure (see the module notes), or ``None`` when it has no figure."""
    tagged = [c for c in notebook.cells if "key-figure" in c.get("metadata", {}).get("tags", [])]
    code_cells = [c for c in notebook.cells if c.cell_type == "code"]
    for cell in tagged + code_cells:
        for output in cell.get("outputs", []):
            png = output.get("data", {}).get("image/png")
            if png:
                return base64.b64decode(png)
    return None


def _number(value: float, digits: int) -> str:
    if abs(value) >= 1000:
        return f"{value:,.0f}"
    return f"{value:.{digits}g}"


def comparison_table(metrics: Mapping[str, float]) -> str:
    """The headline table (HTML) from chapter 09's metrics ``common.<method>.<column>`` (``.ci95`` beside),
    or ``""`` when the chapter recorded none."""
    methods: list[str] = []
    for key in metrics:
        if key.startswith(COMPARISON_PREFIX) and not key.endswith(".ci95"):
            method = key[len(COMPARISON_PREFIX) :].split(".")[0]
            if method not in methods:
                methods.append(method)
    if not methods:
        return ""
    order = sorted(
        methods, key=lambda m: (METHOD_ORDER.index(m) if m in METHOD_ORDER else len(METHOD_ORDER), m)
    )
    header = "".join(f"<th>{html.escape(label)}</th>" for _, label, _ in HEADLINE_COLUMNS)
    rows = []
    for method in order:
        cells = []
        for column, _, digits in HEADLINE_COLUMNS:
            key = f"{COMPARISON_PREFIX}{method}.{column}"
            if key not in metrics:
                cells.append("<td>–</td>")
                continue
            ci = metrics.get(f"{key}.ci95")
            shown = _number(metrics[key], digits) + (f" ± {ci:.2g}" if ci is not None else "")
            cells.append(f"<td>{shown}</td>")
        label = "real (held-out)" if method == "real" else method
        rows.append(f"<tr><th>{html.escape(label)}</th>{''.join(cells)}</tr>")
    return f"<table><tr><th>method</th>{header}</tr>\n" + "\n".join(rows) + "\n</table>"


def _claims_list(claims: Mapping[str, Mapping[str, Any]]) -> str:
    items = []
    for claim_id, claim in sorted(claims.items()):
        verdict, css = claim_verdict(claim)
        label = {"ok": "holds", "gap": "known gap", "bad": "fails"}[css]
        detail = "" if css == "ok" else f" <span class='{css}'>{html.escape(verdict)}</span>"
        items.append(
            f"<li><span class='pill {css}'>{label}</span> <code>{html.escape(claim_id)}</code> "
            f"{html.escape(str(claim.get('text', '')))} "
            f"<span class='muted'>(value {claim.get('value', float('nan')):.4g} "
            f"{html.escape(str(claim.get('op', '')))} {claim.get('threshold', float('nan')):.4g})</span>"
            f"{detail}</li>"
        )
    return (
        f"<ul class='claims'>{''.join(items)}</ul>" if items else "<p class='muted'>No claims recorded.</p>"
    )


def _claims_at_a_glance(results: Mapping[str, Any]) -> str:
    quick = results.get("profile") == "quick"
    counts = {"ok": 0, "gap": 0, "bad": 0}
    notable = []
    for chapter, entry in sorted(results.get("notebooks", {}).items()):
        for claim_id, claim in sorted(entry.get("claims", {}).items()):
            verdict, css = claim_verdict(claim)
            counts[css] += 1
            if css != "ok":
                notable.append(
                    f"<li><span class='pill {css}'>{'known gap' if css == 'gap' else 'fails'}</span> "
                    f"<a href='{html.escape(chapter)}.html'>{html.escape(chapter.split('_', 1)[0])}</a> "
                    f"<code>{html.escape(claim_id)}</code>: {html.escape(str(claim.get('text', '')))} — "
                    f"<span class='{css}'>{html.escape(verdict)}</span></li>"
                )
    total = sum(counts.values())
    summary = (
        f"<p><b>{counts['ok']} of {total}</b> claims hold; "
        f"<span class='gap'>{counts['gap']} known gap(s)</span>; "
        f"<span class='bad'>{counts['bad']} failing</span>."
        + (
            " This is the <b>quick</b> profile: its models are too small to mean anything, so claims are "
            "recorded but not asserted; <code>make course</code> builds the full report."
            if quick
            else ""
        )
        + "</p>"
    )
    return summary + (f"<ul class='claims'>{''.join(notable)}</ul>" if notable else "")


def _status(chapter: ChapterStatus, budget: float | None) -> tuple[str, str]:
    if chapter.error:
        return "failed: " + chapter.error, "bad"
    if chapter.seconds is None:
        return "not run", "gap"
    over = budget is not None and chapter.seconds > budget
    text = "over budget" if over else "within budget"
    if not chapter.current:
        text += " (from an earlier build)"
    text += "".join(f"; executed again after: {retry}" for retry in chapter.retries)
    return text, "bad" if over else "ok"


def _metric_rows(results: Mapping[str, Any]) -> str:
    rows = []
    for chapter, entry in sorted(results.get("notebooks", {}).items()):
        metrics = entry.get("metrics", {})
        for key in sorted(k for k in metrics if not k.endswith(".ci95")):
            ci = metrics.get(f"{key}.ci95")
            shown = f"{metrics[key]:.4g}" + (f" ± {ci:.2g}" if ci is not None else "")
            rows.append(
                f"<tr><td>{html.escape(chapter)}</td><td><code>{html.escape(key)}</code></td><td>{shown}</td></tr>"
            )
    return "\n".join(rows)


def _settings_line(results: dict) -> str:
    """What decided this build's numbers besides the code: the models, the base seed, the numerical path."""
    models = {
        "reference": "the shipped reference models loaded",
        "retrained": "every model trained in this build",
    }.get(str(results.get("models")), "models of unknown origin")
    numerics = results.get("numerics") or {}
    path = ", ".join(f"{k}={v}" for k, v in sorted(numerics.items())) or "the machine's own numerical path"
    trained = (results.get("build") or {}).get("trained_here") or []
    extra = (
        f" Trained in this build, as no reference model has their configuration: {', '.join(trained)}."
        if trained and results.get("models") == "reference"
        else ""
    )
    return html.escape(f"Models: {models}; base training seed {results.get('base_seed', 0)}; {path}.{extra}")


def write_front_page(
    out_dir: Path,
    results: Mapping[str, Any],
    chapters: Sequence[ChapterStatus],
    budgets: Mapping[str, float | None],
) -> Path:
    """Write ``out_dir/index.html`` (and the key figures under ``out_dir/figures``); return its path.

    Args:
        results: the build's ``results.json``.
        chapters: every chapter to show, in course order.
        budgets: each chapter's budget in seconds for the build's profile (None: no budget).
    """
    figures = out_dir / "figures"
    cards = []
    comparison_figure = ""
    total = sum(c.seconds or 0.0 for c in chapters)
    wall = float((results.get("build") or {}).get("wall_seconds", total))
    for chapter in chapters:
        executed = out_dir / f"{chapter.name}.ipynb"
        notebook = nbformat.read(executed, as_version=4) if executed.exists() else None
        title, intro = chapter_intro(notebook) if notebook is not None else ("", "")
        figure = key_figure(notebook) if notebook is not None else None
        image = ""
        if figure is not None:
            figures.mkdir(exist_ok=True)
            (figures / f"{chapter.name}.png").write_bytes(figure)
            source = f"figures/{html.escape(chapter.name)}.png"
            image = f"<img src='{source}' alt='key figure of {html.escape(chapter.name)}'>"
            if chapter.name == COMPARISON_CHAPTER:
                comparison_figure = f"<figure><img src='{source}' alt='accuracy against diversity'></figure>"
        budget = budgets.get(chapter.name)
        status, css = _status(chapter, budget)
        seconds = "–" if chapter.seconds is None else f"{chapter.seconds:.1f} s"
        claims = results.get("notebooks", {}).get(chapter.name, {}).get("claims", {})
        appendix = is_appendix(chapter.name)
        label = f"<span class='muted'>appendix to chapter {notebook_number(chapter.name)[:2]}:</span> "
        link = f"<a href='{html.escape(chapter.name)}.html'>{html.escape(title or chapter.name)}</a>"
        cards.append(
            f"<div class='card{' appendix' if appendix else ''}' id='{html.escape(chapter.name)}'>{image}"
            f"<h3>{label if appendix else ''}{link}</h3>"
            f"<p class='summary'>{_inline_markdown(intro)}</p>"
            f"<p><b>time</b> {seconds}"
            + ("" if budget is None else f" of a {budget:.0f} s budget")
            + f" — <span class='{css}'>{html.escape(status)}</span></p>"
            f"{_claims_list(claims)}</div>"
        )
    comparison = comparison_table(results.get("notebooks", {}).get(COMPARISON_CHAPTER, {}).get("metrics", {}))
    headline = (
        "<h2>The five generators on one benchmark</h2>"
        "<p>Chapter 09's comparison: the same held-out walk and jog clips, one evaluator, the same number of "
        "samples, everything at 30 fps; each method given what its paper conditions on. Means ± 95 % "
        "interval "
        "half-widths over repeated sample sets. <a href='"
        f"{COMPARISON_CHAPTER}.html'>How it was measured, and what each method is given.</a></p>"
        f"{comparison}{comparison_figure}"
        if comparison
        else "<h2>The five generators on one benchmark</h2>"
        "<p class='muted'>Chapter 09 has not run in this build.</p>"
    )
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>motionlab course report</title>
<style>{_STYLE}</style></head><body>
<h1>motionlab: probabilistic human-motion synthesis</h1>
<p class="lead">{html.escape(INTRO)}</p>
<p class="muted">Profile <b>{html.escape(str(results.get("profile", "")))}</b>, Python
{html.escape(str(results.get("python", "")))}, torch {html.escape(str(results.get("torch", "")))}.
{_settings_line(results)}
Course time <span class="{"bad" if wall > COURSE_BUDGET_SECONDS else "ok"}">{wall / 60:.1f} min</span>
(two notebooks at a time; their times add up to {total / 60:.1f} min, appendices included; the whole
course's budget: {COURSE_BUDGET_SECONDS / 60:.0f} min).
Raw numbers: <a href="results.json">results.json</a>.</p>
<h2>Claims at a glance</h2>
<p>Statements from the papers (and a few of ours) checked on our data. A known gap is a claim that does not
hold here after investigation; its chapter explains why.</p>
{_claims_at_a_glance(results)}
{headline}
<h2>Chapters</h2>
{"".join(cards)}
<details><summary><b>Every recorded metric</b></summary>
<table><tr><th>chapter</th><th>metric</th><th>value (± 95% CI half-width)</th></tr>
{_metric_rows(results)}
</table></details>
</body></html>
"""
    index = out_dir / "index.html"
    index.write_text(page, encoding="utf-8")
    return index
