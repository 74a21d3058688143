"""The course's notebooks: chapters ``NN_<topic>.ipynb`` and their appendices ``NNa_<topic>_appendix.ipynb``.

An appendix holds what its chapter's story does not need (audits, ablations, extra measurements, primers) and
is built, reported and tested like a chapter: executed right after it, with its own budget, page, results
(``Chapter("04a_motion_cell_appendix")``) and card on the report's front page.
"""

from __future__ import annotations

import re
from pathlib import Path

#: A notebook's number: two digits for a chapter, then one lower-case letter for an appendix of it.
NUMBER = re.compile(r"\d\d[a-z]?")


def notebook_number(name: str) -> str:
    """The number of the notebook with stem ``name``: ``"04"`` for ``04_motion_cell``, ``"04a"`` for its
    appendix ``04a_motion_cell_appendix``. Raises ``ValueError`` for a stem that does not start with one."""
    number = name.split("_", 1)[0]
    if "_" not in name or not NUMBER.fullmatch(number):
        raise ValueError(f"a notebook's name starts with NN_ or NNa_ (e.g. 04_, 04a_), got {name!r}")
    return number


def is_appendix(name: str) -> bool:
    """Whether the notebook with stem ``name`` is an appendix (``NNa_*``) rather than a chapter (``NN_*``)."""
    return len(notebook_number(name)) == 3


def numbered_notebooks(directory: Path) -> list[Path]:
    """The chapters ``NN_*.ipynb`` and appendices ``NNa_*.ipynb`` in ``directory`` (possibly none), in course
    order: each chapter followed by its appendices (04, 04a, 05, ...)."""
    found = [
        p
        for pattern in ("[0-9][0-9]_*.ipynb", "[0-9][0-9][a-z]_*.ipynb")
        for p in directory.glob(pattern)
        if p.is_file()
    ]
    return sorted(found, key=lambda p: (notebook_number(p.stem), p.name))
