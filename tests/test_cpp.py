"""Build the C++ tests with CMake and run each binary, in a Release build (the fast tier) and
again under AddressSanitizer and UndefinedBehaviorSanitizer (the slow tier): the builds are
tests/cpp_builds.py's, started in the background while the Python tests run (conftest.py).

Needs cmake and Eigen (system libeigen3-dev, or cmeel-eigen from the ``test`` extra).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

import cpp_builds

REPO = Path(__file__).resolve().parents[1]
BINARIES = [
    "test_quadrature",
    "test_cramer",
    "test_lanes",
    "test_estimator",
    "test_one_force",
    "test_sizes",
    "test_realtime",
    "test_no_exceptions",
    "firmware_loop",
    "test_continuous",
    "test_fuzz",
]
# The same tests built for the wider instruction sets the wheel ships (x86-64 only; built for
# the levels this CPU runs, skipped otherwise): the slow tier.
WIDE_BINARIES = [f"{name}_{level}" for level in ("v3", "v4") for name in ("test_lanes", "test_sizes")]
RELEASE_BINARIES = BINARIES + [pytest.param(name, marks=pytest.mark.slow) for name in WIDE_BINARIES]


def _built(name: str) -> Path:
    try:
        return cpp_builds.wait(name)
    except cpp_builds.BuildError as err:
        pytest.fail(str(err))


@pytest.fixture(scope="session")
def cpp_build() -> Path:
    return _built("release")


@pytest.fixture(scope="session")
def sanitized_build() -> Path:
    return _built("sanitized")


def _binary(build: Path, name: str) -> Path | None:
    for candidate in (build / "tests" / "cpp" / name, build / "tests" / "cpp" / "Release" / name):
        if candidate.exists():
            return candidate
    return None


def _locate(build: Path, name: str) -> Path:
    """The binary `name` of `build`; skips (a wide build the compiler or CPU lacks, a source not in
    this tree) or fails (not built)."""
    exe = _binary(build, name)
    if exe is None and name in WIDE_BINARIES:
        pytest.skip(f"{name}: not built (this compiler, architecture or CPU has no {name.rsplit('_', 1)[1]} level)")
    if exe is None:
        source = {
            "firmware_loop": REPO / "examples" / "firmware_loop.cpp",
            "test_continuous": REPO / "tests" / "cpp" / "test_continuous.cpp",
        }.get(name)
        if source is not None and not source.exists():
            pytest.skip(f"{source.name} is not part of this tree")
        pytest.fail(f"{name} was not built")
    return exe


def _run(exe: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(exe)], capture_output=True, text=True, timeout=900)


def _check(proc: subprocess.CompletedProcess) -> None:
    print(proc.stdout)
    if proc.returncode == 77:
        pytest.skip(proc.stdout.strip())
    summary = re.search(r"(\d+) passed, (\d+) failed", proc.stdout)
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]
    assert summary is not None and int(summary.group(2)) == 0 and int(summary.group(1)) > 0


@pytest.mark.parametrize("name", RELEASE_BINARIES)
def test_cpp_binary(cpp_build: Path, name: str) -> None:
    _check(_run(_locate(cpp_build, name)))


@pytest.fixture(scope="session")
def sanitized_runs(sanitized_build: Path) -> dict[str, subprocess.CompletedProcess]:
    """Every sanitized binary run once, as many at a time as there are cores, the longest
    (test_continuous) first."""
    names = sorted(BINARIES + WIDE_BINARIES, key=lambda name: name != "test_continuous")
    exes = {name: exe for name in names if (exe := _binary(sanitized_build, name)) is not None}
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        futures = {name: pool.submit(_run, exe) for name, exe in exes.items()}
        return {name: future.result() for name, future in futures.items()}


@pytest.mark.parametrize("name", BINARIES + WIDE_BINARIES)
@pytest.mark.slow
def test_cpp_binary_sanitized(sanitized_build: Path, sanitized_runs: dict, name: str) -> None:
    """Every C++ test again under ASan + UBSan: a sanitizer report aborts the binary (non-zero exit)."""
    _locate(sanitized_build, name)
    _check(sanitized_runs[name])


@pytest.mark.parametrize(
    ("mode", "report"),
    [("heap-overflow", "AddressSanitizer: heap-buffer-overflow"), ("signed-overflow", "runtime error: signed integer")],
)
@pytest.mark.slow
def test_sanitizers_catch_the_negative_control(sanitized_build: Path, mode: str, report: str) -> None:
    exe = _binary(sanitized_build, "sanitizer_control")
    assert exe is not None, "sanitizer_control was not built"
    proc = subprocess.run([str(exe), mode], capture_output=True, text=True, timeout=60)
    assert proc.returncode != 0, proc.stdout
    assert report in proc.stderr, proc.stderr[-2000:]


def test_installed_package_is_found_by_cmake(cpp_build: Path, tmp_path: Path) -> None:
    """`cmake --install` then a downstream project with find_package(algid) builds and runs."""
    cmake = shutil.which("cmake")
    prefix = tmp_path / "prefix"
    steps = [[cmake, "--install", str(cpp_build), "--prefix", str(prefix)]]
    eigen_prefix = subprocess.run([sys.executable, "-m", "cmeel", "cmake"], capture_output=True, text=True)
    search = [str(prefix)] + ([eigen_prefix.stdout.strip()] if eigen_prefix.returncode == 0 else [])
    consumer = tmp_path / "consumer-build"
    steps.append(
        [
            cmake,
            "-S",
            str(REPO / "tests" / "cpp" / "consumer"),
            "-B",
            str(consumer),
            f"-DCMAKE_PREFIX_PATH={';'.join(search)}",
            "-DCMAKE_BUILD_TYPE=Release",
        ]
    )
    steps.append([cmake, "--build", str(consumer)])
    for step in steps:
        proc = subprocess.run(step, capture_output=True, text=True)
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert (prefix / "include" / "algid" / "algid.hpp").exists()
    exe = next(p for p in consumer.rglob("consumer") if p.is_file())
    proc = subprocess.run([str(exe)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout
    assert "1 passed, 0 failed" in proc.stdout
