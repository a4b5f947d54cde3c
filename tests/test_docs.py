"""The documentation site builds with warnings as errors (`mkdocs build --strict`): every page
in the navigation, every link and anchor resolved, every README/example snippet found, every
docstring of the API reference parsed."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
#: The strict build takes a while and needs the docs extra: the slow tier.
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    for module in ("mkdocs", "material", "mkdocstrings", "mkdocstrings_handlers.python"):
        pytest.importorskip(module, reason="the docs extra is not installed (pip install '.[docs]')")
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    cmd = [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(REPO / "mkdocs.yml"), "-d", str(out)]
    proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return out


def test_every_markdown_page_is_a_site_page(site: Path) -> None:
    pages = sorted(p.relative_to(REPO / "docs").with_suffix("") for p in (REPO / "docs").rglob("*.md"))
    for page in pages:
        built = site / ("index.html" if page.name == "index" else page / "index.html")
        assert built.is_file(), f"docs/{page}.md was not built"


def test_shared_text_comes_from_its_one_home(site: Path) -> None:
    """The home, theory and firmware pages include the README's sections and the example."""
    readme = (REPO / "README.md").read_text()
    assert "Quick start" in (site / "index.html").read_text() and "## Quick start" in readme
    assert "Quadrature" in (site / "theory" / "index.html").read_text()
    firmware = (site / "firmware" / "index.html").read_text()
    assert "firmware_loop: " in firmware  # from examples/firmware_loop.cpp
    assert "ChainEstimator&lt;3&gt;" in firmware  # the README's C++ section


def test_api_reference_is_generated_from_the_docstrings(site: Path) -> None:
    import algid

    api = (site / "api" / "index.html").read_text()
    for anchor in (
        "algid.estimator.ChainEstimator.spring",
        "algid.estimator.continuous.ContinuousEstimator.ready",
        "algid.recording.Recording",
        "algid.identification.engine.identify",
        "algid.diagnosis.engine.diagnose",
    ):
        assert f'id="{anchor}"' in api, anchor
    first_line = algid.ChainEstimator.spring.__doc__.split("``")[0]
    assert first_line.strip() in api
