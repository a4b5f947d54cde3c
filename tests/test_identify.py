"""``algid identify``: final estimates, history CSV, and one-line errors with exit code 2."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from algid.model.chain import TABLE1, Chain
from algid.recording import Recording, save_recording
from signals import FRICTION_AND_OFFSET, multisine, relative_errors, simulate_chain


def _write(path, t, u, a=None, x=None):
    save_recording(path, Recording(t=t, u=u, a=a, x=x))
    return path


@pytest.fixture(scope="module")
def table1_csv(tmp_path_factory):
    t, a, u, x = simulate_chain(TABLE1, multisine(3), 0.3)
    return _write(tmp_path_factory.mktemp("rec") / "table1.csv", t, u, a=a), (t, a, u, x)


def _identify(*args):
    return subprocess.run(
        [sys.executable, "-m", "algid.cli", "identify", *map(str, args)], capture_output=True, text=True, timeout=120
    )


def test_identify_table1(table1_csv, tmp_path):
    path, _ = table1_csv
    out, trace = tmp_path / "est.json", tmp_path / "trace.csv"
    proc = _identify(path, "--json", out, "--trace", trace)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(out.read_text())
    assert doc["n"] == 3 and doc["valid"] is True and doc["estimator"] == "window"
    assert "clean record" in doc["estimator_reason"]
    np.testing.assert_allclose(doc["mass"], TABLE1.mass, rtol=1e-6)
    np.testing.assert_allclose(doc["damping"], TABLE1.damping, rtol=1e-6)
    np.testing.assert_allclose(doc["stiffness"], TABLE1.stiffness, rtol=1e-6)
    assert all(s is not None and s >= 0 for s in doc["sigma_mass"] + doc["sigma_damping"] + doc["sigma_stiffness"])
    assert [p["status"] for p in doc["parameters"]] == ["ok"] * 10
    lines = trace.read_text().splitlines()
    names = "m1,m2,m3,c1,c2,c3,k1,k2,k3,k4"
    assert lines[0] == "t," + names + "," + ",".join("sigma_" + k for k in names.split(",")) + ",valid"
    assert len(lines) == 302  # one row per sample of the single window
    last = np.array(lines[-1].split(","), dtype=float)
    np.testing.assert_allclose(last[1:4], TABLE1.mass, rtol=1e-6)
    assert last[-1] == 1.0
    assert "m1 =" in proc.stdout and "window estimator" in proc.stdout


def test_identify_from_displacements_and_n1(tmp_path):
    chain = Chain([2.0], [3.0], [800.0, 400.0])
    t, a, u, x = simulate_chain(chain, multisine(1, seed=4), 0.5)
    path = _write(tmp_path / "x_only.npz", t, u, x=x)
    out, trace = tmp_path / "est.json", tmp_path / "trace.csv"
    proc = _identify(path, "--json", out, "--trace", trace)
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(out.read_text())
    assert doc["stiffness"][1] is None  # only k1 + k2 is identifiable, reported in k1
    assert doc["stiffness"][0] == pytest.approx(1200.0, rel=1e-3)
    assert doc["mass"][0] == pytest.approx(2.0, rel=1e-3)
    assert doc["parameters"][3]["status"] == "not_separable" and doc["valid"] is True
    assert trace.read_text().splitlines()[-1].split(",")[4] == ""  # k2 empty


def test_identify_free_end(tmp_path):
    chain = Chain.random(2, np.random.default_rng(3), boundary="free")
    t, a, u, _ = simulate_chain(chain, multisine(2, seed=5), 0.3)
    out = tmp_path / "est.json"
    proc = _identify(_write(tmp_path / "free.csv", t, u, a=a), "--json", out, "--boundary", "free")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(out.read_text())
    assert doc["stiffness"][2] == 0.0 and doc["parameters"][6]["status"] == "known"
    np.testing.assert_allclose(doc["stiffness"][:2], chain.stiffness[:2], rtol=1e-6)


def test_invalid_estimates_carry_reasons_on_stderr_and_in_json(tmp_path):
    from algid.simulator.scenarios import positioning_axis

    sc = positioning_axis(seed=5, duration_s=12.0, effects=FRICTION_AND_OFFSET)
    out = tmp_path / "axis.json"
    proc = _identify(save_recording(tmp_path / "axis.npz", sc.recording), "--json", out, "--replicates", "4")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(out.read_text())
    assert doc["valid"] is False and doc["estimator"] == "integral_equations"  # the diagnosis's linear fit
    bad = [p for p in doc["parameters"] if not p["valid"]]
    assert bad and all(p["reason"] for p in bad)
    assert any("algid diagnose" in line for line in proc.stderr.splitlines())
    assert all(line.startswith("algid identify: ") for line in proc.stderr.splitlines() if line.strip())


def test_nothing_identifiable_exits_3(tmp_path):
    T = 3000
    t = np.arange(T) * 1e-3
    rng = np.random.default_rng(6)
    path = _write(tmp_path / "unforced.csv", t, np.zeros((T, 2)), a=rng.standard_normal((T, 2)))
    proc = _identify(path)  # --json is optional
    assert proc.returncode == 3, proc.stderr
    assert "nothing in this recording is identifiable" in proc.stderr
    assert "no force on DOF 1" in proc.stderr


def test_estimator_override_and_bad_options(table1_csv, tmp_path):
    path, _ = table1_csv
    out = tmp_path / "c.json"
    proc = _identify(path, "--json", out, "--estimator", "continuous", "--replicates", "2", "--quiet")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(out.read_text())
    assert doc["estimator"] == "continuous" and doc["estimator_reason"] == "requested (--estimator)"
    assert proc.stdout == ""
    proc = _identify(path, "--replicates", "1")
    assert proc.returncode == 2 and "replicates" in proc.stderr
    proc = _identify(path, "--json", tmp_path / "no" / "such" / "dir.json")
    assert proc.returncode == 2 and "does not exist" in proc.stderr


def _rows(T=12, dt=1e-3):
    return [[k * dt, 1.0 + k, 2.0 - k] for k in range(T)]


def _csv(header, rows):
    return header + "\n" + "\n".join(",".join(repr(v) for v in r) for r in rows) + "\n"


def _malformed():
    rows = _rows()
    nonuniform = [list(r) for r in rows]
    nonuniform[5][0] += 4e-4
    decreasing = [list(r) for r in rows]
    decreasing[3][0], decreasing[4][0] = decreasing[4][0], decreasing[3][0]
    with_nan = [list(r) for r in rows]
    with_nan[6][0] = float("nan")  # a timestamp: a signal's missing samples are bridged
    ragged = _csv("t,u1,a1", rows).splitlines()
    ragged[4] = ",".join(ragged[4].split(",")[:2])
    return [
        (_csv("t,u1,a2", rows), "mismatched n"),
        (
            _csv("t,u1,q1", rows),
            "missing columns a1..a1 (or velocities v1..v1, or displacements x1..x1) (columns not recognised: 'q1')",
        ),
        (_csv("t,u1", [r[:2] for r in rows]), "missing columns"),
        (_csv("t,u1,a1", nonuniform), "uniform"),
        (_csv("t,u1,a1", decreasing), "increasing"),
        (_csv("t,u1,a1", with_nan), "column t has NaN"),
        ("\n".join(ragged) + "\n", "row"),
    ]


@pytest.mark.parametrize("content,needle", _malformed())
def test_malformed_files_one_line_exit_2(tmp_path, content, needle):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    proc = _identify(path, "--json", tmp_path / "o.json")
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and needle.lower() in lines[0].lower(), proc.stderr


def test_missing_file(tmp_path):
    proc = _identify(tmp_path / "nope.csv", "--json", tmp_path / "o.json")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr


@pytest.mark.parametrize("n", [11, 30])
def test_any_chain_size(tmp_path, n):
    """Sizes without a fixed-size instantiation are identified like the others."""
    chain = Chain.random(n, np.random.default_rng(n))
    t, a, u, _ = simulate_chain(chain, multisine(n, seed=n), 0.3)
    path = _write(tmp_path / f"n{n}.npz", t, u, a=a)
    proc = _identify(path, "--json", tmp_path / "o.json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads((tmp_path / "o.json").read_text())
    assert doc["n"] == n and doc["valid"] is True
    err = relative_errors(chain, np.array(doc["mass"]), np.array(doc["damping"]), np.array(doc["stiffness"]))
    assert err.max() < 1e-4


def test_plots_write_the_estimate_histories(table1_csv, tmp_path):
    path, _ = table1_csv
    proc = _identify(path, "--plots", tmp_path / "figs", "--quiet")
    assert proc.returncode == 0, proc.stderr
    png = tmp_path / "figs" / "estimates.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
