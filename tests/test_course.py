"""The course build executes chapters and their appendices, records their time, and writes the report."""

import json

import nbformat
import pytest

from motionlab import config
from motionlab.course import run as course
from motionlab.course.chapters import is_appendix, notebook_number


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


def test_the_command_builds_the_chosen_chapters_with_their_appendices_and_fails_when_one_fails(
    tmp_path, build, monkeypatch
):
    """One build, two notebooks at a time: chapter 01 with its appendix after it, a chapter that fails
    beside them, one left out."""
    monkeypatch.setenv("MOTIONLAB_PARALLEL", "2")
    _notebook(tmp_path, "03_later", "raise RuntimeError('--only 01 02 must not run chapter 03')")
    _notebook(
        tmp_path,
        "01a_ok_appendix",
        "from motionlab.course.results import Chapter\n"
        "c = Chapter('01a_ok_appendix')\nc.metric('x.audit', 4.0)\n"
        "c.claim('01a.audited', 4.0, 5.0, '<', 'the audit passes')\nprint('appendix ran')",
    )
    _notebook(
        tmp_path,
        "01_ok",
        "from motionlab.course.results import Chapter\n"
        "c = Chapter('01_ok')\nc.metric('x.value', 2.5)\n"
        "c.claim('01.small', 2.5, 3.0, '<', 'value is small')\nprint('chapter ran')",
    )
    _notebook(tmp_path, "02_broken", "raise RuntimeError('boom')")
    assert course.main(["--notebooks", str(tmp_path / "notebooks"), "--only", "01", "02"]) == 1
    out = build / "course-quick"
    notebooks = json.loads((out / "results.json").read_text())["notebooks"]
    assert sorted(notebooks) == ["01_ok", "01a_ok_appendix", "02_broken"]
    assert notebooks["01_ok"]["metrics"] == {"x.value": 2.5} and notebooks["01_ok"]["seconds"] > 0
    appendix = notebooks["01a_ok_appendix"]
    assert appendix["metrics"] == {"x.audit": 4.0} and appendix["claims"]["01a.audited"]["holds"]
    assert appendix["seconds"] > 0
    assert "chapter ran" in (out / "01_ok.html").read_text()
    assert "appendix ran" in (out / "01a_ok_appendix.html").read_text()
    index = (out / "index.html").read_text()
    chapter, after = index.index("id='01_ok'"), index.index("id='01a_ok_appendix'")
    assert chapter < after and "class='card appendix'" in index[after - 40 : after]
    assert "appendix to chapter 01" in index and "01.small" in index and "01a.audited" in index
    assert index.count("failed: ") == 1 and "boom" in index and "03_later" not in index


def test_missing_chapters_are_reported(tmp_path):
    with pytest.raises(FileNotFoundError, match="no chapters"):
        course.chapter_notebooks(tmp_path)


def test_only_selects_a_chapter_with_its_appendices_or_an_appendix_alone(tmp_path):
    for name in ("04_cell", "04a_cell_appendix", "04b_cell_primer", "05_flow", "10_real"):
        _notebook(tmp_path, name, "pass")
    notebooks = tmp_path / "notebooks"
    names = [p.stem for p in course.select_chapters(notebooks)]
    assert names == ["04_cell", "04a_cell_appendix", "04b_cell_primer", "05_flow", "10_real"]
    assert [p.stem for p in course.select_chapters(notebooks, ["04"])] == names[:3]
    assert [p.stem for p in course.select_chapters(notebooks, ["04a", "05"])] == names[1:2] + names[3:4]
    with pytest.raises(ValueError, match="no chapter 05a"):
        course.select_chapters(notebooks, ["05a"])
    with pytest.raises(ValueError, match="appendix numbers such as 04a"):
        course.select_chapters(notebooks, ["4a"])


def test_notebook_numbers_and_budgets(monkeypatch):
    assert notebook_number("04_motion_cell") == "04" and notebook_number("04a_motion_cell_appendix") == "04a"
    assert is_appendix("04a_motion_cell_appendix") and not is_appendix("04_motion_cell")
    for bad in ("motion_cell", "4a_x", "04A_x", "04ab_x", "04a"):
        with pytest.raises(ValueError, match="NN_ or NNa_"):
            notebook_number(bad)
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    assert course.budget_seconds("04_motion_cell") == course.BUDGETS["04"][0]
    assert course.budget_seconds("99a_unlisted_appendix") == course.APPENDIX_BUDGET[0]
    assert course.budget_seconds("99_new") is None
    monkeypatch.setitem(course.BUDGETS, "04a", (300.0, 50.0))
    assert course.budget_seconds("04a_motion_cell_appendix") == 300.0
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    assert config.is_quick() and course.budget_seconds("04a_motion_cell_appendix") == 50.0


def test_appendices_without_a_chapter_are_no_course(tmp_path):
    _notebook(tmp_path, "04a_orphan_appendix", "pass")
    with pytest.raises(FileNotFoundError, match="no chapters"):
        course.chapter_notebooks(tmp_path / "notebooks")


def test_the_longest_chain_starts_first(tmp_path, monkeypatch) -> None:
    """A chapter ranks by its time plus its appendices' (they run after it), an appendix by its own: the
    chapter that ends the longest chain starts first, and its appendix before shorter notebooks."""
    seconds = {"04_mc": 60, "04a_mc_appendix": 80, "10_real": 95, "11_mdm": 90, "11a_mdm_appendix": 85}
    monkeypatch.setattr(
        course, "load_results", lambda: {"notebooks": {name: {"seconds": s} for name, s in seconds.items()}}
    )
    paths = [tmp_path / f"{name}.ipynb" for name in seconds]
    order = [path.stem for path in course.longest_first(paths)]
    assert order == ["11_mdm", "04_mc", "10_real", "11a_mdm_appendix", "04a_mc_appendix"]


def test_two_at_a_time_the_longest_first_and_an_appendix_after_its_chapter(tmp_path, monkeypatch) -> None:
    """:func:`execute_all` with two workers: every notebook runs once, never more than two at once, and an
    appendix starts only after its chapter has finished."""
    import threading
    import time as clock

    from motionlab.course.run import ChapterRun, execute_all

    names = ["01_a", "01a_a_appendix", "02_b", "03_c", "03a_c_appendix"]
    paths = [tmp_path / f"{name}.ipynb" for name in names]
    started, finished, active, most = {}, {}, [0], [0]
    lock = threading.Lock()

    def execute(path):
        with lock:
            started[path.stem] = clock.perf_counter()
            active[0] += 1
            most[0] = max(most[0], active[0])
        clock.sleep(0.05)
        with lock:
            active[0] -= 1
            finished[path.stem] = clock.perf_counter()
        return ChapterRun(path.stem, 0.05, None, ())

    done = execute_all(paths, execute, workers=2)
    assert sorted(done) == sorted(names) and most[0] == 2
    assert started["01a_a_appendix"] >= finished["01_a"] and started["03a_c_appendix"] >= finished["03_c"]
