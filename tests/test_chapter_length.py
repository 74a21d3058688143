"""Short chapters: each restructured chapter keeps to the limits of :mod:`motionlab.course.stats` (at most 40
cells, 3,500 words of prose, a first code cell of 12 lines); what its story does not need lives in its
appendix. Chapters are restructured one at a time: ``RESTRUCTURED`` lists those done, and a chapter that
keeps to the limits must be listed so that it stays within them."""

from __future__ import annotations

import nbformat
import pytest

from motionlab.course import stats
from motionlab.course.chapters import is_appendix, notebook_number, numbered_notebooks
from motionlab.paths import REPO_ROOT

NOTEBOOKS = REPO_ROOT / "notebooks"

#: The chapters (two-digit numbers) written or restructured as a short chapter and its appendix. A listed
#: chapter whose notebook is missing fails the test.
RESTRUCTURED: tuple[str, ...] = ("01", "02", "03", "04", "05", "06", "07", "08", "09", "10", "11")


def _chapters() -> dict[str, object]:
    """{number: path} of the course's chapters (not their appendices)."""
    return {notebook_number(p.stem): p for p in numbered_notebooks(NOTEBOOKS) if not is_appendix(p.stem)}


def test_restructured_chapters_keep_to_the_limits() -> None:
    chapters = _chapters()
    missing = [number for number in RESTRUCTURED if number not in chapters]
    assert not missing, f"RESTRUCTURED lists chapters with no notebook NN_*.ipynb in notebooks/: {missing}"
    over = {number: stats.notebook_stats(chapters[number]).over() for number in RESTRUCTURED}
    assert not any(over.values()), {number: problems for number, problems in over.items() if problems}


def test_a_chapter_within_the_limits_is_declared_restructured() -> None:
    within = [n for n, path in _chapters().items() if not stats.notebook_stats(path).over()]
    undeclared = sorted(set(within) - set(RESTRUCTURED))
    assert not undeclared, f"chapters {undeclared} keep to the limits: add them to RESTRUCTURED"


def test_prose_words_leave_out_math_code_markup_and_link_targets() -> None:
    text = (
        "# The KL weight\n\nWe weigh it by $\\beta$ in `loss_fn`, see [the paper](https://x.org/a b).\n\n"
        "$$\\mathcal{L} = \\beta\\,\\mathrm{KL}$$\n\n```python\nx = 1\n```\n\n"
        "| a | b |\n|---|---|\n| it's | 3.5 |\n\n<img src='x.png'> ![figure](f.png) α\n"
    )
    words = "# The KL weight We weigh it by in , see [the paper . a b it's 3.5 α".split()
    assert stats.prose_words(text) == sum(any(ch.isalnum() for ch in w) for w in words) == 16
    assert stats.prose_words("") == 0
    with pytest.raises(TypeError, match="Markdown text"):
        stats.prose_words(["a list"])


def _write(tmp_path, name: str, cells: list) -> object:
    nb = nbformat.v4.new_notebook()
    nb.cells = cells
    path = tmp_path / f"{name}.ipynb"
    nbformat.write(nb, path)
    return path


def test_a_notebook_is_measured_and_only_a_chapter_has_limits(tmp_path, monkeypatch) -> None:
    first = "import torch\n\n" + "\n".join(f"x{i} = {i}" for i in range(12))
    cells = [nbformat.v4.new_markdown_cell("# Title\n\nOne two $x$ three.")]
    cells += [nbformat.v4.new_code_cell(first)] + [nbformat.v4.new_code_cell("pass") for _ in range(39)]
    chapter = stats.notebook_stats(_write(tmp_path, "04_long", cells))
    assert (chapter.cells, chapter.words, chapter.first_code_lines) == (41, 4, 13)
    assert chapter.over() == ["41 cells (at most 40)", "13 lines in the first code cell (at most 12)"]
    appendix = stats.notebook_stats(_write(tmp_path, "04a_long_appendix", cells))
    assert appendix.appendix and appendix.over() == []
    monkeypatch.setattr(stats, "MAX_WORDS", 3)
    assert chapter.over()[1] == "4 words of prose (at most 3)"
    table = stats.stats_table([tmp_path / "04_long.ipynb", tmp_path / "04a_long_appendix.ipynb"])
    assert (
        "| 04_long | 41 | 4 | 13 | 41 cells" in table
        and "| 04a_long_appendix | 41 | 4 | 13 | appendix" in table
    )


def test_the_command_prints_every_chapter_and_appendix(tmp_path, capsys) -> None:
    _write(tmp_path, "01_short", [nbformat.v4.new_markdown_cell("# One\n\nShort.")])
    _write(tmp_path, "01a_short_appendix", [nbformat.v4.new_code_cell("a = 1\nb = 2")])
    assert stats.main(["--notebooks", str(tmp_path)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[2:] == [
        "| 01_short | 1 | 2 | 0 | within all |",
        "| 01a_short_appendix | 1 | 0 | 2 | appendix: no limits |",
    ]
    with pytest.raises(SystemExit):
        stats.main(["--notebooks", str(tmp_path / "nowhere")])
