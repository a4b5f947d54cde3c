"""Command-line conventions: optional ``--json`` (``-`` for stdout), plain-text help, one
progress helper that is silent off a terminal, and the modal table of ``algid identify``."""

from __future__ import annotations

import io
import json
import re
import subprocess
import sys

import numpy as np
import pytest

from algid.model.chain import TABLE1, Chain
from algid.recording import Recording, save_recording
from signals import multisine, simulate_chain

PNG = b"\x89PNG\r\n\x1a\n"


def _algid(*args, timeout=180):
    return subprocess.run(
        [sys.executable, "-m", "algid.cli", *map(str, args)], capture_output=True, text=True, timeout=timeout
    )


@pytest.fixture(scope="module")
def table1_csv(tmp_path_factory):
    t, a, u, _ = simulate_chain(TABLE1, multisine(3), 0.3)
    return save_recording(tmp_path_factory.mktemp("rec") / "table1.csv", Recording(t=t, u=u, a=a))


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_is_silent_off_a_terminal_and_when_quiet():
    from algid.messages.progress import Progress

    log = io.StringIO()
    p = Progress("identify", stream=log)
    for stage in ("window length", "uncertainty"):
        for fraction in np.linspace(0, 1, 11):
            p(stage, fraction)
    p.message("candidate 1/3: cubic_stiffness at spring 3")
    p.fraction("simulating")(0.5)
    p.close()
    assert log.getvalue() == ""
    quiet = _Terminal()
    q = Progress("identify", quiet=True, stream=quiet)
    q("slow", 0.5)
    q.close()
    assert quiet.getvalue() == ""


def test_progress_on_a_terminal_is_one_bar_per_stage_cleared_at_the_end():
    from algid.messages.progress import Progress

    term = _Terminal()
    p = Progress("identify", stream=term)
    p("window length", 0.0)
    p("window length", 0.42)
    assert "[identify] window length" in term.getvalue() and " 42%" in term.getvalue()
    p.message("locating the gap")
    assert "[identify] locating the gap" in term.getvalue()
    p.close()
    assert re.search(r"\r +\r$", term.getvalue())  # the line blanked and the cursor back at its start


@pytest.mark.parametrize("command", ["", "demo", "identify", "diagnose"])
def test_help_is_plain_text(command):
    proc = _algid(*([command] if command else []), "--help", timeout=60)
    assert proc.returncode == 0, proc.stderr
    for markup in ("``", ":class:", ":func:", ":mod:", ":data:", "**", ".. "):
        assert markup not in proc.stdout, (markup, proc.stdout)
    if command in ("identify", "diagnose"):
        assert "--json -" in proc.stdout and "stdout" in proc.stdout


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_identify_json_to_stdout_summary_to_stderr(table1_csv):
    plain = _algid("identify", table1_csv)
    assert plain.returncode == 0, plain.stderr
    assert "m1 =" in plain.stdout and "modes" in plain.stdout and "zeta" in plain.stdout
    piped = _algid("identify", table1_csv, "--json", "-")
    assert piped.returncode == 0, piped.stderr
    doc = json.loads(piped.stdout)
    assert doc["n"] == 3 and len(doc["modes"]) == 3
    assert "m1 =" in piped.stderr and "zeta" in piped.stderr
    quiet = _algid("identify", table1_csv, "--json", "-", "--quiet")
    assert json.loads(quiet.stdout)["modes"] == doc["modes"] and quiet.stderr == ""


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_identify_modes_are_those_of_the_estimated_chain_and_round_trip(table1_csv, tmp_path):
    out = tmp_path / "est.json"
    proc = _algid("identify", table1_csv, "--json", out, "--plots", tmp_path / "figs")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(out.read_text())
    chain = Chain.from_json(out)
    np.testing.assert_allclose(chain.mass, doc["mass"], rtol=0)
    np.testing.assert_allclose(chain.stiffness, doc["stiffness"], rtol=0)
    truth = TABLE1.modes()
    f = [m["frequency_hz"] for m in doc["modes"]]
    np.testing.assert_allclose(f, truth.frequencies_hz, rtol=1e-6)  # noise-free: the estimates are exact
    np.testing.assert_allclose([m["damping_ratio"] for m in doc["modes"]], truth.damping_ratios, rtol=1e-5)
    assert all(m["sigma_frequency_hz"] is not None and m["sigma_frequency_hz"] >= 0 for m in doc["modes"])
    # the printed table carries the same numbers
    table = proc.stdout[proc.stdout.index("modes") :]
    printed = [float(x) for x in re.findall(r"^\s+\d+\s+([\d.]+)", table, flags=re.M)]
    np.testing.assert_allclose(printed, f, rtol=1e-4)
    for name in ("estimates.png", "frf.png"):
        assert (tmp_path / "figs" / name).read_bytes()[:8] == PNG


@pytest.mark.parametrize("boundary", ["fixed", "free"])
def test_from_json_of_n1_and_free_end_results(tmp_path, boundary):
    chain = (
        Chain([2.0], [3.0], [800.0, 400.0])
        if boundary == "fixed"
        else Chain([2.0, 1.0], [3.0, 1.0], [800, 400, 0], "free")
    )
    t, a, u, _ = simulate_chain(chain, multisine(chain.n, seed=4), 0.5)
    path = save_recording(tmp_path / "rec.csv", Recording(t=t, u=u, a=a))
    out = tmp_path / "est.json"
    proc = _algid("identify", path, "--json", out, "--boundary", boundary, "--quiet")
    assert proc.returncode == 0, proc.stderr
    back = Chain.from_json(out)
    for got, want in zip(back.matrices(), chain.matrices()):
        np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-9)
    doc = json.loads(out.read_text())
    np.testing.assert_allclose([m["frequency_hz"] for m in doc["modes"]], chain.modes().frequencies_hz, rtol=1e-4)


def test_identify_without_a_chain_has_no_modes_and_says_why():
    from algid.identification.result import Identification

    class Fake:  # just what the modal layer reads of an Identification
        n, boundary = 2, "fixed"
        theta = np.array([1.0, np.nan, 2.0, 2.0, 100.0, 100.0, 100.0])
        sigma = np.full(7, 0.1)
        modes = Identification.modes

    modal, why = Fake().modes()
    assert modal is None and why == "no estimate of m2: a chain needs every parameter"


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_diagnose_json_is_optional_and_can_go_to_stdout(tmp_path):
    t, a, u, _ = simulate_chain(TABLE1, multisine(3), 2.0)
    path = save_recording(tmp_path / "rec.csv", Recording(t=t, u=u, a=a))
    plain = _algid("diagnose", path)
    assert plain.returncode == 0, plain.stderr
    assert "signal band" in plain.stdout and "\r" not in plain.stderr
    piped = _algid("diagnose", path, "--json", "-")
    assert piped.returncode == 0, piped.stderr
    assert "effect" in json.loads(piped.stdout) and "signal band" in piped.stderr


def test_demo_writes_no_carriage_returns_into_a_log(tmp_path):
    pytest.importorskip("algid._core")
    proc = _algid("demo", "--n", "1", "--duration", "0.6", "--out", tmp_path, "--no-plots")
    assert proc.returncode == 0, proc.stderr
    assert "\r" not in proc.stderr and "\r" not in proc.stdout
    assert proc.stderr == ""  # progress is for terminals; a log gets only what the demo says on purpose


def test_from_a_pandas_csv_to_modes_and_frf_in_one_command(tmp_path):
    # the path: a CSV as pandas writes it (index column, `time`, units in the header) to a
    # modal table with damping ratios and a model-vs-measured FRF plot, in one command
    pd = pytest.importorskip("pandas")
    from algid.simulator import simulate

    chain = Chain(np.array([2.0]), np.array([6.0]), np.array([2000.0, 0.0]))  # f_n 5.03 Hz, zeta 0.0335
    rng = np.random.default_rng(3)
    r = simulate(chain, 10 * rng.standard_normal((10000, 1)), 10.0, 1000.0, noise_db=50, noise_on=("accel", "force"))
    frame = pd.DataFrame({"time [s]": r.t, "u1 [N]": r.u[:, 0], "a1 [m/s^2]": r.a[:, 0]})
    frame.to_csv(tmp_path / "rig.csv")  # with pandas' index column
    proc = _algid("identify", tmp_path / "rig.csv", "--plots", tmp_path / "plots", "--json", tmp_path / "r.json")
    assert proc.returncode == 0, proc.stderr
    mode = json.loads((tmp_path / "r.json").read_text())["modes"][0]
    assert mode["frequency_hz"] == pytest.approx(np.sqrt(2000.0 / 2.0) / (2 * np.pi), rel=0.01)
    assert mode["damping_ratio"] == pytest.approx(6.0 / (2 * np.sqrt(2000.0 * 2.0)), rel=0.1)
    assert re.search(r"damping ratio|zeta", proc.stdout, re.I), proc.stdout
    assert (tmp_path / "plots" / "frf.png").read_bytes()[:8] == PNG
