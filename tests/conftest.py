"""Shared fixtures (paths to the repository and to the measured data sets), and the order of
the run: the C++ tests go last, and the builds they need start in the background as soon as
the tests are collected, so that they compile while the Python tests run (tests/cpp_builds.py)."""

from __future__ import annotations

import os
from pathlib import Path

# The C++ tests compile beside the Python tests: BLAS threads that spin while they wait for a
# core the compiler holds would slow every numpy call down, so numpy's BLAS runs on one thread
# (set before numpy is first imported; a value already set is kept).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import pytest  # noqa: E402

import cpp_builds  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
#: Real measured data live beside the checkout (../shared/data), never in the repository.
SHARED_DATA = REPO.parent / "shared" / "data"


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO


@pytest.fixture(scope="session")
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        pytest.skip(f"measured data not present at {SHARED_DATA}")
    return SHARED_DATA


@pytest.hookimpl(trylast=True)  # after -m and -k have deselected what will not run
def pytest_collection_modifyitems(session, config, items) -> None:
    """The C++ tests last, their builds started now (module docstring)."""
    cpp = [item for item in items if Path(str(item.fspath)).name == "test_cpp.py"]
    if not cpp or config.option.collectonly:
        return
    wide = any(any(name in item.name for name in ("_v3]", "_v4]")) for item in cpp if "cpp_build" in item.fixturenames)
    for fixture, build in cpp_builds.FIXTURES.items():
        if any(fixture in item.fixturenames for item in cpp):
            cpp_builds.start(build, wide)
    rest = [item for item in items if Path(str(item.fspath)).name != "test_cpp.py"]
    items[:] = rest + cpp
