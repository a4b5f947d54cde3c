"""The multiplexed converter's channel skew: found, undone, and told apart from an input delay."""

from __future__ import annotations

import numpy as np
import pytest

from algid.diagnosis import diagnose
from algid.diagnosis.report import to_json, to_text
from algid.diagnosis.timing import ChainFit, channel_timing, realign, shifted
from algid.diagnosis.windows import window_length
from algid.model.chain import TABLE1
from algid.recording import Recording
from algid.simulator import simulate

#: A scan of six channels in this order (u1, u2, u3, a1, a2, a3): lateness k/6 of a sample.
SCAN = np.array([3, 5, 1, 0, 4, 2]) / 6.0


def skewed(rec: Recording, late: np.ndarray) -> Recording:
    """The record as a multiplexer writes it: channel c ``late[c]`` samples late."""
    return realign(rec, -np.asarray(late, dtype=float))


def _table1(noise_db: float | None) -> Recording:
    rng = np.random.default_rng(4)
    spectrum = np.fft.rfft(rng.standard_normal((8000, 3)), axis=0)
    f = np.fft.rfftfreq(8000, 1e-3)
    u = np.fft.irfft(spectrum * ((f > 0.5) & (f < 50.0))[:, None], 8000, axis=0)  # 0.5-50 Hz random forces
    res = simulate(TABLE1, 10.0 * u / u.std(axis=0), 8.0, 1000.0, noise_db=noise_db, seed=4)
    return Recording(t=res.t, u=res.u, a=res.a)


@pytest.fixture(scope="module")
def table1():
    return _table1(50.0)


def _timing(rec: Recording):
    skip = 100
    return channel_timing(rec, ChainFit("fixed", window_length(float(rec.dt), 1.0, rec.u.shape[0] - skip), skip))


def test_shift_is_exact_on_a_cubic_and_undoes_itself():
    k = np.arange(200, dtype=float)
    cubic = [1e-3, -0.2, 1.0, 0.5]
    late = 0.37
    np.testing.assert_allclose(shifted(np.polyval(cubic, k), late), np.polyval(cubic, k - late), rtol=1e-10, atol=1e-9)
    s = np.sin(2 * np.pi * 0.01 * k)
    np.testing.assert_allclose(shifted(shifted(s, late), -late)[10:-10], s[10:-10], atol=1e-6)


def test_a_converter_skew_is_found_exactly_without_noise():
    t = _timing(skewed(_table1(None), SCAN))
    assert t.realigned
    np.testing.assert_allclose(t.late, SCAN - np.median(SCAN), atol=1e-4)
    assert t.gap_after < 1e-5 * t.gap_before


def test_a_converter_skew_is_found_and_undone_at_50_db(table1):
    t = _timing(skewed(table1, SCAN))
    assert t.realigned
    np.testing.assert_allclose(t.late, SCAN - np.median(SCAN), atol=0.04)  # noise in the regressors biases it
    assert t.gap_after < 0.1 * t.gap_before


def test_a_record_on_time_is_left_alone(table1):
    t = _timing(table1)
    assert not t.realigned
    assert np.all(np.abs(t.late) < 0.02)


@pytest.mark.slow
def test_one_late_force_is_an_input_delay_not_a_skew(table1):
    late = np.zeros(6)
    late[1] = 0.6  # u2 sampled 0.6 dt late: the record of a 0.6 ms actuator lag
    t = _timing(skewed(table1, late))
    assert not t.realigned
    d = diagnose(skewed(table1, late))
    assert (d.effect, d.location) == ("input_delay", {"dof": 2})
    assert d.params["delay"] == pytest.approx(0.6e-3, rel=0.05)


@pytest.mark.slow
def test_the_diagnosis_of_a_skewed_linear_chain_is_none_and_says_what_it_realigned(table1):
    d = diagnose(skewed(table1, SCAN))
    assert d.effect == "none"
    assert d.extra["timing"]["realigned"]
    assert set(d.extra["timing"]["late_samples"]) == {"u1", "u2", "u3", "y1", "y2", "y3"}
    assert "channel skew (a multiplexed converter), undone before the fit" in to_text(d)
    assert to_json(d)["channel_timing"]["late_samples"]["u2"] == pytest.approx(SCAN[1] - np.median(SCAN), abs=0.04)


@pytest.mark.slow
def test_identify_realigns_a_skewed_record_and_its_estimates_are_valid(table1):
    from algid import identify

    res = identify(skewed(table1, SCAN))
    assert res.channel_timing["realigned"]
    assert "channel skew (a multiplexed converter), undone before the fit" in res.summary()
    assert res.to_json()["channel_timing"]["late_samples"]["y1"] == pytest.approx(SCAN[3] - np.median(SCAN), abs=0.04)
    truth = np.r_[TABLE1.mass, TABLE1.damping, TABLE1.stiffness]
    ok = [v.status == "ok" for v in res.verdicts]
    assert all(ok)
    assert np.all(np.abs(res.theta - truth) <= 5 * res.sigma)


@pytest.mark.slow
def test_a_skewed_record_with_an_effect_is_realigned_with_the_effect_in_the_fit():
    """An effect biases the latenesses the linear chain alone finds; fitted with the leading
    candidate's force columns, the timing finds the skew and the diagnosis the effect."""
    rng = np.random.default_rng(4)
    spectrum = np.fft.rfft(rng.standard_normal((8000, 3)), axis=0)
    f = np.fft.rfftfreq(8000, 1e-3)
    u = np.fft.irfft(spectrum * ((f > 0.5) & (f < 50.0))[:, None], 8000, axis=0)
    quadratic = {"name": "quadratic_damping", "location": {"dof": 2}, "params": {"c_quadratic": 30.0}}
    res = simulate(TABLE1, 10.0 * u / u.std(axis=0), 8.0, 1000.0, effects=[quadratic], noise_db=50.0, seed=4)
    rec = skewed(Recording(t=res.t, u=res.u, a=res.a), SCAN)
    d = diagnose(rec)
    timing = d.extra["timing"]
    assert d.effect == "quadratic_damping" and d.location == {"dof": 2}, d.effect
    assert d.params["c_quadratic"] == pytest.approx(30.0, rel=0.05)
    assert timing["realigned"]
    late = np.array(list(timing["late_samples"].values()))
    assert np.max(np.abs(late - (SCAN - np.median(SCAN)))) < 0.05
