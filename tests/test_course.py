"""The course build executes chapters, records their time, and writes the report."""

import json

import nbformat
import pytest

from motionlab.course import run as course


def _notebook(tmp_path, name, source):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(source)]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    path = tmp_path / "notebooks" / f"{name}.ipynb"
    path.parent.mkdir(exist_ok=True)
    nbformat.write(nb, path)
    return path


@pytest.fixture
def build(monkeypatch, tmp_path):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path / "build"))
    return tmp_path / "build"


def test_build_runs_chapters_and_writes_report(tmp_path, build):
    _notebook(
        tmp_path,
        "01_ok",
        "from motionlab.course.results import Chapter\n"
        "c = Chapter('01_ok')\nc.metric('x.value', 2.5)\n"
        "c.claim('01.small', 2.5, 3.0, '<', 'value is small')\nprint('done')",
    )
    _notebook(tmp_path, "02_broken", "raise RuntimeError('boom')")
    runs = course.build(tmp_path / "notebooks")
    assert [r.name for r in runs] == ["01_ok", "02_broken"]
    assert runs[0].error is None and "boom" in runs[1].error
    out = build / "course-quick"
    results = json.loads((out / "results.json").read_text())
    assert results["notebooks"]["01_ok"]["metrics"] == {"x.value": 2.5}
    assert results["notebooks"]["01_ok"]["seconds"] > 0
    index = (out / "index.html").read_text()
    assert "01_ok.html" in index and "01.small" in index and "failed" in index
    assert "done" in (out / "01_ok.html").read_text()


def test_main_exits_non_zero_when_a_chapter_fails(tmp_path, build):
    _notebook(tmp_path, "01_broken", "1/0")
    assert course.main(["--notebooks", str(tmp_path / "notebooks")]) == 1


def test_missing_chapters_are_reported(tmp_path):
    with pytest.raises(FileNotFoundError, match="no chapters"):
        course.chapter_notebooks(tmp_path)
