"""``algid.identify`` judged by the diagnosis's test, and with effects (issue 35, items 0 and 2).

Records from the simulator: a 2-DOF chain under random forcing at 40 dB, linear or with a
cubic spring or dry friction, and the closed-loop positioning axis with Coulomb friction read
by its encoder. The truths are the simulated parameters."""

from __future__ import annotations

import json

import numpy as np
import pytest

import algid
from algid.diagnosis import diagnose
from algid.diagnosis.report import to_json
from algid.model.chain import Chain
from algid.recording import Recording
from algid.simulator import simulate
from algid.simulator.scenarios import positioning_axis

CHAIN = Chain([2.0, 1.0], [4.0, 2.0], [4800.0, 2000.0, 3000.0])
TRUTH = np.concatenate([CHAIN.mass, CHAIN.damping, CHAIN.stiffness])
CUBIC = {"name": "cubic_stiffness", "location": {"spring": 1}, "params": {"k_cubic": 3e7}}
FRICTION = {"name": "coulomb_friction", "location": {"dof": 2}, "params": {"force": 2.0}}


def _record(effects, seed: int, band_hz=None, duration_s: float = 20.0) -> Recording:
    from scipy.signal import butter, sosfiltfilt

    fs = 1000.0
    F = 20.0 * np.random.default_rng(seed).standard_normal((int(duration_s * fs), 2))
    if band_hz is not None:
        F = sosfiltfilt(butter(4, band_hz, btype="bandpass", fs=fs, output="sos"), F, axis=0)
    sim = simulate(CHAIN, F, duration_s, fs, effects=effects, noise_db=40, noise_on=("accel", "force"), seed=seed)
    return Recording(t=sim.t, u=sim.u, a=sim.a)


@pytest.mark.parametrize("effect, spec", [(CUBIC, "cubic_stiffness:1"), (FRICTION, "coulomb_friction:2")])
def test_a_biased_linear_fit_is_not_valid_and_the_effect_makes_it_right(effect, spec):
    rec = _record([effect], seed=0)
    linear = algid.identify(rec)
    assert not any(v.valid for v in linear.verdicts)
    assert {v.status for v in linear.verdicts} == {"model_misfit"}
    assert f"--effect {spec}" in linear.verdict("m1").reason
    assert linear.model_fit["explains_record"] is False and linear.model_fit["diagnosis"].startswith(spec[:8])

    fitted = algid.identify(rec, effects=[spec])
    assert fitted.valid and fitted.plan.estimator == "augmented"
    z = (fitted.theta - TRUTH) / fitted.sigma
    assert np.all(np.abs(z) < 5), z
    assert np.allclose(fitted.theta[:2], TRUTH[:2], rtol=0.01)
    (e,) = fitted.effects
    main = next(iter(effect["params"]))
    assert e["effect"] == effect["name"] and e["location"] == effect["location"] and e["valid"]
    assert e["params"][main] == pytest.approx(effect["params"][main], rel=0.03)
    assert abs(e["params"][main] - effect["params"][main]) < 5 * e["params_std"][main]


def test_one_linear_fit_for_one_record_whichever_command_prints_it():
    """On a record the linear chain does not explain, ``identify`` reports the diagnosis's
    linear fit: the same numbers as ``diagnose``'s linear model, each ``model_misfit``."""
    rec = _record([CUBIC], seed=1, duration_s=10.0)
    linear = algid.identify(rec)
    lm = to_json(diagnose(rec))["linear_model"]
    packed = np.array(lm["mass"] + lm["damping"] + lm["stiffness"], dtype=float)
    sigma = np.array(lm["sigma_mass"] + lm["sigma_damping"] + lm["sigma_stiffness"], dtype=float)
    np.testing.assert_allclose(linear.theta, packed, rtol=1e-12)
    np.testing.assert_allclose(linear.sigma, sigma, rtol=1e-12)
    assert linear.plan.estimator == "integral_equations"
    assert {v.status for v in linear.verdicts} == {"model_misfit"}


def test_a_linear_record_stays_valid_within_five_sigma():
    """Band-limited forcing (0.5-25 Hz), 20 s, 1 % noise: every estimate valid, and every
    valid one within 5 of its sigmas of the truth."""
    for seed in range(2):
        res = algid.identify(_record([], seed, band_hz=(0.5, 25.0)))
        assert res.valid and res.model_fit["explains_record"]
        assert np.all(np.abs((res.theta - TRUTH) / res.sigma) < 5)


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_the_positioning_axis_with_friction_in_one_call():
    """Encoder only, closed loop: mass within 1 %, viscous within 5 %, Coulomb level within
    3 % (the issue's targets), all valid, whether named or taken from the diagnosis."""
    sc = positioning_axis(
        seed=1, duration_s=20.0, effects=[{**FRICTION, "location": {"dof": 1}, "params": {"force": 6.0}}]
    )
    for effects in (["coulomb_friction:1"], ["auto"]):
        res = algid.identify(sc.recording, boundary="free", effects=effects)
        assert res.valid
        assert res.mass[0] == pytest.approx(5.0, rel=0.01)
        assert res.damping[0] == pytest.approx(25.0, rel=0.05)
        assert res.effects[0]["params"]["force"] == pytest.approx(6.0, rel=0.03)
    assert "diagnosis" in res.model_fit["source"]
    doc = res.to_json()
    (e,) = doc["effects"]
    assert set(e) >= {"effect", "location", "params", "params_std", "units", "valid"}
    assert e["units"]["force"] == "N"
    json.dumps(doc)
    assert "coulomb_friction (DOF 1) force" in res.summary()


def test_auto_on_a_linear_record_identifies_the_linear_chain():
    res = algid.identify(_record([], 1, band_hz=(0.5, 25.0)), effects="auto")
    assert res.plan.estimator != "augmented" and res.effects == []
    assert "reports 'none'" in res.model_fit["source"] and res.valid


@pytest.mark.parametrize(
    "specs, message",
    [
        (["coulom_friction:1"], "did you mean coulomb_friction"),
        (["coulomb_friction"], "needs a location on this 2-DOF chain"),
        (["coulomb_friction:3"], "no DOF 3"),
        (["cubic_stiffness:4"], "no spring 4"),
        (["coulomb_friction:x"], "must be a DOF number"),
        (["auto", "coulomb_friction:1"], "give it alone"),
        (["coulomb_friction:1", "coulomb_friction:1"], "twice"),
        (["coulomb_friction:1", "input_delay:1"], "can be fitted together"),
    ],
)
def test_effect_specs_are_checked(specs, message):
    rec = _record([], 0, duration_s=2.0)
    with pytest.raises(ValueError, match=message):
        algid.identify(rec, effects=specs)


def test_cli_effect_option(tmp_path, capsys):
    from algid.cli import main

    rec = _record([CUBIC], seed=1)
    path = tmp_path / "cubic.csv"
    np.savetxt(path, np.column_stack([rec.t, rec.u, rec.a]), delimiter=",", header="t,u1,u2,a1,a2", comments="")
    plots = tmp_path / "plots"
    args = ["identify", str(path), "--effect", "cubic_stiffness:1", "--json", "-", "--quiet", "--plots", str(plots)]
    assert main(args) == 0
    assert sorted(p.name for p in plots.iterdir()) == ["frf.png", "prediction.png"]
    doc = json.loads(capsys.readouterr().out)
    assert doc["valid"] and doc["estimator"] == "augmented"
    assert doc["effects"][0]["effect"] == "cubic_stiffness" and doc["effects"][0]["params"]["k_cubic"] > 0
    assert main(["identify", str(path), "--effect", "cubic:1", "--quiet"]) == 2
    assert "did you mean cubic_stiffness" in capsys.readouterr().err


def test_identify_and_diagnose_take_a_path_or_a_frame(tmp_path):
    """`algid.identify("recording.csv")` as a user first tries it (issue 37, item 5)."""
    from algid.diagnosis import diagnose

    rec = _record([], 0, duration_s=4.0)
    path = tmp_path / "rig.csv"
    np.savetxt(path, np.column_stack([rec.t, rec.u, rec.a]), delimiter=",", header="t,u1,u2,a1,a2", comments="")
    res = algid.identify(str(path))
    assert res.n == 2 and res.path == path
    assert algid.identify(rec.to_frame()).n == 2
    assert diagnose(path).P.n == 2
    with pytest.raises(TypeError, match="expected a Recording, a path or a pandas DataFrame, got int"):
        algid.identify(3)
