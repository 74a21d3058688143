"""The report's pages in a real browser (headless Chromium): formulas typeset, widgets rendered, animations
playing, nothing fetched from the web, no console error. Skipped, with how to enable it, when Chromium is not
installed; the whole course report is checked the same way by `.ci/run` after `make course`."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import nbformat
import pytest

from motionlab.course.assets import install_assets
from motionlab.course.browser import browser_available, check_report
from motionlab.course.kernel import CellLimits, execute_notebook
from motionlab.course.run import export_html

pytestmark = pytest.mark.skipif(
    not browser_available() or shutil.which("npm") is None,
    reason="needs Debian's chromium and chromium-driver (apt-get install chromium chromium-driver) and npm",
)

MARKDOWN = r"""## A page like a chapter's

The ELBO, $\mathcal L = \mathbb E_{q(z \mid x)}[\ln p(x \mid z)] - \mathrm{KL}(q \,\Vert\, p)$, and a display:

$$\lVert \hat q \rVert = \sqrt{\sum_i \hat q_i^2} = 1 .$$
"""

WIDGET = """\
import ipywidgets as widgets
import matplotlib.pyplot as plt
import numpy as np

slider = widgets.FloatSlider(value=1.0, min=0.5, max=2.0, description="frequency")
out = widgets.interactive_output(
    lambda frequency: (plt.plot(np.sin(frequency * np.linspace(0, 6, 50))), plt.show()), {"frequency": slider}
)
display(widgets.VBox([slider, out]))
slider.value = 1.5
"""

ANIMATION = """\
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import HTML
from matplotlib.animation import FuncAnimation

fig, ax = plt.subplots(figsize=(3, 2))
(line,) = ax.plot([], [])
ax.set(xlim=(0, 6), ylim=(-1, 1))
x = np.linspace(0, 6, 50)
animation = FuncAnimation(fig, lambda i: line.set_data(x, np.sin(x + 0.5 * i)), frames=12, interval=100)
plt.close(fig)
HTML(animation.to_jshtml())
"""


def test_a_built_page_works_offline_in_chromium(tmp_path: Path) -> None:
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [
        nbformat.v4.new_markdown_cell(MARKDOWN),
        nbformat.v4.new_code_cell(WIDGET),
        nbformat.v4.new_code_cell(ANIMATION),
    ]
    execution = execute_notebook(notebook, tmp_path, CellLimits(cell_seconds=120))
    assert execution.error is None, execution.error
    assets = install_assets(tmp_path)
    assert {"mathjax_url", "require_js_url", "widget_renderer_url", "font_awesome_css"} <= set(assets)
    page = export_html(execution.notebook, assets)
    assert not re.search(r"""<(script|link)[^>]*(src|href)=["']https?://""", page)  # nothing from the web
    (tmp_path / "page.html").write_text(page, encoding="utf-8")

    (report,) = check_report(tmp_path)
    assert report.problems == []
    assert report.state["typeset"] >= 2  # the inline formula and the display
    assert report.state["views"] >= 1 and report.state["emptyViews"] == 0
    assert report.animation_checked
