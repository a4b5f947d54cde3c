"""Reprs: one line naming the class, size, sampling, state and validity, never whole arrays;
``_repr_html_``: the same fields as a table, and the estimates with their units."""

from __future__ import annotations

import html
import re
from types import SimpleNamespace

import numpy as np
import pytest

import algid
from algid.diagnosis.engine import diagnose
from algid.messages.display import html_table, number, parameter_rows, recording_fields
from algid.model.chain import TABLE1
from signals import multisine, simulate_chain


@pytest.fixture(scope="module")
def table1_recording() -> algid.Recording:
    t, a, u, _ = simulate_chain(TABLE1, multisine(3), 4.0)
    return algid.Recording(t=t, u=u, a=a)


def _fields(text: str) -> dict[str, str]:
    """``key=value`` pairs of a one-line repr (values without commas)."""
    return dict(re.findall(r"(\w+)=([^,)]+)", text))


def _html_rows(table: str) -> dict[str, str]:
    return {html.unescape(k): html.unescape(v) for k, v in re.findall(r"<th[^>]*>([^<]+)</th><td>([^<]*)</td>", table)}


def test_recording_shows_a_summary_not_its_arrays() -> None:
    T = 200_000
    t = np.arange(T) * 2e-4
    rec = algid.Recording(t=t, u=np.zeros((T, 2)), x=np.zeros((T, 2)) + 1e-3)
    text = repr(rec)
    assert "\n" not in text and len(text) < 200
    assert _fields(text) == {
        "n": "2",
        "samples": "200000",
        "duration_s": number(t[-1]),
        "dt_s": "0.0002",
        "signals": "u+x",
    }
    assert _html_rows(rec._repr_html_())["signals"] == "u+x"


@pytest.mark.parametrize("cls", [algid.ChainEstimator, algid.ContinuousEstimator])
def test_estimators_show_state_and_estimates(cls, table1_recording) -> None:
    rec = table1_recording
    est = cls(3, rec.dt)
    assert _fields(repr(est))["valid"] == "0/3 DOF"
    est.run(rec.a, rec.u)
    fields = _fields(repr(est))
    assert repr(est).startswith(f"{cls.__name__}(n=3, dt=0.001, boundary='fixed'")
    assert fields["valid"] == "3/3 DOF"
    table = est._repr_html_()
    assert _html_rows(table)["valid"] == "3/3 DOF"
    rows = re.findall(r"<tr><td>(\w+)</td><td>([^<]+)</td><td>([^<]*)</td><td>([^<]+)</td></tr>", table)
    values = np.concatenate([est.mass, est.damping, est.stiffness])
    assert [r[0] for r in rows] == est.names
    assert [r[1] for r in rows] == [number(v) for v in values]
    assert [r[3] for r in rows] == ["kg"] * 3 + ["N s/m"] * 3 + ["N/m"] * 4
    np.testing.assert_allclose([float(r[1]) for r in rows], np.r_[TABLE1.mass, TABLE1.damping, TABLE1.stiffness], 1e-3)


def test_identification_and_diagnosis_show_their_verdicts(table1_recording) -> None:
    res = algid.identify(table1_recording, replicates=3)
    text = repr(res)
    assert "\n" not in text
    assert text.startswith("Identification(n=3, boundary='fixed', estimator=")
    ok = sum(v.valid for v in res.verdicts)
    assert _fields(text)["valid"] == f"{ok}/10 parameters"
    assert f"<td>{number(res.sigma[0], 2)}</td>" in res._repr_html_()

    rec = table1_recording
    noisy = rec.a + 1e-3 * rec.a.std() * np.random.default_rng(0).standard_normal(rec.a.shape)
    d = diagnose(algid.Recording(t=rec.t, u=rec.u, a=noisy), effects=("cubic_stiffness",))
    text = repr(d)
    assert "\n" not in text and len(text) < 200
    assert _fields(text)["gap_before"] == number(d.gap_before, 4)
    assert _html_rows(d._repr_html_())["effect"] == repr(d.effect)


def test_declared_units_label_the_summary_and_the_estimates() -> None:
    """A recording in volts says so; estimates carry the units they are given (SI otherwise)."""
    volts = SimpleNamespace(
        n=1, t=np.arange(5.0), duration_s=4.0, dt=1.0, u=np.zeros((5, 1)), a=None, v=None, x=np.ones((5, 1)),
        units={"time": "s", "force": "V", "displacement": "V"}, is_si=lambda: False,
    )  # fmt: skip
    assert recording_fields(volts)["units"] == "time:s force:V displacement:V"
    assert "units" not in recording_fields(SimpleNamespace(**{**vars(volts), "is_si": lambda: True}))
    rows = parameter_rows(["m1", "c1", "k1"], [1.0, 2.0, 3.0], None, {"m": "V s^2/V", "c": "V s/V", "k": "V/V"})
    assert [r[3] for r in rows] == ["V s^2/V", "V s/V", "V/V"]
    assert [r[3] for r in parameter_rows(["k1"], [3.0])] == ["N/m"]
    assert "<td>V/V</td>" in html_table("X", {}, rows)
