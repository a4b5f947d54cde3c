"""``algid diagnose`` on recordings as rigs write them (issue 16): encoder positions, velocities,
quasi-static devices, closed loops, hum, anti-alias filters, struck structures. Every record
is generated with its truth (``algid.simulator.scenarios``); the checks are on the diagnosis's answers."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import butter, lfilter

from algid.diagnosis import diagnose
from algid.diagnosis.report import to_json
from algid.model.chain import TABLE1, Chain
from algid.recording import Recording
from algid.simulator import simulate
from algid.simulator.scenarios import displacement_driven, impact_test, positioning_axis
from signals import FRICTION_AND_OFFSET, multisine


def _coulomb(force):
    return {"name": "coulomb_friction", "location": {"dof": 1}, "params": {"force": force}}


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_closed_loop_axis_from_encoder_counts_is_dry_friction():
    d = diagnose(positioning_axis(seed=2, effects=FRICTION_AND_OFFSET).recording)
    assert d.band.source == "force 1"  # not the differentiated encoder noise
    assert d.effect == "coulomb_friction" and d.params["force"] == pytest.approx(1.5, rel=0.3)
    js = to_json(d)
    assert js["gap_after_force"] < js["gap_before_force"] and js["gap_before"] / js["gap_after"] > 1.5


def test_quasi_static_device_is_solved_for_the_force():
    lin = diagnose(displacement_driven(seed=1).recording)
    assert lin.effect == "none" and lin.extra["form"] == "force"
    assert lin.extra["model"].verdict == "inertia_not_identifiable"
    assert lin.lin.theta[0][1] == pytest.approx(200.0, rel=0.02)  # damping
    assert lin.lin.theta[0][2] == pytest.approx(2e4, rel=0.01)  # spring
    d = diagnose(displacement_driven(seed=1, effects=[_coulomb(20.0)]).recording)
    assert d.effect == "coulomb_friction" and d.params["force"] == pytest.approx(20.0, rel=0.05)
    assert d.gap_before / d.gap_after > 10


def test_friction_with_backlash_is_reported_as_a_combination():
    backlash = {"name": "clearance", "location": {"spring": 1}, "params": {"gap": 2e-4, "k_contact": 2e4}}
    d = diagnose(displacement_driven(seed=0, stiffness_n_m=0.0, effects=[_coulomb(20.0), backlash]).recording)
    combo = to_json(d)["combination"]
    assert combo is not None
    parts = {p["effect"]: p for p in combo["effects"]}
    assert set(parts) == {"coulomb_friction", "clearance"}
    assert parts["coulomb_friction"]["params"]["force"] == pytest.approx(20.0, rel=0.05)
    assert parts["clearance"]["params"]["gap"] == pytest.approx(2e-4, rel=0.4)
    assert combo["gap_after"] < 0.5 * d.gap_after


@pytest.mark.parametrize(
    "effect,params,loc",
    [
        ("amplitude_damping", {"c_amp": 4e6}, {"spring": 1}),
        ("stribeck_friction", {"force": 8.0, "static": 24.0, "v_stribeck": 2e-3}, {"dof": 1}),
    ],
)
def test_new_effects_of_the_vocabulary(effect, params, loc):
    d = diagnose(displacement_driven(seed=3, effects=[{"name": effect, "location": loc, "params": params}]).recording)
    assert d.effect == effect and d.location == loc
    main = "c_amp" if effect == "amplitude_damping" else "force"
    assert d.params[main] == pytest.approx(params[main], rel=0.2)


def test_struck_structure_keeps_the_modes_outside_its_band_as_residual_modes():
    """A one-DOF hammer record of a five-mode structure: the chain holds the band of the lowest
    mode, the other four are reported as residual modes, not blamed on the chain."""
    sc = impact_test(seed=0)  # force and drive-point velocity, 10 kHz, five modes, four hits
    d = diagnose(sc.recording)
    tr = d.extra["transient"]
    found = np.array(tr["modes_in_band_hz"] + tr["residual_modes_hz"])
    assert len(tr["modes_in_band_hz"]) == 1 and len(tr["residual_modes_hz"]) == 4
    for f in sc.info["natural_hz"]:
        assert min(abs(found - f)) < 0.03 * f
    assert d.extra["model"].verdict != "no_force_response"


def _table1(noise_db=50.0, seed=4):
    r = simulate(TABLE1, multisine(3, seed=seed, offset_n=0.0), 10.0, 1000.0)
    rng = np.random.default_rng(seed)
    a = r.a + 10 ** (-noise_db / 20) * r.a.std(axis=0) * rng.standard_normal(r.a.shape)
    return r.t, r.u, a


def test_hum_and_anti_alias_filter_are_not_effects():
    t, u, a = _table1()
    hum = np.sin(2 * np.pi * 50.0 * t)[:, None] + 0.5 * np.sin(2 * np.pi * 150.0 * t + 1.0)[:, None]
    d = diagnose(Recording(t=t, u=u, a=a + 0.05 * a.std(axis=0) * hum))
    assert d.effect == "none" and {50.0, 150.0} <= set(d.extra["mains_hz"])
    bb, aa = butter(4, 0.6)  # a common anti-alias filter at 0.3 fs on every channel
    d = diagnose(Recording(t=t, u=lfilter(bb, aa, u, axis=0), a=lfilter(bb, aa, a, axis=0)))
    assert d.effect == "none" and d.extra["model"].verdict == "chain"


def test_velocity_record_with_dry_friction():
    chain = Chain([1.5, 2.0], [3.0, 4.0], [800.0, 600.0, 900.0])
    r = simulate(chain, multisine(2, seed=5, offset_n=0.0), 10.0, 1000.0, effects=[_coulomb(0.5)])
    v = r.v + 1e-3 * r.v.std(axis=0) * np.random.default_rng(5).standard_normal(r.v.shape)
    d = diagnose(Recording(t=r.t, u=r.u, v=v))  # a laser vibrometer on each mass
    assert (d.effect, d.location) == ("coulomb_friction", {"dof": 1})
    assert d.params["force"] == pytest.approx(0.5, rel=0.2)


def _slow_encoder_record(q_m: float, effects=(), seed: int = 0) -> Recording:
    """A 2-DOF chain under a 0.5-5 Hz multisine of about 10 mm RMS deflection, recorded by
    encoders of step ``q_m`` (positions only) and a force sensor at 60 dB."""
    chain = Chain([1.5, 2.5], [4.0, 6.0], [900.0, 700.0, 1100.0])
    rng = np.random.default_rng(seed)
    fs, T = 1000.0, 10000
    k = np.arange(5, 51)  # lines at 0.1 Hz steps over 0.5-5 Hz (period of the record)
    U = np.zeros((T // 2 + 1, 2), dtype=complex)
    U[k] = np.exp(2j * np.pi * rng.uniform(size=(k.size, 2)))
    u = np.fft.irfft(U, n=T, axis=0)
    u *= 5.0 / u.std(axis=0)
    r = simulate(
        chain,
        u,
        T / fs,
        fs,
        effects=list(effects),
        noise_db=60,
        noise_on=("force",),
        seed=seed,
        encoder_resolution_m=q_m,
    )
    return Recording(t=r.t, u=r.u, x=r.x_meas)


@pytest.mark.parametrize("q_m", [5e-6, 20e-6])
def test_linear_chain_in_encoder_counts_is_none(q_m):
    # the twice-differentiated quantisation noise leaks into the few in-band bins of the short
    # windows; the noise floor carries it through the analysis, so the gap sits at the floor
    rec = _slow_encoder_record(q_m)
    assert 5e-3 < float(np.max(rec.x.std(axis=0))) < 2e-2
    d = diagnose(rec)
    assert d.effect == "none"
    assert d.gap_before == pytest.approx(d.extra["noise_floor"], rel=0.25)


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_dry_friction_in_encoder_counts_is_still_found():
    d = diagnose(_slow_encoder_record(5e-6, [_coulomb(1.0)]))
    assert d.effect == "coulomb_friction" and d.location == {"dof": 1}
    assert d.params["force"] == pytest.approx(1.0, rel=0.2)


@pytest.mark.parametrize("q_m", [5e-6, 20e-6])
@pytest.mark.slow  # one of the longest cases of the fast tier
def test_closed_loop_axis_in_encoder_counts_is_none(q_m):
    # the counts enter the force through the controller and bias the linear fit into a
    # significant negative spring (tens to thousands of N/m); held at zero, the spring-less
    # chain still explains the record to its noise, so the fit is admissible and the
    # diagnosis none
    sc = positioning_axis(seed=0, encoder_m=q_m, stroke_m=0.01)
    d = diagnose(sc.recording)
    model = d.extra["model"]
    assert d.effect == "none" and model.verdict == "chain"
    k1, sigma = float(d.lin.theta[0][2]), float(model.evidence["parameters_sigma"][0][2])
    assert k1 < -3 * sigma  # the biased spring is there, and is not taken as evidence
    bound = model.evidence["at_bound"]
    assert not bound["needed"] and bound["gap_at_bound"] <= bound["noise_gap"]


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_closed_loop_axis_in_encoder_counts_with_dry_friction():
    u_rms = float(np.sqrt(np.mean(positioning_axis(seed=0, encoder_m=5e-6, stroke_m=0.01).recording.u ** 2)))
    effects = [{"name": "coulomb_friction", "location": {"dof": 1}, "params": {"force": 0.3 * u_rms}}]
    d = diagnose(positioning_axis(seed=0, encoder_m=5e-6, stroke_m=0.01, effects=effects).recording)
    assert (d.effect, d.location) == ("coulomb_friction", {"dof": 1})
    assert d.params["force"] == pytest.approx(0.3 * u_rms, rel=0.2)
