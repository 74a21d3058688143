"""The widgets in a live JupyterLab, driven by headless Chromium: each chapter of :data:`CHAPTERS` runs in
the quick profile, then one slider of each of its listed widgets is moved with the keyboard, and each
widget's figure must change, with no error output anywhere. Skipped, with how to enable it, when Chromium
is not installed. One server and one browser serve every chapter; the server is stopped at the end, whatever
happens.

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

import pytest

from motionlab.course.browser import browser_available, chromium, console_errors, poll
from motionlab.paths import REPO_ROOT

pytestmark = pytest.mark.skipif(
    not browser_available(),
    reason="needs Debian's chromium and chromium-driver (apt-get install chromium chromium-driver)",
)

#: The chapters driven, each with its widgets: a snippet of the code cell that builds the widget and the
#: label of the slider moved in it. Chapter 11's sample widget alone: every widget of chapters 08 and 11
#: draws through the same ``motionlab.widgets.controls.wire``, and the unit tests move a slider of each
#: without a browser; what only a live JupyterLab shows (the widgets' comms, a key press on a slider reaching
#: the kernel, the new image reaching the page) one slider shows as well as three. The conftest runs this
#: module on the worker that ran chapter 11 under nbval, right after it, so the chapter's models are in the
#: build's cache.
CHAPTERS: dict[str, tuple[tuple[str, str], ...]] = {
    "notebooks/11_motion_diffusion.ipynb": (("sample_widget(", "seed"),),
}
#: Seconds for JupyterLab to answer, for the chapter to open with an idle kernel, and for a slider's new
#: figure: each takes seconds here.
WAIT_SECONDS = 300
#: Seconds for the chapter to run in the quick profile (under a minute here).
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


def _wait_for_notebook(driver, chapter: str, log: Path, done, seconds: float, what: str) -> dict:
    """Poll the state of the notebook ``chapter`` until ``done`` holds for it; past ``seconds``, fail saying
    what was seen."""
    state = poll(lambda: driver.execute_script(_NOTEBOOK_STATE, chapter), done, seconds)
    assert done(state), (
        f"waited {seconds:.0f} s for {what}; the notebook's state last: {json.dumps(state)}; "
        f"console errors: {console_errors(driver)}; the end of JupyterLab's log:\n{_log_tail(log)}"
    )
    return state


def _widget_output(driver, panel_id: str, source_snippet: str):
    """The rendered output element of the code cell whose source contains ``source_snippet``, in the notebook
    panel ``panel_id`` (the other chapters stay open in their own tabs)."""
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
    """A running JupyterLab server on the repository and a headless Chromium: what every chapter's test
    drives."""

    base: str
    token: str
    driver: Any
    log: Path


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Lab]:
    """One JupyterLab server and one Chromium for the module's chapters (each starts in seconds, but
    JupyterLab's page takes as long again to load); stopped at the end, whatever happens."""
    with serve(tmp_path_factory.mktemp("jupyterlab"), REPO_ROOT) as (base, token, log), chromium() as driver:
        yield Lab(base, token, driver, log)


@pytest.mark.parametrize("chapter", list(CHAPTERS))
def test_widgets_respond_in_a_live_jupyterlab(lab: Lab, chapter: str) -> None:
    original = (REPO_ROOT / chapter).read_bytes()
    drive_chapter(lab, chapter, CHAPTERS[chapter])
    assert (REPO_ROOT / chapter).read_bytes() == original, f"{chapter} was changed by the test"


@contextmanager
def serve(tmp_path: Path, root: Path) -> Iterator[tuple[str, str, Path]]:
    """JupyterLab serving ``root`` in the quick profile, without autosave (the chapters run in the
    repository's own files: JupyterLab must not save outputs into them); yields its address, token and log
    once it answers, and stops it at the end."""
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


def drive_chapter(lab: Lab, chapter: str, sliders: tuple[tuple[str, str], ...]) -> None:
    """Open the notebook ``chapter`` (a path under the server's root) in ``lab``, run it and move each slider
    of ``sliders`` (cell snippet, slider label)."""
    from selenium.webdriver.common.keys import Keys

    driver, log = lab.driver, lab.log
    driver.get(f"{lab.base}/lab/tree/{chapter}?token={lab.token}")
    state = _wait_for_notebook(
        driver,
        chapter,
        log,
        lambda s: s["found"] and s["loaded"] and s["cells"] > 0 and s["kernel"] == "idle",
        WAIT_SECONDS,
        f"{chapter} to open, its cells loaded and its kernel idle",
    )
    driver.execute_script(
        "window.jupyterapp.commands.execute('notebook:run-all-cells', {widgetId: arguments[0]});",
        state["id"],
    )
    state = _wait_for_notebook(
        driver,
        chapter,
        log,
        lambda s: (
            s["found"]
            and bool(
                s["errors"] or (s["executed"] == s["cells"] and s["kernel"] == "idle" and not s["running"])
            )
        ),
        RUN_SECONDS,
        "the chapter to run",
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
    state = driver.execute_script(_NOTEBOOK_STATE, chapter)
    assert state["errors"] == [], state["errors"]
