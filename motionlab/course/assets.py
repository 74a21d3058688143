"""The scripts, styles and fonts that the report's pages need, kept beside the pages so they work offline.

nbconvert's page template and matplotlib's animations load their helpers from the web: MathJax (the
formulas), require.js and the widget manager ``@jupyter-widgets/html-manager`` (the stored widget views),
and Font Awesome (the animation buttons). Opened from the file system without a network, such a page shows
raw LaTeX, empty widget boxes and blank buttons. So the course build copies local versions of them into
``<course>/_static/`` (the widget manager into ``<course>/@jupyter-widgets/``, where its stylesheet looks
for its fonts) and points the pages there. They are pinned npm packages (:data:`NPM_PACKAGES`), fetched
once with ``npm pack`` from the npm registry into ``build/vendor/`` (checked against their pinned SHA-512
integrity) and reused after that; the files the pages use are unpacked there once too, and each build links
them into its report (a copy where the file system cannot link).

When npm or the registry is not reachable, :func:`install_assets` says so and the pages keep the web
addresses for what is missing (they then need a network, as before).
"""

from __future__ import annotations

import base64
import hashlib
import os
import shutil
import subprocess
import tarfile
import tempfile
from dataclasses import dataclass
from fnmatch import fnmatch
from pathlib import Path

from motionlab.paths import build_dir

#: Where the assets go, relative to the report directory.
STATIC = "_static"


@dataclass(frozen=True)
class NpmPackage:
    """A pinned npm package and the files the report needs from it (paths or ``fnmatch`` patterns inside the
    package; a directory ends with ``/``)."""

    name: str
    version: str
    integrity: str
    files: tuple[str, ...]

    @property
    def tarball(self) -> str:
        """The file name ``npm pack`` gives the package."""
        return f"{self.name.lstrip('@').replace('/', '-')}-{self.version}.tgz"


#: The npm packages of the report pages, by the directory they get under ``_static``.
NPM_PACKAGES: dict[str, NpmPackage] = {
    "mathjax": NpmPackage(
        "mathjax",
        "2.7.9",
        "sha512-NOGEDTIM9+MrsqnjPEjVGNx4q0GQxqm61yQwSK+/5S59i26wId5IC5gNu9/bu8+CCVl5p9G2IHcAl/wJa+5+BQ==",
        (
            "MathJax.js",
            "config/TeX-AMS-MML_SVG-full.js",
            "config/Safe.js",
            "extensions/",
            "jax/input/",
            "jax/element/",
            "jax/output/SVG/config.js",
            "jax/output/SVG/jax.js",
            "jax/output/SVG/autoload/",
            "jax/output/SVG/fonts/TeX/",
            "localization/en/",
        ),
    ),
    "html-manager": NpmPackage(
        "@jupyter-widgets/html-manager",
        "1.0.15",
        "sha512-5thBIV6ymNgmPVOHvzx+gGy8ZSKmSazhtGw4/c4xJDVzRhG9PTeQsRjF3FUTopvFi//SABeNz1yp47bCrJ3CQA==",
        ("dist/embed-amd.js", "dist/*.woff2", "dist/*.woff", "dist/*.ttf", "dist/*.eot", "dist/*.svg"),
    ),
    "requirejs": NpmPackage(
        "requirejs",
        "2.3.7",
        "sha512-DouTG8T1WanGok6Qjg2SXuCMzszOo0eHeH9hDZ5Y4x8Je+9JB38HdTLT4/VA8OaUhBa0JPVHJ0pyBkM1z+pDsw==",
        ("require.js",),
    ),
    "font-awesome": NpmPackage(
        "font-awesome",
        "4.7.0",
        "sha512-U6kGnykA/6bFmg1M/oT9EkFeIYv7JlX3bozwQJWiiLz6L0w3F5vBVPxHlwyX/vtNq1ckcpRKOB9f2Qal/VtFpg==",
        ("css/", "fonts/"),
    ),
}

#: The MathJax configuration the pages ask for: MathJax 2.7's combined TeX/MathML input with SVG output
#: (glyph outlines drawn from JavaScript data, so no web font has to load: Chromium refuses fonts to pages
#: opened from the file system), and the Safe extension.
MATHJAX_CONFIG = "TeX-AMS-MML_SVG-full,Safe"

#: The web address of Font Awesome in matplotlib's animation HTML, replaced by the local copy.
FONT_AWESOME_WEB = "https://maxcdn.bootstrapcdn.com/font-awesome/4.4.0/css/font-awesome.min.css"


#: The environment variable that names the vendor folder, for builds under another ``MOTIONLAB_BUILD`` that
#: share one (the tests' builds in temporary folders).
VENDOR_VARIABLE = "MOTIONLAB_VENDOR"


def vendor_dir() -> Path:
    """Where fetched npm packages are kept between builds: ``MOTIONLAB_VENDOR`` if set, else
    ``build/vendor``."""
    named = os.environ.get(VENDOR_VARIABLE, "").strip()
    return Path(named) if named else build_dir() / "vendor"


def _sha512(path: Path) -> str:
    return "sha512-" + base64.b64encode(hashlib.sha512(path.read_bytes()).digest()).decode()


def fetch_npm_package(package: NpmPackage, directory: Path | None = None) -> Path:
    """The package's tarball in ``directory`` (default :func:`vendor_dir`), fetched with ``npm pack`` if
    absent; raises ``RuntimeError`` naming the package if npm fails or the tarball's integrity is wrong."""
    directory = vendor_dir() if directory is None else directory
    directory.mkdir(parents=True, exist_ok=True)
    tarball = directory / package.tarball
    if not tarball.exists():
        spec = f"{package.name}@{package.version}"
        # Packed into a folder of its own, then moved into place: a build beside this one never reads a
        # tarball half written.
        staging = Path(tempfile.mkdtemp(prefix=".pack-", dir=directory))
        try:
            try:
                proc = subprocess.run(
                    ["npm", "pack", spec, "--silent", "--pack-destination", str(staging)],
                    capture_output=True,
                    text=True,
                    timeout=300,
                )
            except (OSError, subprocess.TimeoutExpired) as error:
                raise RuntimeError(f"npm pack {spec}: {error}") from error
            if proc.returncode != 0 or not (staging / package.tarball).exists():
                raise RuntimeError(f"npm pack {spec} failed: {proc.stderr.strip()[-300:]}")
            os.replace(staging / package.tarball, tarball)
        finally:
            shutil.rmtree(staging, ignore_errors=True)
    if _sha512(tarball) != package.integrity:
        tarball.unlink()
        raise RuntimeError(
            f"{package.name}@{package.version}: the downloaded tarball does not match its pinned integrity"
        )
    return tarball


def _unpacked(tarball: Path, files: tuple[str, ...]) -> Path:
    """The folder beside ``tarball`` that holds ``files`` unpacked from it (:func:`_extract`), made on first
    use (in a folder of its own, then renamed into place, so a build beside this one sees it whole or not
    at all)."""
    digest = hashlib.sha256("\n".join(files).encode()).hexdigest()[:12]
    folder = tarball.with_name(f"{tarball.name.removesuffix('.tgz')}-{digest}")
    if not folder.is_dir():
        staging = Path(tempfile.mkdtemp(prefix=".unpack-", dir=tarball.parent))
        try:
            _extract(tarball, files, staging)
            staging.rename(folder)
        except OSError:
            if not folder.is_dir():  # not another build's folder that won the race
                raise
        finally:
            shutil.rmtree(staging, ignore_errors=True)
    return folder


def _link_or_copy(source: str, destination: str) -> None:
    """A hard link of ``source`` at ``destination`` (the report's assets are never written to), a copy where
    the two are on different file systems; a build in the folder of an earlier one finds its links in place,
    and replaces any other file there."""
    if os.path.lexists(destination):
        if os.path.exists(destination) and os.path.samefile(source, destination):
            return
        os.unlink(destination)
    try:
        os.link(source, destination)
    except OSError:
        shutil.copy2(source, destination)


def _install(tarball: Path, files: tuple[str, ...], target: Path) -> None:
    """``files`` of ``tarball`` in ``target``, keeping their paths inside the package."""
    shutil.copytree(_unpacked(tarball, files), target, copy_function=_link_or_copy, dirs_exist_ok=True)


def _extract(tarball: Path, files: tuple[str, ...], target: Path) -> None:
    """Copy ``files`` (paths or patterns, or directories ending in ``/``, inside the package) from
    ``tarball`` to ``target``, keeping their relative paths."""
    with tarfile.open(tarball) as archive:
        for member in archive.getmembers():
            inner = member.name.removeprefix("package/")
            wanted = any(fnmatch(inner, f) or (f.endswith("/") and inner.startswith(f)) for f in files)
            if member.isfile() and wanted:
                destination = target / inner
                destination.parent.mkdir(parents=True, exist_ok=True)
                source = archive.extractfile(member)
                assert source is not None
                destination.write_bytes(source.read())


def install_assets(report_dir: Path) -> dict[str, str]:
    """Copy every asset into ``report_dir`` and return nbconvert's resource URLs for the ones present.

    The returned dict has the ``HTMLExporter`` settings (``mathjax_url``, ``require_js_url``,
    ``widget_renderer_url``) as relative URLs, plus ``"font_awesome_css"`` for :func:`localize_page`. A
    missing asset is reported on stdout and left out, so its web address stays in the pages.
    """
    urls: dict[str, str] = {}
    for key, package in NPM_PACKAGES.items():
        try:
            tarball = fetch_npm_package(package)
        except RuntimeError as error:
            print(f"[report] {error}; the pages load it from the web", flush=True)
            continue
        if key == "html-manager":
            # Its stylesheet asks for its icon fonts at "@jupyter-widgets/html-manager/dist/" and at
            # "@jupyter-widgets/", both relative to the page: the manager goes where it expects to be.
            _install(tarball, package.files, report_dir / "@jupyter-widgets" / "html-manager")
            fonts = _unpacked(tarball, package.files[1:]) / "dist"
            shutil.copytree(
                fonts, report_dir / "@jupyter-widgets", copy_function=_link_or_copy, dirs_exist_ok=True
            )
            urls["widget_renderer_url"] = "@jupyter-widgets/html-manager/dist/embed-amd.js"
            continue
        _install(tarball, package.files, report_dir / STATIC / key)
        if key == "mathjax":
            urls["mathjax_url"] = f"{STATIC}/mathjax/MathJax.js?config={MATHJAX_CONFIG}"
        elif key == "requirejs":
            urls["require_js_url"] = f"{STATIC}/requirejs/require.js"
        elif key == "font-awesome":
            urls["font_awesome_css"] = f"{STATIC}/font-awesome/css/font-awesome.min.css"
    return urls


def localize_page(page: str, urls: dict[str, str]) -> str:
    """``page`` with the web addresses that :func:`install_assets` replaced by local copies rewritten
    (today: Font Awesome in matplotlib's animations)."""
    if "font_awesome_css" in urls:
        page = page.replace(FONT_AWESOME_WEB, urls["font_awesome_css"])
        # the same link inside stored widget state, whose JSON writes "/" as "\/"
        page = page.replace(
            FONT_AWESOME_WEB.replace("/", "\\/"), urls["font_awesome_css"].replace("/", "\\/")
        )
    return page
