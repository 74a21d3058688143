"""The report's pages checked in a real browser: headless Chromium, opened from the file system.

For every page: no console error and no failed request (a page that fetches from the web fails here, as it
would offline), every image decoded, every formula typeset by MathJax (no raw LaTeX left in the text), and
every stored widget view rendered. For a page with a matplotlib animation, its first animation is played
and two screenshots taken half a second apart must differ.

It needs Debian's ``chromium`` and ``chromium-driver`` (``apt-get install chromium chromium-driver``);
:func:`browser_available` says whether they are there. Command line::

    python -m motionlab.course.browser build/course          # every .html page of the report
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

from motionlab import arguments

T = TypeVar("T")

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"

#: Chromium's flags for a closed network: no background connections, no first-run work, no GPU.
CHROMIUM_FLAGS = (
    "--headless=new",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
    "--window-size=1280,1600",
)

#: Seconds a page may take to load, typeset its formulas and render its widgets, and an animation to show a
#: new frame once played. A page here takes a few seconds; the limit leaves room for a slow machine that is
#: busy too, and a page that runs out of it is reported with what it still lacked.
PAGE_SECONDS = 300.0

#: LaTeX commands that must not be visible in the prose (Markdown outside code) once MathJax has typeset it.
RAW_LATEX = r"\\(frac|mathcal|mathbf|mathrm|sum|sqrt|lVert|operatorname|hat|tilde|sigma|mu)\b"

_PAGE_STATE = """
const viewType = 'script[type="application/vnd.jupyter.widget-view+json"]';
const views = Array.from(document.querySelectorAll(viewType));
const empty = views.filter(v => !Array.from(v.parentElement.children).some(c => c.tagName !== 'SCRIPT'));
const images = Array.from(document.images);
const broken = images.filter(i => !(i.complete && i.naturalWidth > 0)).map(i => (i.src || '').slice(0, 80));
const hub = window.MathJax && window.MathJax.Hub;
const mathPending = hub ? hub.queue.pending + hub.queue.running : 0;
const mathScripts = document.querySelectorAll('script[type^="math/tex"]').length;
const typeset = document.querySelectorAll('.MathJax, .MathJax_Display, .MathJax_SVG').length;
const prose = Array.from(document.querySelectorAll('.jp-RenderedMarkdown')).map(cell => {
  const copy = cell.cloneNode(true);
  copy.querySelectorAll('pre, code, script, style').forEach(e => e.remove());
  return copy.textContent;
}).join(' ');
const raw = (prose.match(new RegExp(arguments[0], 'g')) || []).slice(0, 5);
return {views: views.length, emptyViews: empty.length, images: images.length, broken: broken,
        mathJax: !!hub, mathPending: mathPending, mathScripts: mathScripts, typeset: typeset, rawLatex: raw,
        animations: document.querySelectorAll('.animation img').length};
"""


@dataclass
class PageReport:
    """What the browser found on one page; ``problems`` is empty when the page is fine."""

    page: str
    problems: list[str] = field(default_factory=list)
    state: dict = field(default_factory=dict)
    animation_checked: bool = False


def poll(probe: Callable[[], T], done: Callable[[T], bool], seconds: float, step: float = 0.5) -> T:
    """Call ``probe`` every ``step`` seconds until ``done`` holds for what it returned or ``seconds`` have
    passed; return what it returned last (so a caller that ran out can say what it saw)."""
    deadline = time.monotonic() + seconds
    while True:
        seen = probe()
        if done(seen) or time.monotonic() > deadline:
            return seen
        time.sleep(step)


def browser_available() -> bool:
    """Whether Debian's Chromium and its driver are installed (and selenium importable)."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return False
    return Path(CHROMIUM).exists() and Path(CHROMEDRIVER).exists()


@contextmanager
def chromium() -> Iterator[object]:
    """A headless Chromium under selenium, logging the console and the network; quit at the end.

    Its pages behave as if their window had the focus, whether or not it has (DevTools' focus emulation, as
    Playwright sets it): what follows the focus (JupyterLab's current widget, a focused slider) is then the
    same on every machine, desktop or headless, foreground or background."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    profile = tempfile.mkdtemp(prefix="motionlab-chromium-")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in (*CHROMIUM_FLAGS, f"--user-data-dir={profile}"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    driver = webdriver.Chrome(options=options, service=Service(CHROMEDRIVER))
    try:
        driver.execute_cdp_cmd("Emulation.setFocusEmulationEnabled", {"enabled": True})
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def console_errors(driver) -> list[str]:
    """The console's errors since the last call (each cut to 300 characters)."""
    return [entry["message"][:300] for entry in driver.get_log("browser") if entry["level"] == "SEVERE"]


def _failed_requests(driver) -> list[str]:
    """URLs whose loading failed, from the performance log (Chrome DevTools ``Network`` events)."""
    requested: dict[str, str] = {}
    failed = []
    for entry in driver.get_log("performance"):
        message = json.loads(entry["message"])["message"]
        params = message.get("params", {})
        if message.get("method") == "Network.requestWillBeSent":
            requested[params["requestId"]] = params["request"]["url"]
        elif message.get("method") == "Network.loadingFailed" and not params.get("canceled"):
            url = requested.get(params["requestId"])
            if url is not None:  # None: a request the browser started before this page, not the page's
                failed.append(f"{url[:120]} ({params.get('errorText', '')})")
    return failed


def _animation_moves(driver, seconds: float) -> bool:
    """Play the page's first matplotlib animation; whether a screenshot taken within ``seconds`` differs
    from the first one (screenshots are taken until one does)."""
    from selenium.webdriver.common.by import By

    image = driver.find_element(By.CSS_SELECTOR, ".animation img")
    driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", image)
    container = image.find_element(By.XPATH, "ancestor::div[contains(@class, 'animation')]")
    play = container.find_elements(By.CSS_SELECTOR, "button[title='Play']") or container.find_elements(
        By.CSS_SELECTOR, "button"
    )
    if not play:
        return False
    driver.execute_script("arguments[0].click();", play[0])
    first = image.screenshot_as_png
    return poll(lambda: image.screenshot_as_png, lambda shot: shot != first, seconds) != first


def check_page(driver, page: Path, timeout: float = PAGE_SECONDS) -> PageReport:
    """Open ``page`` (a file) and check it (see the module docstring)."""
    report = PageReport(page.name)
    driver.get_log("browser")  # drop what earlier pages left
    driver.get_log("performance")
    driver.get(page.resolve().as_uri())
    state = poll(
        lambda: driver.execute_script(_PAGE_STATE, RAW_LATEX),
        lambda s: (
            (s["mathJax"] or not s["mathScripts"])
            and s["mathPending"] == 0
            and s["emptyViews"] == 0
            and not s["broken"]
        ),
        timeout,
    )
    report.state = state
    report.problems += [f"console error: {message}" for message in console_errors(driver)]
    report.problems += [f"failed request: {url}" for url in _failed_requests(driver)]
    within = f"within {timeout:.0f} s"
    if state["broken"]:
        report.problems.append(
            f"{len(state['broken'])} image(s) not decoded {within}, e.g. {state['broken'][0]}"
        )
    if state["mathScripts"] and not state["mathJax"]:
        report.problems.append(f"MathJax did not load {within}: formulas show as raw LaTeX")
    elif state["mathPending"]:
        report.problems.append(
            f"MathJax did not finish typesetting {within} ({state['mathPending']} pending)"
        )
    if state["rawLatex"]:
        report.problems.append(f"raw LaTeX in the text: {state['rawLatex']}")
    if state["emptyViews"]:
        report.problems.append(
            f"{state['emptyViews']} of {state['views']} widget views did not render {within}"
        )
    if state["animations"]:
        report.animation_checked = True
        if not _animation_moves(driver, timeout):
            report.problems.append(f"the first animation did not advance {within} of being played")
    return report


def check_report(report_dir: Path) -> list[PageReport]:
    """Check every ``.html`` page in ``report_dir`` (the index first), in one browser."""
    pages = sorted(report_dir.glob("*.html"), key=lambda p: (p.name != "index.html", p.name))
    if not pages:
        raise ValueError(f"check_report: no .html pages in {report_dir}")
    with chromium() as driver:
        return [check_page(driver, page) for page in pages]


def _main(directory: Path) -> int:
    if not browser_available():
        print(
            "motionlab.course.browser: needs chromium and chromium-driver"
            " (apt-get install chromium chromium-driver)"
        )
        return 1
    reports = check_report(directory)
    for report in reports:
        status = "ok" if not report.problems else "FAILED"
        extra = ", animation played" if report.animation_checked else ""
        state = report.state
        print(
            f"[browser] {report.page}: {status} ({state.get('typeset', 0)} formulas, {state.get('views', 0)} "
            f"widget views, {state.get('images', 0)} images{extra})"
        )
        for problem in report.problems:
            print(f"[browser]   {problem}")
    return 1 if any(report.problems for report in reports) else 0


def main(argv: list[str] | None = None) -> int:
    """The command line; returns the exit status (1 when a page has problems)."""
    prog = "python -m motionlab.course.browser"
    parser = argparse.ArgumentParser(prog=prog, description="Check the report's pages in headless Chromium.")
    parser.add_argument(
        "directory", type=arguments.existing_directory, help="the report directory (build/course)"
    )
    args = parser.parse_args(argv)
    return arguments.run(prog, lambda: _main(args.directory))


if __name__ == "__main__":
    sys.exit(main())
