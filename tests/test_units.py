"""Units: what ``algid diagnose`` and ``algid identify`` report, in their text, JSON and
figures, is in the units the recording declares (V, V/V, V/V^3 for a Silverbox-like
Duffing oscillator recorded in volts; N, N/m, kg for SI data).

Oracles: the unit of every effect parameter is checked against how the fitted value scales
when the forces and the motion are rescaled (a diagnosis is equivariant: a parameter of
unit force^a length^b must scale as alpha^a beta^b), and the SI labels against the table
of the candidates' module docstring.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import algid
import algid.cli
from algid.diagnosis import diagnose
from algid.diagnosis.equations import force_form
from algid.diagnosis.units import PARAMETER_DIMENSIONS, SI, diagnosis_units
from algid.model.chain import Chain
from algid.recording import Recording, load_recording, save_recording
from algid.recording.units import unit_label

#: A Duffing oscillator (one DOF between walls, hardening spring), sampled at 1 kHz.
DUFFING = Chain([2.0], [4.0], [800.0, 600.0])
K3 = 8e5
VOLTS = {"force": "V", "displacement": "V"}
#: An SI unit in a label: in brackets or after a number (``[N]``, ``[mm]``, ``1.5 N/m``), or m/s.
SI_WORD = re.compile(r"(?:\[|\d |\()(?:N|kg|mm|m)(?:[\]/ )^]|$)|m/s")


@pytest.fixture(scope="module")
def duffing():
    """(t, u, x, a): forces, displacements and accelerations of the Duffing oscillator
    under a multisine."""
    from algid.simulator import simulate

    T, fs = 4000, 1000.0
    rng = np.random.default_rng(0)
    lines = np.arange(1, int(50 * T / fs))
    spectrum = np.zeros(T // 2 + 1, complex)
    spectrum[lines] = np.exp(2j * np.pi * rng.uniform(size=lines.size))
    u = np.fft.irfft(spectrum, T)
    effect = {"name": "cubic_stiffness", "location": {"spring": 1}, "params": {"k_cubic": K3}}
    res = simulate(DUFFING, 10 * u[:, None] / u.std(), T / fs, fs, effects=[effect], noise_db=60, seed=4)
    return res.t, res.u, res.x, res.a


def _cli(capsys, *args):
    code = algid.cli.main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def _texts(fig) -> list[str]:
    """Every piece of text on a figure: title, axis labels, legend entries."""
    out = [t.get_text() for t in fig.texts]
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()]
        legend = ax.get_legend()
        out += [t.get_text() for t in legend.get_texts()] if legend is not None else []
    return [t for t in out if t]


# ---------------------------------------------------------------------------- the labels


def test_si_labels_are_those_of_the_candidates_table():
    assert SI == {
        "force": "N",
        "displacement": "m",
        "velocity": "m/s",
        "acceleration": "m/s^2",
        "m": "kg",
        "c": "N s/m",
        "k": "N/m",
        "static": "N",
        "excess": "N",
        "v_scale": "m/s",
        "v_stribeck": "m/s",
        "c_amp": "N s/m^2",
        "c_quadratic": "N s^2/m^2",
        "k_cubic": "N/m^3",
        "gap": "m",
        "k_contact": "N/m",
        "delay": "s",
        "bias": "m/s^2",
        "cutoff_hz": "Hz",
        "rel_change": "-",
    }


def test_labels_in_the_units_the_recording_declares():
    volts = diagnosis_units(VOLTS, "displacement")
    assert (volts["m"], volts["c"], volts["k"]) == ("V s^2/V", "V s/V", "V/V")
    assert (volts["k_cubic"], volts["gap"], volts["c_quadratic"], volts["bias"]) == ("V/V^3", "V", "V s^2/V^2", "V/s^2")
    # accelerations in V: a length is V s^2
    acc = diagnosis_units({"acceleration": "V"}, "acceleration")
    assert (acc["displacement"], acc["velocity"], acc["acceleration"]) == ("V s^2", "V s", "V")
    assert (acc["k_cubic"], acc["m"], acc["delay"]) == ("N/(V^3 s^6)", "N/V", "s")
    # a compound label stays one symbol; a unit alone is written as it is
    assert unit_label({"velocity": "mV/(m/s)"}, "velocity", length=-1) == "1/((mV/(m/s)) s)"
    assert unit_label({"velocity": "mV/(m/s)"}, "velocity", length=1, time=-1) == "mV/(m/s)"


@pytest.mark.parametrize("motion", ["displacement", "acceleration"])
def test_effect_parameters_scale_as_their_units_say(duffing, motion):
    """Forces in V (alpha V per N) and motion in V (beta V per metre, or per m/s^2): every
    fitted parameter of unit force^a length^b is alpha^a beta^b times its SI value."""
    t, u, x, a = duffing
    y, key = (x, "x") if motion == "displacement" else (a, "a")
    alpha, beta = 0.1, 20.0
    si = diagnose(Recording(t=t, u=u, **{key: y}))
    volts = diagnose(Recording(t=t, u=alpha * u, **{key: beta * y}, units={"force": "V", motion: "V"}))
    assert volts.effect == si.effect == "cubic_stiffness"
    fitted = {s.fit.effect: s.fit.params for s in si.ranking}
    checked = set()
    for s in volts.ranking:
        for name, value in s.fit.params.items():
            a, b, _ = PARAMETER_DIMENSIONS.get(name, (0, 0, 0))
            if np.isfinite(value):
                assert value == pytest.approx(fitted[s.fit.effect][name] * alpha**a * beta**b, rel=1e-6), name
                checked.add(name)
            assert name in volts.units
    assert checked >= {
        "k_cubic",
        "gap",
        "k_contact",
        "c_amp",
        "c_quadratic",
        "force",
        "v_scale",
        "bias",
        "delay",
        "cutoff_hz",
    }
    m, c, k = volts.lin.theta[0]
    np.testing.assert_allclose([m, c, k], np.array(si.lin.theta[0]) * alpha / beta, rtol=1e-9)


# ---------------------------------------------------------------------------- diagnose


@pytest.mark.parametrize("declared", ["volts", "si"])
def test_diagnose_report_json_and_figures_in_the_recording_units(tmp_path, capsys, duffing, declared):
    from algid.plotting.diagnosis import FIGURES

    t, u, x, _ = duffing
    units = VOLTS if declared == "volts" else {}
    path = save_recording(tmp_path / "duffing.csv", Recording(t=t, u=u, x=x, units=units))
    out = tmp_path / "d.json"
    code, stdout, stderr = _cli(capsys, "diagnose", path, "--json", out, "--plots", tmp_path / "figs")
    assert code == 0, stderr
    doc = json.loads(out.read_text())
    assert doc["effect"] == "cubic_stiffness" and doc["params"]["k_cubic"] == pytest.approx(K3, rel=0.02)
    expected = diagnosis_units(units, "displacement")
    assert doc["units"] == expected and doc["recording_notes"] == []
    assert doc["recording_units"] == {"time": "s", "force": "N", "displacement": "m"} | units
    k3 = "V/V^3" if units else "N/m^3"
    assert doc["units"]["k_cubic"] == k3 and re.search(rf"fitted: k_cubic = \S+ \+- \S+ {re.escape(k3)}\n", stdout)
    header = "m [V s^2/V], c [V s/V], springs [V/V]" if units else "m [kg], c [N s/m], springs [N/m]"
    assert f"Linear chain, the windowed equation-error fit ({header}):\n" in stdout
    assert sorted(f.name for f in (tmp_path / "figs").iterdir()) == sorted(FIGURES)
    d = diagnose(load_recording(path))
    figures = {name: _texts(make(d)) for name, make in FIGURES.items()}
    target = expected["force"] if force_form(d.P, 0) else expected["acceleration"]
    assert f"DOF 1\n[{target}]" in figures["residuals_time.png"]
    assert f"DOF 1\n[({target})^2/Hz]" in figures["residuals_spectrum.png"]
    assert f"DOF 1\n[{target}]" in figures["prediction.png"]
    restoring, damping = figures["restoring_force.png"], figures["damping_force.png"]
    force = expected["force"]
    assert {f"restoring force [{force}]", f"unexplained force [{force}]"} <= set(restoring)
    assert ("deformation [V]" if units else "deformation [mm]") in restoring
    assert any(text.startswith("linear k = ") and text.endswith(f" {expected['k']}") for text in restoring)
    assert {f"damping force [{force}]", f"velocity [{expected['velocity']}]"} <= set(damping)
    assert any(text.endswith(f" {expected['c']}") for text in damping)
    legend = figures["window_parameters.png"]
    assert {text.split(" ", 2)[2] for text in legend if text[:2] in ("m ", "c ", "k1")} == {
        f"{expected[p]})" for p in "mck"
    }
    words = [text for texts in figures.values() for text in texts if SI_WORD.search(text)]
    assert (words == []) if units else words, words


def test_silverbox_read_as_volts_is_diagnosed_in_volts(tmp_path, capsys, shared_data):
    """The measured Silverbox (V1 drives, V2 is the displacement, both in volts; no time
    column), its first 40 000 samples (the "arrow") through a column mapping."""
    with np.load(shared_data / "silverbox" / "SNLS80mV.npz") as z:
        arrow = {name: z[name][:40000] for name in ("V1_input_V", "V2_output_V")}
    path = tmp_path / "arrow.npz"
    np.savez(path, **arrow)
    out = tmp_path / "d.json"
    mapping = ("--force", "V1_input_V", "--displacement", "V2_output_V", "--units", "force=V,displacement=V")
    code, stdout, stderr = _cli(capsys, "diagnose", path, "--json", out, *mapping, "--rate", 1e7 / 2**14)
    assert code == 0, stderr
    doc = json.loads(out.read_text())
    assert (doc["effect"], doc["location"]) == ("cubic_stiffness", {"spring": 1})
    assert 3.0 < doc["params"]["k_cubic"] < 4.0  # PROVENANCE.md: k3 ~ 3.5 V/V^3 (hardening)
    assert (doc["units"]["k_cubic"], doc["units"]["k"], doc["units"]["m"]) == ("V/V^3", "V/V", "V s^2/V")
    assert doc["recording_units"] == {"time": "s", "force": "V", "displacement": "V"}
    assert doc["recording_notes"] == ["no time column: t = k * 0.0016384 s"]
    assert "springs [V/V]" in stdout and re.search(r"fitted: k_cubic = 3\.\d+ \+- \S+ V/V\^3\n", stdout)


# ---------------------------------------------------------------------------- identify


def test_identify_plots_and_table_in_the_recording_units(tmp_path, capsys):
    """A linear oscillator recorded in volts (alpha V per N, beta V per metre): the estimates
    are alpha / beta times the SI ones and say so in the table, the JSON and the figure."""
    from algid.plotting.identify import estimates_figure
    from signals import multisine, simulate_chain

    t, _, u, x = simulate_chain(DUFFING, multisine(1), 0.5)
    alpha, beta = 0.1, 20.0
    si = algid.identify(Recording(t=t, u=u, x=x))
    path = save_recording(tmp_path / "volts.csv", Recording(t=t, u=alpha * u, x=beta * x, units=VOLTS))
    out = tmp_path / "est.json"
    code, stdout, stderr = _cli(capsys, "identify", path, "--json", out, "--plots", tmp_path / "figs")
    assert code == 0, stderr
    doc = json.loads(out.read_text())
    assert doc["units"] == {"m": "V s^2/V", "c": "V s/V", "k": "V/V"}
    np.testing.assert_allclose(doc["mass"] + doc["damping"], np.r_[si.mass, si.damping] * alpha / beta, rtol=1e-6)
    assert (tmp_path / "figs" / "estimates.png").is_file()
    assert "V s^2/V" in stdout and "kg" not in stdout and "N/m" not in stdout
    volts = algid.identify(load_recording(path))
    legend = _texts(estimates_figure(volts))
    for name, unit in (("m1", "V s^2/V"), ("c1", "V s/V"), ("k1", "V/V")):
        assert any(re.fullmatch(rf"{name} = \S+ {re.escape(unit)}", text) for text in legend), legend
    assert not [text for text in legend if SI_WORD.search(text)]
    si_legend = _texts(estimates_figure(si))
    assert any(re.fullmatch(r"m1 = \S+ kg", text) for text in si_legend), si_legend
    assert any(re.fullmatch(r"k1 = \S+ N/m", text) for text in si_legend), si_legend
