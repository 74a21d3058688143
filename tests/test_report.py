"""The front page: comparison table from chapter 09's metrics, chapter cards with key figures, claims in plain
sight, nothing fetched from the web."""

import base64
import re

import nbformat

from motionlab.course.report import (
    ChapterStatus,
    chapter_intro,
    comparison_table,
    key_figure,
    write_front_page,
)

PNG = base64.b64encode(
    bytes.fromhex(
        "89504e470d0a1a0a0000000d4948445200000001000000010806000000"
        "1f15c4890000000d49444154789c63f8ffff3f0005fe02fea7d6a1a50000000049454e44ae426082"
    )
).decode()


def _executed(path, title, tagged):
    nb = nbformat.v4.new_notebook()
    first = nbformat.v4.new_code_cell("plt.plot()")
    first.outputs = [nbformat.v4.new_output("display_data", data={"image/png": PNG, "text/plain": "first"})]
    key = nbformat.v4.new_code_cell("scatter()")
    key.outputs = [nbformat.v4.new_output("display_data", data={"image/png": PNG, "text/plain": "key"})]
    if tagged:
        key.metadata["tags"] = ["key-figure"]
    nb.cells = [
        nbformat.v4.new_markdown_cell(f"# {title}\n\nThe **idea** of $q(z\\mid x)$.\n\nMore."),
        first,
        key,
    ]
    nbformat.write(nb, path)
    return nb


RESULTS = {
    "profile": "full",
    "python": "3.11",
    "torch": "2",
    "notebooks": {
        "01_intro": {
            "seconds": 10.0,
            "metrics": {"x": 1.0},
            "claims": {"01.good": {"holds": True, "value": 1, "threshold": 2, "op": "<", "text": "small"}},
        },
        "09_evaluating_and_comparing": {
            "seconds": 50.0,
            "metrics": {
                "common.ODMO.fid": 3.0,
                "common.ODMO.fid.ci95": 0.5,
                "common.real.fid": 0.1,
                "common.Motion Cell.fid": 2.0,
                "common.Motion Cell.parameters": 28166.0,
            },
            "claims": {
                "09.gap": {
                    "holds": False,
                    "expected": False,
                    "why": "too few clips",
                    "value": 3,
                    "threshold": 2,
                    "op": "<",
                    "text": "gap claim",
                }
            },
        },
    },
}


def test_comparison_table_orders_methods_and_shows_intervals():
    table = comparison_table(RESULTS["notebooks"]["09_evaluating_and_comparing"]["metrics"])
    assert table.index("real (held-out)") < table.index("Motion Cell") < table.index("ODMO")
    assert "3 ± 0.5" in table and "28,166" in table
    assert comparison_table({"x": 1.0}) == ""


def test_intro_and_key_figure(tmp_path):
    nb = _executed(tmp_path / "a.ipynb", "01 · Intro", tagged=True)
    title, paragraph = chapter_intro(nb)
    assert title == "01 · Intro" and paragraph.startswith("The **idea**") and "More" not in paragraph
    assert key_figure(nb) == base64.b64decode(PNG)
    nb.cells = nb.cells[:1]
    assert key_figure(nb) is None


def test_front_page(tmp_path):
    _executed(tmp_path / "01_intro.ipynb", "01 · Intro", tagged=False)
    _executed(tmp_path / "09_evaluating_and_comparing.ipynb", "09 · Evaluating", tagged=True)
    chapters = [
        ChapterStatus("01_intro", 10.0, current=False),
        ChapterStatus("09_evaluating_and_comparing", 250.0),
    ]
    index = write_front_page(
        tmp_path, RESULTS, chapters, {"01_intro": 30.0, "09_evaluating_and_comparing": 180.0}
    )
    page = index.read_text()
    assert (tmp_path / "figures" / "09_evaluating_and_comparing.png").exists()
    assert "figures/01_intro.png" in page and "<b>idea</b>" in page and "<i>q(z" in page
    assert "1 of 2</b> claims hold" in page and "known gap: too few clips" in page
    assert "over budget" in page and "from an earlier build" in page
    assert "The five generators on one benchmark" in page and "accuracy against diversity" in page
    assert "<details>" in page and "common.ODMO.fid" in page
    assert not re.search(r"""(src|href)=["']https?://""", page)


def test_the_front_page_names_the_models_a_reference_build_trained_itself(tmp_path):
    _executed(tmp_path / "01_intro.ipynb", "01 · Intro", tagged=False)
    results = {**RESULTS, "models": "reference", "build": {"trained_here": ["fixed_length_glow", "moglow"]}}
    page = write_front_page(
        tmp_path, results, [ChapterStatus("01_intro", 10.0)], {"01_intro": 30.0}
    ).read_text()
    assert "the shipped reference models loaded" in page
    assert "as no reference model has their configuration: fixed_length_glow, moglow." in page
    quiet = {**RESULTS, "models": "reference", "build": {"trained_here": []}}
    page = write_front_page(
        tmp_path, quiet, [ChapterStatus("01_intro", 10.0)], {"01_intro": 30.0}
    ).read_text()
    assert "no reference model has" not in page
