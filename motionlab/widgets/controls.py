"""Controls and outputs that several chapters' widgets share."""

from __future__ import annotations

import io
from collections.abc import Callable, Sequence

import ipywidgets as widgets
import matplotlib.pyplot as plt
from IPython.display import Image
from matplotlib.figure import Figure


def action_dropdown(action_names: Sequence[str], description: str = "action") -> widgets.Dropdown:
    """A dropdown of the actions by name whose value is the action's index (the first chosen)."""
    return widgets.Dropdown(
        options=[(name, i) for i, name in enumerate(action_names)], value=0, description=description
    )


def show_figure(output: widgets.Output, fig: Figure, dpi: int = 72) -> None:
    """Replace what ``output`` shows by ``fig`` as a PNG image, then close ``fig``.

    Setting the output's ``outputs`` (rather than displaying inside ``with output:``) works without a kernel
    too, so a test can drive the controls and read the image that a change produced.
    """
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    plt.close(fig)
    output.outputs = ()
    output.append_display_data(Image(data=buffer.getvalue(), format="png"))


def wire(
    output: widgets.Output, draw: Callable[..., Figure], controls: dict[str, widgets.ValueWidget]
) -> Callable[..., None]:
    """Show ``draw(**values)`` in ``output`` (:func:`show_figure`) now and whenever one of ``controls``
    changes, ``values`` being each control's value under its name; returns the redraw callback (to detach it
    from a control that redraws by other means)."""

    def redraw(_change: object = None) -> None:
        show_figure(output, draw(**{name: control.value for name, control in controls.items()}))

    for control in controls.values():
        control.observe(redraw, names="value")
    redraw()
    return redraw
