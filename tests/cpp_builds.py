"""The CMake builds of the C++ tests, started in the background as soon as pytest knows it will
run tests that need them (conftest.py), so that they compile while the Python tests run; the
fixtures of tests/test_cpp.py wait for them.

* ``release``: the tests as firmware builds them (``-O3 -DNDEBUG``), the fast tier; with
  ``wide``, also the binaries built for the wider instruction-set levels this CPU runs
  (x86-64-v3, v4: the slow tier; the same build directory, so that only those are compiled
  when the fast tier has built the rest);
* ``sanitized``: every test, the wide ones included, under AddressSanitizer and
  UndefinedBehaviorSanitizer, in a Debug build (Eigen's and the library's assertions on)
  optimised to -O1 (tests/cpp/CMakeLists.txt says which checks and why), the slow tier.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BUILDS = {
    "release": (REPO / "build" / "cpp-tests", ("-DCMAKE_BUILD_TYPE=Release",)),
    "sanitized": (REPO / "build" / "cpp-tests-sanitized", ("-DCMAKE_BUILD_TYPE=Debug", "-DALGID_SANITIZE=ON")),
}
#: The fixture of each build, by name (tests/test_cpp.py).
FIXTURES = {"cpp_build": "release", "sanitized_build": "sanitized"}


class BuildError(RuntimeError):
    """A configure or build step failed; the message holds the end of its output."""


def runnable_levels() -> list[str]:
    """The wide instruction-set levels (v3, v4) this CPU runs: the test binaries are built for
    those only (a binary this CPU cannot run would be compiled to be skipped)."""
    from algid import _core

    return [level for level in ("v3", "v4") if _core.cpu_supports(f"x86-64-{level}")]


def configure_and_build(build: Path, options: tuple[str, ...], levels: list[str]) -> Path:
    """Configure and build the C++ tests in ``build``, the wide ones for ``levels``, on every
    core; BuildError on a failed step."""
    cmake = shutil.which("cmake")
    if cmake is None:
        raise BuildError("cmake not found: install the test extra (pip install '.[test]')")
    cmd = [cmake, "-S", str(REPO), "-B", str(build), "-DALGID_BUILD_TESTS=ON", f"-DPython_EXECUTABLE={sys.executable}"]
    cmd += [f"-DALGID_TEST_ISA_LEVELS={';'.join(levels)}", *options]
    if shutil.which("ninja") and not (build / "CMakeCache.txt").exists():
        cmd += ["-G", "Ninja"]
    for step in (cmd, [cmake, "--build", str(build), "-j", str(os.cpu_count() or 2)]):
        proc = subprocess.run(step, capture_output=True, text=True)
        if proc.returncode != 0:
            raise BuildError(f"{' '.join(step[:3])} failed:\n{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}")
    return build


_pool = ThreadPoolExecutor(max_workers=len(BUILDS), thread_name_prefix="cpp-build")
_started: dict[str, Future] = {}


def start(name: str, wide: bool = True) -> Future:
    """Start build ``name`` (once), with the ``wide`` binaries or not (``release``; the
    sanitized build has them always); its future."""
    if name not in _started:
        build, options = BUILDS[name]
        levels = runnable_levels() if wide or name != "release" else []
        _started[name] = _pool.submit(configure_and_build, build, options, levels)
    return _started[name]


def wait(name: str) -> Path:
    """The build directory of ``name``, once built (started here, with the wide binaries, if
    it was not)."""
    return start(name).result()
