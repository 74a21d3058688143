"""The widgets in a live JupyterLab, driven by headless Chromium: chapter 08 runs in the quick profile, then
a slider of its sampling widget and a slider of its interpolation widget are moved with the keyboard, and
each widget's figure must change, with no error output anywhere. Skipped, with how to enable it, when
Chromium is not installed. The server is stopped at the end, whatever happens."""

from __future__ import annotations

import os
import secrets
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from motionlab.course.browser import browser_available, chromium
from motionlab.paths import REPO_ROOT

pytestmark = pytest.mark.skipif(
    not browser_available(),
    reason="needs Debian's chromium and chromium-driver (apt-get install chromium chromium-driver)",
)

CHAPTER = "notebooks/08_contrastive_mode_discovery.ipynb"
#: Seconds for JupyterLab to start, and for the chapter to run in the quick profile (its cell limit).
START_SECONDS = 90
RUN_SECONDS = 600

_NOTEBOOK_STATE = """
const panel = window.jupyterapp && window.jupyterapp.shell.currentWidget;
if (!panel || !panel.content || !panel.sessionContext) { return null; }
const kernel = panel.sessionContext.session && panel.sessionContext.session.kernel;
const cells = panel.content.widgets.filter(c => c.model.type === 'code');
const errors = [];
cells.forEach((cell, i) => {
  cell.model.outputs.toJSON().forEach(o => {
    if (o.output_type === 'error') { errors.push(`cell ${i}: ${o.ename}: ${o.evalue}`); }
  });
});
return {kernel: kernel ? kernel.status : 'none', cells: cells.length,
        executed: cells.filter(c => c.model.executionCount !== null).length,
        running: cells.filter(c => c.promptNode && c.promptNode.textContent.includes('*')).length,
        errors: errors};
"""


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _wait(condition, seconds: float, what: str):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.5)
    raise AssertionError(f"timed out after {seconds:.0f} s waiting for {what}")


def _server_answers(url: str) -> bool:
    try:
        with urllib.request.urlopen(url, timeout=2) as reply:
            return reply.status == 200
    except OSError:
        return False


def _widget_output(driver, source_snippet: str):
    """The rendered output element of the code cell whose source contains ``source_snippet``."""
    from selenium.webdriver.common.by import By

    for cell in driver.find_elements(By.CSS_SELECTOR, ".jp-CodeCell"):
        if source_snippet in cell.find_element(By.CSS_SELECTOR, ".jp-InputArea").text:
            return cell.find_element(By.CSS_SELECTOR, ".jp-OutputArea")
    raise AssertionError(f"no cell with {source_snippet!r}")


def _move_slider(driver, output, description: str) -> bytes:
    """Press the right arrow on the slider labelled ``description`` in ``output``; return a screenshot of
    the widget's figure taken before the move."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", output)
    sliders = [
        s
        for s in output.find_elements(By.CSS_SELECTOR, ".widget-slider")
        if s.find_element(By.CSS_SELECTOR, "label").text.strip() == description
    ]
    assert sliders, f"no slider {description!r}"
    figure = output.find_elements(By.CSS_SELECTOR, ".widget-output img")
    assert figure, "the widget shows no figure"
    before = figure[0].screenshot_as_png
    handle = sliders[0].find_element(By.CSS_SELECTOR, ".noUi-handle")
    handle.click()
    handle.send_keys(Keys.ARROW_RIGHT)
    return before


def _figure_changed(output, before: bytes) -> bool:
    from selenium.webdriver.common.by import By

    figure = output.find_elements(By.CSS_SELECTOR, ".widget-output img")
    return bool(figure) and figure[0].screenshot_as_png != before


def test_widgets_respond_in_a_live_jupyterlab(tmp_path: Path) -> None:
    port, token = _free_port(), secrets.token_hex(16)
    environment = {**os.environ, "MOTIONLAB_PROFILE": "quick", "JUPYTER_CONFIG_DIR": str(tmp_path / "config")}
    server = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "jupyterlab",
            "--no-browser",
            "--ServerApp.ip=127.0.0.1",
            f"--ServerApp.port={port}",
            f"--IdentityProvider.token={token}",
            f"--ServerApp.root_dir={REPO_ROOT}",
            "--LabApp.expose_app_in_browser=True",
            "--allow-root",
            "--LabApp.news_url=",
            "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
        ],
        env=environment,
        stdout=(tmp_path / "jupyterlab.log").open("w"),
        stderr=subprocess.STDOUT,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        _wait(lambda: _server_answers(f"{base}/api/status?token={token}"), START_SECONDS, "JupyterLab")
        with chromium() as driver:
            driver.get(f"{base}/lab/tree/{CHAPTER}?token={token}")
            state = _wait(
                lambda: (s := driver.execute_script(_NOTEBOOK_STATE)) and s["kernel"] == "idle" and s,
                START_SECONDS,
                "the notebook and an idle kernel",
            )
            driver.execute_script("window.jupyterapp.commands.execute('notebook:run-all-cells');")
            state = _wait(
                lambda: (
                    (s := driver.execute_script(_NOTEBOOK_STATE))
                    and (
                        s["errors"]
                        or (s["executed"] == s["cells"] and s["kernel"] == "idle" and not s["running"])
                    )
                    and s
                ),
                RUN_SECONDS,
                "the chapter to run",
            )
            assert state["errors"] == [], state["errors"]
            for snippet, slider in (("mode_sampler_widget(", "seed"), ("interpolation_widget(", "weight")):
                output = _widget_output(driver, snippet)
                before = _move_slider(driver, output, slider)
                _wait(
                    lambda o=output, b=before: _figure_changed(o, b), 60, f"the {slider} slider's new figure"
                )
            state = driver.execute_script(_NOTEBOOK_STATE)
            assert state["errors"] == [], state["errors"]
    finally:
        server.terminate()
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()
