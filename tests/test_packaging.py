"""Packaging habits: one version everywhere, and imports without side effects on matplotlib."""

from __future__ import annotations

import importlib.metadata
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import algid

REPO = Path(__file__).resolve().parents[1]


def _numeric_part(version: str) -> str:
    """The leading X.Y.Z of a version, which is what CMake's project(VERSION) can hold."""
    match = re.match(r"v?(\d+(?:\.\d+)*)", version)
    assert match is not None, f"__version__ {version!r} does not start with a number"
    return match.group(1)


def test_version_of_the_installed_metadata_is_the_package_version() -> None:
    """pyproject.toml reads the version from python/algid/__init__.py (scikit-build-core regex)."""
    assert importlib.metadata.version("algid") == algid.__version__


def test_version_is_written_only_in_the_package() -> None:
    source = (REPO / "python" / "algid" / "__init__.py").read_text()
    assert re.findall(r'^__version__ = "([^"]+)"$', source, flags=re.M) == [algid.__version__]
    pyproject = (REPO / "pyproject.toml").read_text()
    project = pyproject.split("[project]", 1)[1].split("\n[", 1)[0]
    assert not re.search(r"^version\s*=", project, flags=re.M), "pyproject.toml [project] sets a version"
    assert re.search(r'^dynamic\s*=\s*\[[^]]*"version"', project, flags=re.M)
    cmake = (REPO / "CMakeLists.txt").read_text()
    assert re.search(r"project\(algid VERSION \$\{", cmake), "CMakeLists.txt project() hard-codes a version"


def test_version_configured_by_cmake_is_the_package_version(tmp_path: Path) -> None:
    """A plain CMake configure (no Python module, no tests) writes the installed package version file."""
    cmake = shutil.which("cmake")
    if cmake is None:
        pytest.fail("cmake not found: install the test extra (pip install '.[test]')")
    build = tmp_path / "build"
    cmd = [
        cmake,
        "-S",
        str(REPO),
        "-B",
        str(build),
        "-DALGID_BUILD_PYTHON=OFF",
        "-DALGID_BUILD_TESTS=OFF",
        f"-DPython_EXECUTABLE={sys.executable}",
    ]
    if shutil.which("ninja"):
        cmd += ["-G", "Ninja"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    config_version = (build / "algidConfigVersion.cmake").read_text()
    match = re.search(r'set\(PACKAGE_VERSION "([^"]+)"\)', config_version)
    assert match is not None, config_version[:2000]
    assert match.group(1) == _numeric_part(algid.__version__)


# Run in a fresh interpreter: the test session may already have imported matplotlib or pyplot.
_BACKEND_PROBE = textwrap.dedent("""
    import importlib, io, json, pkgutil, sys

    import algid
    report = {"matplotlib_after_import_algid": "matplotlib" in sys.modules}

    import matplotlib
    matplotlib.use("svg")
    import algid.plotting
    modules = [m.name for m in pkgutil.iter_modules(algid.plotting.__path__, "algid.plotting.")]
    for name in modules:
        importlib.import_module(name)
    report["modules"] = modules
    report["backend_after_import"] = matplotlib.get_backend()

    fig, ax = algid.plotting.subplots()
    ax.plot([0.0, 1.0], [0.0, 1.0])
    png = io.BytesIO()
    fig.savefig(png, format="png")
    report["png_bytes"] = len(png.getvalue())
    report["backend_after_figure"] = matplotlib.get_backend()
    report["pyplot_imported"] = "matplotlib.pyplot" in sys.modules
    print(json.dumps(report))
""")


def test_plotting_leaves_the_matplotlib_backend_alone() -> None:
    """`import algid` does not import matplotlib; `import algid.plotting` (every module) and drawing
    a figure keep the backend the user chose and never import pyplot."""
    import json

    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    proc = subprocess.run([sys.executable, "-c", _BACKEND_PROBE], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-4000:]
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert report["matplotlib_after_import_algid"] is False
    assert "algid.plotting.identify" in report["modules"]
    assert report["backend_after_import"] == "svg"
    assert report["backend_after_figure"] == "svg"
    assert report["pyplot_imported"] is False
    assert report["png_bytes"] > 1000
