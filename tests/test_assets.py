"""The report's scripts, styles and fonts: fetched and unpacked once into the vendor folder, then linked into
each report."""

import os
from pathlib import Path

import pytest

from motionlab.course.assets import NPM_PACKAGES, fetch_npm_package, install_assets


def _files(root: Path) -> list[str]:
    return sorted(str(path.relative_to(root)) for path in root.rglob("*") if path.is_file())


def test_every_report_gets_the_same_assets_linked_from_one_unpacked_copy(tmp_path):
    try:
        for package in NPM_PACKAGES.values():
            fetch_npm_package(package)
    except RuntimeError as error:
        pytest.skip(f"the npm registry cannot be reached here: {error}")
    first, second = tmp_path / "first", tmp_path / "second"
    urls = install_assets(first)
    assert urls == install_assets(second)
    assert set(urls) == {"mathjax_url", "require_js_url", "widget_renderer_url", "font_awesome_css"}
    assert _files(first) == _files(second) and len(_files(first)) > 100
    for url in (urls["require_js_url"], urls["widget_renderer_url"], urls["font_awesome_css"]):
        assert (first / url).is_file(), url
    assert (first / urls["mathjax_url"].split("?")[0]).is_file()
    # The widget manager's icon fonts sit where its stylesheet asks for them, beside its folder.
    assert list((first / "@jupyter-widgets").glob("*.woff2"))
    # One copy on disk: the two reports' files are links of the same unpacked file.
    assert os.path.samefile(first / urls["require_js_url"], second / urls["require_js_url"])
    # A build in the folder of an earlier one: its links are found in place, a file left there is replaced.
    stray = first / urls["require_js_url"]
    stray.unlink()
    stray.write_text("an old copy")
    assert install_assets(first) == urls and _files(first) == _files(second)
    assert os.path.samefile(stray, second / urls["require_js_url"])
