"""How long the course's notebooks are: cells, words of prose, lines of the first code cell.

A chapter (``NN_*``) keeps to :data:`MAX_CELLS` cells, :data:`MAX_WORDS` words of prose and a first code
cell of at most :data:`MAX_FIRST_CODE_LINES` lines; what its story does not need goes to its appendix
(``NNa_*``, :mod:`motionlab.course.chapters`), which has no such limits. The counts, precisely:

- *cells*: every cell of the notebook, Markdown and code;
- *words*: the words of the Markdown cells' prose, as a reader counts them: LaTeX (``$...$``, ``$$...$$``),
  code (fenced blocks and ``inline spans``), HTML tags, link targets and image references are left out;
  a word is a run of non-blank characters holding at least one letter or digit (so a table's ``|`` and
  ``---`` count for nothing);
- *first code cell lines*: the non-blank lines of the first code cell's source.

Command line (the table for every chapter and appendix, Markdown, for closing notes)::

    python -m motionlab.course.stats [--notebooks DIR]
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from motionlab import arguments, config
from motionlab.course.chapters import is_appendix, numbered_notebooks

#: The limits of a main chapter (an appendix has none).
MAX_CELLS = 40
MAX_WORDS = 3500
MAX_FIRST_CODE_LINES = 12

#: What :func:`prose_words` leaves out, removed in this order (display math before inline math, fenced code
#: before inline code).
_NOT_PROSE = tuple(
    re.compile(pattern, re.S)
    for pattern in (
        r"```.*?```",  # fenced code
        r"\$\$.*?\$\$",  # display math
        r"\\begin\{(\w+\*?)\}.*?\\end\{\1\}",  # a LaTeX environment outside dollars
        r"(?<!\\)\$.+?(?<!\\)\$",  # inline math
        r"`[^`]*`",  # inline code
        r"<[^>\n]+>",  # HTML tags
        r"!\[[^\]]*\]\([^)]*\)",  # images
        r"\]\([^)]*\)",  # link targets (the link's text stays)
    )
)
_WORD = re.compile(r"\S*[^\W_]\S*")


def prose_words(markdown: str) -> int:
    """The number of words of prose in ``markdown`` (see the module notes for what is left out)."""
    if not isinstance(markdown, str):
        raise TypeError(f"prose_words: expected the Markdown text, got {type(markdown).__name__}")
    for pattern in _NOT_PROSE:
        markdown = pattern.sub(" ", markdown)
    return len(_WORD.findall(markdown))


@dataclass(frozen=True)
class NotebookStats:
    """The length of one notebook (its stem ``name``)."""

    name: str
    cells: int
    words: int
    #: Non-blank lines of the first code cell (0 when it has none).
    first_code_lines: int

    @property
    def appendix(self) -> bool:
        return is_appendix(self.name)

    def over(self) -> list[str]:
        """The limits a chapter exceeds, one phrase each (none for an appendix)."""
        if self.appendix:
            return []
        measured = (
            (self.cells, MAX_CELLS, "cells"),
            (self.words, MAX_WORDS, "words of prose"),
            (self.first_code_lines, MAX_FIRST_CODE_LINES, "lines in the first code cell"),
        )
        return [f"{value} {what} (at most {limit})" for value, limit, what in measured if value > limit]


def notebook_stats(path: Path) -> NotebookStats:
    """The :class:`NotebookStats` of the notebook file ``path``."""
    cells = json.loads(Path(path).read_text(encoding="utf-8"))["cells"]
    sources = [("".join(c["source"]) if isinstance(c["source"], list) else c["source"]) for c in cells]
    code = [s for c, s in zip(cells, sources) if c["cell_type"] == "code"]
    return NotebookStats(
        name=Path(path).stem,
        cells=len(cells),
        words=sum(prose_words(s) for c, s in zip(cells, sources) if c["cell_type"] == "markdown"),
        first_code_lines=sum(1 for line in code[0].splitlines() if line.strip()) if code else 0,
    )


def stats_table(paths: list[Path]) -> str:
    """A Markdown table of the notebooks' :class:`NotebookStats`, with each chapter's limits exceeded."""
    rows = [
        f"| notebook | cells (≤ {MAX_CELLS}) | words (≤ {MAX_WORDS}) | "
        f"first code cell lines (≤ {MAX_FIRST_CODE_LINES}) | over |",
        "|---|---:|---:|---:|---|",
    ]
    for path in paths:
        s = notebook_stats(path)
        verdict = "appendix: no limits" if s.appendix else ("; ".join(s.over()) or "within all")
        rows.append(f"| {s.name} | {s.cells} | {s.words} | {s.first_code_lines} | {verdict} |")
    return "\n".join(rows)


def _print_table(directory: Path) -> int:
    print(stats_table(numbered_notebooks(directory)))
    return 0


def main(argv: list[str] | None = None) -> int:
    """The command line: print the table of every chapter and appendix."""
    prog = "python -m motionlab.course.stats"
    parser = argparse.ArgumentParser(prog=prog, description="The length of every chapter and appendix.")
    parser.add_argument(
        "--notebooks",
        type=arguments.existing_directory,
        default=config.REPO_ROOT / "notebooks",
        help="directory of the chapters NN_name.ipynb and appendices NNa_name.ipynb (default: the course's)",
    )
    args = parser.parse_args(argv)
    return arguments.run(prog, lambda: _print_table(args.notebooks))


if __name__ == "__main__":
    sys.exit(main())
