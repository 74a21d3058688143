"""The widgets in a live JupyterLab, driven by headless Chromium: a notebook that builds chapter 11's sample
widget the way the chapter does (its model from the build's cache, the quick profile) runs, then one slider is
moved with the keyboard, and the widget's figure must change, with no error output anywhere. Skipped, with
how to enable it, when Chromium is not installed. The server is stopped at the end, whatever happens.

Nothing here follows the focus: the notebook is found among the main area's widgets by its path (not as
JupyterLab's current widget, which is whatever had the focus last) and run through its own id. Each wait has
a limit of minutes, though a run here takes seconds, so a slow machine that is busy too passes; a wait that
runs out says what it waited for and what it saw last (the notebook's state, the main area's widgets, the
console's errors, the end of the server's log)."""

from __future__ import annotations

import json
import os
import secrets
import socket
import subprocess
import sys
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import nbformat
import pytest

from motionlab.course.browser import browser_available, chromium, console_errors, poll

pytestmark = pytest.mark.skipif(
    not browser_available(),
    reason="needs Debian's chromium and chromium-driver (apt-get install chromium chromium-driver)",
)

#: The notebook driven: chapter 11's sample widget, built as in the chapter, and the label of the slider
#: moved in it. Every widget of chapters 08 and 11 draws through the same
#: ``motionlab.widgets.controls.wire``, nbval builds each of them in its chapter, and the unit tests move a
#: slider of each without a browser; what only a live JupyterLab shows (the widgets' comms, a key press on a
#: slider reaching the kernel, the new image reaching the page) one slider shows as well as every one. The
#: conftest runs this module on the worker that ran chapter 11 under nbval, right after it, so the chapter's
#: models are in the build's cache.
WIDGET_CELLS = (
    "%matplotlib inline\n"
    "from IPython.display import display\n\n"
    "from motionlab import config\n"
    "from motionlab.evaluation.benchmark import load_benchmark\n"
    "from motionlab.models.diffusion.experiment import ExperimentConfig, load_data, train_all\n"
    "from motionlab.widgets import diffusion as diffusion_widgets\n\n"
    "config.setup(seed=0)\n"
    "cfg = ExperimentConfig.current()\n"
    "data = load_data(cfg)\n"
    "mdm = train_all(cfg, data)['mdm'].model\n"
    "action_names = list(load_benchmark().train.action_names)",
    "display(diffusion_widgets.sample_widget(mdm, action_names, fps=data.fps / cfg.frame_stride))",
)
SLIDERS = (("sample_widget(", "seed"),)
#: Seconds for JupyterLab to answer, for the notebook to open with an idle kernel, and for a slider's new
#: figure: each takes seconds here.
WAIT_SECONDS = 300
#: Seconds for the notebook to run in the quick profile (seconds; longer if chapter 11's model must train).
RUN_SECONDS = 900

#: The state of the notebook at ``arguments[0]`` (its path under the server's root), found among the main
#: area's widgets; ``main`` lists them all, so a wait that runs out shows what was open instead.
_NOTEBOOK_STATE = """
const app = window.jupyterapp;
if (!app) { return {found: false, main: [], note: 'window.jupyterapp is not defined yet'}; }
const main = Array.from(app.shell.widgets('main'));
const seen = main.map(w => (w.context ? w.context.path : w.title.label) || w.id);
const panel = main.find(w => w.context && w.context.path === arguments[0] && w.content && w.sessionContext);
if (!panel) { return {found: false, main: seen}; }
const session = panel.sessionContext.session;
const kernel = session && session.kernel;
const cells = panel.content.widgets.filter(c => c.model.type === 'code');
const errors = [];
cells.forEach((cell, i) => {
  cell.model.outputs.toJSON().forEach(o => {
    if (o.output_type === 'error') { errors.push(`cell ${i}: ${o.ename}: ${o.evalue}`); }
  });
});
return {found: true, id: panel.id, main: seen, loaded: panel.context.isReady,
        kernel: kernel ? kernel.status : 'none', cells: cells.length,
        executed: cells.filter(c => c.model.executionCount !== null).length,
        running: cells.filter(c => c.model.executionState === 'running').length,
        errors: errors};
"""


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _server_state(url: str, server: subprocess.Popen) -> str:
    """``answers`` when ``url`` replies 200, ``exited with N`` when the server has ended, else the error."""
    if server.poll() is not None:
        return f"exited with {server.returncode}"
    try:
        with urllib.request.urlopen(url, timeout=5) as reply:
            return "answers" if reply.status == 200 else f"HTTP {reply.status}"
    except OSError as error:
        return f"no answer ({error})"


def _log_tail(log: Path, lines: int = 15) -> str:
    return "\n".join(log.read_text(errors="replace").splitlines()[-lines:])


def _wait_for_notebook(driver, path: str, log: Path, done, seconds: float, what: str) -> dict:
    """Poll the state of the notebook at ``path`` until ``done`` holds for it; past ``seconds``, fail saying
    what was seen."""
    state = poll(lambda: driver.execute_script(_NOTEBOOK_STATE, path), done, seconds)
    assert done(state), (
        f"waited {seconds:.0f} s for {what}; the notebook's state last: {json.dumps(state)}; "
        f"console errors: {console_errors(driver)}; the end of JupyterLab's log:\n{_log_tail(log)}"
    )
    return state


def _widget_output(driver, panel_id: str, source_snippet: str):
    """The rendered output element of the code cell whose source contains ``source_snippet``, in the notebook
    panel ``panel_id``."""
    from selenium.webdriver.common.by import By

    for cell in driver.find_element(By.ID, panel_id).find_elements(By.CSS_SELECTOR, ".jp-CodeCell"):
        if source_snippet in cell.find_element(By.CSS_SELECTOR, ".jp-InputArea").text:
            return cell.find_element(By.CSS_SELECTOR, ".jp-OutputArea")
    raise AssertionError(f"no cell with {source_snippet!r}")


def _slider(output, description: str) -> dict | None:
    """The slider labelled ``description`` in a widget's ``output``: its handle, its readout and a screenshot
    of the widget's figure; None while either is not rendered (or is being rendered again)."""
    from selenium.common.exceptions import StaleElementReferenceException
    from selenium.webdriver.common.by import By

    try:
        sliders = [
            s
            for s in output.find_elements(By.CSS_SELECTOR, ".widget-slider")
            if s.find_element(By.CSS_SELECTOR, "label").text.strip() == description
        ]
        figure = output.find_elements(By.CSS_SELECTOR, ".widget-output img")
        if not sliders or not figure:
            return None
        return {
            "handle": sliders[0].find_element(By.CSS_SELECTOR, ".noUi-handle"),
            "readout": sliders[0].find_element(By.CSS_SELECTOR, ".widget-readout").text,
            "figure": figure[0].screenshot_as_png,
        }
    except StaleElementReferenceException:
        return None


def _moved(before: dict, now: dict | None) -> bool:
    """Whether the slider's readout and the widget's figure both differ from ``before``."""
    return now is not None and now["readout"] != before["readout"] and now["figure"] != before["figure"]


def _seen(before: dict, now: dict | None) -> str:
    """What :func:`_slider` saw last, in words, for a wait that ran out."""
    if now is None:
        return "no slider or no figure"
    figure = "changed" if now["figure"] != before["figure"] else "unchanged"
    return f"the readout {now['readout']}, the figure {figure}"


@dataclass
class Lab:
    """A running JupyterLab server and a headless Chromium: what the test drives."""

    base: str
    token: str
    driver: Any
    log: Path


def test_a_widget_responds_in_a_live_jupyterlab(tmp_path: Path) -> None:
    root = tmp_path / "root"
    root.mkdir()
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(cell) for cell in WIDGET_CELLS])
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nbformat.write(notebook, root / "widgets.ipynb")
    with serve(tmp_path, root) as (base, token, log), chromium() as driver:
        drive_notebook(Lab(base, token, driver, log), "widgets.ipynb", SLIDERS)


@contextmanager
def serve(tmp_path: Path, root: Path) -> Iterator[tuple[str, str, Path]]:
    """JupyterLab serving ``root`` in the quick profile, without autosave (a notebook stays as it was
    written); yields its address, token and log once it answers, and stops it at the end."""
    port, token = _free_port(), secrets.token_hex(16)
    config = tmp_path / "config"
    settings = config / "lab" / "user-settings" / "@jupyterlab" / "docmanager-extension"
    settings.mkdir(parents=True)
    (settings / "plugin.jupyterlab-settings").write_text(json.dumps({"autosave": False}))
    environment = {**os.environ, "MOTIONLAB_PROFILE": "quick", "JUPYTER_CONFIG_DIR": str(config)}
    log = tmp_path / "jupyterlab.log"
    server = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "jupyterlab",
            "--no-browser",
            "--ServerApp.ip=127.0.0.1",
            f"--ServerApp.port={port}",
            f"--IdentityProvider.token={token}",
            f"--ServerApp.root_dir={root}",
            "--LabApp.expose_app_in_browser=True",
            "--allow-root",
            "--LabApp.news_url=",
            "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
        ],
        env=environment,
        stdout=log.open("w"),
        stderr=subprocess.STDOUT,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        status = f"{base}/api/status?token={token}"
        answer = poll(
            lambda: _server_state(status, server), lambda a: not a.startswith("no answer"), WAIT_SECONDS
        )
        assert answer == "answers", (
            f"waited {WAIT_SECONDS} s for JupyterLab to answer: {answer}; its log:\n{_log_tail(log)}"
        )
        yield base, token, log
    finally:
        server.terminate()
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()


def drive_notebook(lab: Lab, path: str, sliders: tuple[tuple[str, str], ...]) -> None:
    """Open the notebook ``path`` (a path under the server's root) in ``lab``, run it and move each slider
    of ``sliders`` (cell snippet, slider label)."""
    from selenium.webdriver.common.keys import Keys

    driver, log = lab.driver, lab.log
    driver.get(f"{lab.base}/lab/tree/{path}?token={lab.token}")
    state = _wait_for_notebook(
        driver,
        path,
        log,
        lambda s: s["found"] and s["loaded"] and s["cells"] > 0 and s["kernel"] == "idle",
        WAIT_SECONDS,
        f"{path} to open, its cells loaded and its kernel idle",
    )
    driver.execute_script(
        "window.jupyterapp.commands.execute('notebook:run-all-cells', {widgetId: arguments[0]});",
        state["id"],
    )
    state = _wait_for_notebook(
        driver,
        path,
        log,
        lambda s: (
            s["found"]
            and bool(
                s["errors"] or (s["executed"] == s["cells"] and s["kernel"] == "idle" and not s["running"])
            )
        ),
        RUN_SECONDS,
        "the notebook to run",
    )
    assert state["errors"] == [], state["errors"]
    for snippet, description in sliders:
        output = _widget_output(driver, state["id"], snippet)
        driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", output)
        before = poll(lambda o=output, d=description: _slider(o, d), bool, WAIT_SECONDS)
        assert before, (
            f"waited {WAIT_SECONDS} s for the {description} slider and its figure; the cell's output "
            f"shows {output.text[:300]!r}; console errors: {console_errors(driver)}"
        )
        before["handle"].click()
        before["handle"].send_keys(Keys.ARROW_RIGHT)
        now = poll(
            lambda o=output, d=description: _slider(o, d),
            lambda n, b=before: _moved(b, n),
            WAIT_SECONDS,
        )
        assert _moved(before, now), (
            f"waited {WAIT_SECONDS} s for the {description} slider to move from {before['readout']} "
            f"and its figure to change; last saw {_seen(before, now)}; "
            f"console errors: {console_errors(driver)}"
        )
    state = driver.execute_script(_NOTEBOOK_STATE, path)
    assert state["errors"] == [], state["errors"]
