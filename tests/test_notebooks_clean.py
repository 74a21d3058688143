"""Committed notebooks carry no outputs and no execution counts (the design notes' "Conventions"): what a
reader sees is what the chapter prints when run, never a stale copy of an earlier run. The one exception is a
cell marked ``# NBVAL_CHECK_OUTPUT``, whose small, deterministic output nbval compares."""

from __future__ import annotations

import json

import nbformat
import pytest

from motionlab.paths import REPO_ROOT

NOTEBOOKS = sorted((REPO_ROOT / "notebooks").glob("*.ipynb"))
CHECKED_OUTPUT = "# NBVAL_CHECK_OUTPUT"


def committed_outputs(notebook: dict, name: str) -> list[str]:
    """One line per code cell of ``notebook`` (its JSON) that holds outputs or an execution count, naming
    the notebook ``name``, the cell's index and id; cells marked ``# NBVAL_CHECK_OUTPUT`` may keep both."""
    found = []
    for index, cell in enumerate(notebook["cells"]):
        if cell["cell_type"] != "code" or CHECKED_OUTPUT in "".join(cell["source"]):
            continue
        outputs, count = cell.get("outputs", []), cell.get("execution_count")
        if outputs or count is not None:
            found.append(
                f"{name} cell {index} (id {cell.get('id')}): {len(outputs)} outputs, execution_count {count}"
            )
    return found


def test_the_notebooks_are_found() -> None:
    assert len(NOTEBOOKS) >= 10, [p.name for p in NOTEBOOKS]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_committed_notebook_has_no_outputs(path) -> None:
    found = committed_outputs(json.loads(path.read_text()), path.name)
    assert not found, "strip the outputs (outputs: [], execution_count: null) of:\n" + "\n".join(found)


def test_a_stale_output_is_named_and_a_checked_cell_is_allowed() -> None:
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_markdown_cell("# title"),
        nbformat.v4.new_code_cell("x = 1", execution_count=3),
        nbformat.v4.new_code_cell(
            "print(2)", outputs=[nbformat.v4.new_output("stream", name="stdout", text="2\n")]
        ),
        nbformat.v4.new_code_cell(
            f"{CHECKED_OUTPUT}\nprint(3)",
            execution_count=5,
            outputs=[nbformat.v4.new_output("stream", name="stdout", text="3\n")],
        ),
        nbformat.v4.new_code_cell("y = 2"),
    ]
    found = committed_outputs(json.loads(nbformat.writes(nb)), "99_example.ipynb")
    assert len(found) == 2
    assert found[0].startswith("99_example.ipynb cell 1 (id ") and found[0].endswith(
        "0 outputs, execution_count 3"
    )
    assert found[1].startswith("99_example.ipynb cell 2 (id ") and found[1].endswith(
        "1 outputs, execution_count None"
    )
