"""Showing the package's own code in a notebook: the code that runs, never a copy of it."""

from __future__ import annotations

import inspect
from typing import Any


def show_source(obj: Any) -> None:
    """Display the source of a package function, class or method as highlighted Python in the notebook."""
    from IPython.display import Code, display

    display(Code(inspect.getsource(obj), language="python"))
