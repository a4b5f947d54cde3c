"""The wheel as users get it: built and repaired to a manylinux tag by tools/build_wheel.sh,
installed into a fresh virtual environment, and run there.

CI builds that wheel anyway (``.ci/run`` installs the package from it) and passes its path
in ``ALGID_WHEEL``; without it (a developer's ``pytest``) the test is skipped. To run it by
hand: ``bash tools/build_wheel.sh dist`` and ``ALGID_WHEEL=dist/algid-...whl pytest
tests/test_wheel.py``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import venv
import zipfile
from pathlib import Path

import pytest

import algid

# In the fresh environment: a polynomial motion of degree 5 (accelerations of degree 3), which
# the 8-point quadrature integrates exactly, so the estimates are the chain's to rounding.
_PROBE = textwrap.dedent("""
    import json, shutil
    import numpy as np
    import algid

    t = np.arange(1000) * 1e-3
    x = np.polynomial.Polynomial([0, 1, 2, -3, 1, 0.5]) * 1e-3   # [m]
    v, a = x.deriv(), x.deriv(2)
    m, c, k = 2.0, 3.0, 800.0                                      # [kg], [N s/m], [N/m]
    u = m * a(t) + c * v(t) + k * x(t)                             # [N]
    est = algid.ChainEstimator(1, 1e-3)
    est.run(a(t)[:, None], u[:, None])
    print(json.dumps({
        "file": algid.__file__, "version": algid.__version__, "isa": algid.ISA,
        "estimates": [float(est.mass[0]), float(est.damping[0]), est.spring(1)],
        "header": __import__("os").path.isfile(algid.get_include() + "/algid/algid.hpp"),
        "cli": shutil.which("algid"),
    }))
""")


@pytest.fixture(scope="module")
def wheel() -> Path:
    path = os.environ.get("ALGID_WHEEL")
    if not path:
        pytest.skip("ALGID_WHEEL not set: CI sets it to the wheel tools/build_wheel.sh built")
    return Path(path).resolve()


def test_wheel_is_tagged_manylinux(wheel: Path) -> None:
    assert wheel.is_file(), wheel
    with zipfile.ZipFile(wheel) as zf:
        meta = next(n for n in zf.namelist() if n.endswith(".dist-info/WHEEL"))
        tags = [line.split(": ", 1)[1] for line in zf.read(meta).decode().splitlines() if line.startswith("Tag: ")]
    assert tags and all("manylinux_" in tag for tag in tags), tags
    assert "manylinux_" in wheel.name


def test_wheel_installs_and_runs_in_a_fresh_environment(wheel: Path, tmp_path: Path) -> None:
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=True).create(env_dir)
    python = env_dir / ("Scripts" if sys.platform == "win32" else "bin") / "python"
    install = subprocess.run(
        [str(python), "-m", "pip", "install", "--quiet", str(wheel)], capture_output=True, text=True, timeout=900
    )
    assert install.returncode == 0, install.stderr[-4000:]
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PATH"] = f"{python.parent}{os.pathsep}{env.get('PATH', '')}"
    probe = subprocess.run([str(python), "-c", _PROBE], capture_output=True, text=True, cwd=tmp_path, env=env)
    assert probe.returncode == 0, probe.stderr[-4000:]
    report = json.loads(probe.stdout.strip().splitlines()[-1])
    assert Path(report["file"]).is_relative_to(env_dir)
    assert report["version"] == algid.__version__
    assert report["estimates"] == pytest.approx([2.0, 3.0, 800.0], rel=1e-9)
    assert report["header"] is True
    assert report["cli"] and Path(report["cli"]).is_relative_to(env_dir)
    cli = subprocess.run([report["cli"], "identify", "--help"], capture_output=True, text=True, env=env)
    assert cli.returncode == 0 and "usage: algid identify" in cli.stdout
