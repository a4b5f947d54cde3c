"""algid.identify: the estimator chosen from the recording, uncertainties from surrogates,
and verdicts that never call an impossible or undetermined estimate valid."""

from __future__ import annotations

import numpy as np
import pytest

import algid
from algid.identification.motion import Motion, band_limited_motion, chain_forces, equation_error_fit
from algid.identification.plan import make_plan, natural_frequencies_hz
from algid.identification.surrogate import replicate_signals
from algid.identification.verdicts import judge
from algid.model.chain import TABLE1, Chain
from algid.recording import Recording, second_derivative
from algid.recording.noise import analyse
from algid.simulator import simulate
from algid.simulator.scenarios import displacement_driven, positioning_axis
from signals import FRICTION_AND_OFFSET, multisine, relative_errors, simulate_chain

DT = 1e-3
# ---- surrogates ----------------------------------------------------------------------------


def _sines(T, freqs, amps, dt=DT):
    t = np.arange(T) * dt
    w = 2 * np.pi * np.asarray(freqs)
    x = (amps * np.sin(np.outer(t, w) + 0.3)).sum(axis=1)
    v = (amps * w * np.cos(np.outer(t, w) + 0.3)).sum(axis=1)
    a = -(amps * w**2 * np.sin(np.outer(t, w) + 0.3)).sum(axis=1)
    return x, v, a


def test_surrogate_motion_from_displacements_is_exactly_differentiated():
    T = 4000
    x, v, a = _sines(T, [1.5, 7.0, 19.0], [1e-2, 1e-3, 2e-4])
    x = x + 0.02 + 0.003 * np.arange(T) * DT  # an offset and a drift: the line the FFT must not see
    mo = band_limited_motion(x[:, None], "displacement", DT, 100.0)
    inner = slice(200, T - 200)  # the periodic extension's seam touches the ends only
    np.testing.assert_allclose(mo.a[inner, 0], a[inner], atol=2e-3 * np.abs(a).max())
    np.testing.assert_allclose(mo.v[inner, 0], v[inner] + 0.003, atol=2e-3 * np.abs(v).max())
    np.testing.assert_allclose(second_derivative(mo.x, DT, 7)[inner], mo.a[inner], rtol=0, atol=1e-6 * np.abs(a).max())


def test_surrogate_motion_from_accelerations_integrates_consistently():
    T = 5000
    _, _, a = _sines(T, [3.0, 11.0], [1e-3, 1e-4])
    mo = band_limited_motion(a[:, None], "acceleration", DT, 50.0)
    inner = slice(300, T - 300)
    np.testing.assert_allclose(mo.a[inner, 0], a[inner], atol=5e-3 * np.abs(a).max())
    # x'' = a to the differentiation rule's accuracy, everywhere (the surrogate is periodic)
    np.testing.assert_allclose(second_derivative(mo.x, DT, 7)[inner], mo.a[inner], atol=1e-6 * np.abs(a).max())


def test_chain_forces_are_eq1_with_the_chain_matrices():
    rng = np.random.default_rng(0)
    mo = Motion(*(rng.standard_normal((50, 3)) for _ in range(3)))
    for chain in (TABLE1, Chain.random(3, rng, boundary="free")):
        M, C, K = chain.matrices()
        u = chain_forces(chain.identifiable(), 3, chain.boundary, mo)
        np.testing.assert_allclose(u, mo.a @ M + mo.v @ C + mo.x @ K.T, rtol=1e-12)
    one = Chain([2.0], [3.0], [500.0, 300.0])
    mo1 = Motion(mo.x[:, :1], mo.v[:, :1], mo.a[:, :1])
    np.testing.assert_allclose(
        chain_forces(one.identifiable(), 1, "fixed", mo1)[:, 0],
        2.0 * mo1.a[:, 0] + 3.0 * mo1.v[:, 0] + 800.0 * mo1.x[:, 0],
    )


def _first_look(chain, u, fs, noise_db, seed=1):
    T = u.shape[0] / fs
    r = simulate(chain, u, T, fs, noise_db=noise_db, noise_on=("accel", "force"), seed=seed)
    return equation_error_fit(r.u, r.a, analyse(r.u, r.a, 1 / fs), chain.boundary)


@pytest.mark.parametrize("chain", [TABLE1, Chain.random(3, np.random.default_rng(7), boundary="free")])
def test_first_look_is_eq1_on_a_noise_free_multisine(chain):
    fs, T = 1000.0, 10.0
    t = np.arange(int(T * fs)) / fs
    u = np.stack([np.sin(2 * np.pi * (1.3 + i) * t) + 0.5 * np.sin(2 * np.pi * (4.4 + 3 * i) * t) for i in range(3)], 1)
    theta = _first_look(chain, 10 * u, fs, None)
    truth = chain.identifiable()
    np.testing.assert_allclose(
        theta[np.isfinite(truth) & (truth != 0)], truth[np.isfinite(truth) & (truth != 0)], rtol=2e-3
    )


@pytest.mark.parametrize("T", [10.0, 60.0])
def test_first_look_under_white_forcing_is_not_pulled_by_the_integrated_noise(T):
    # white to the Nyquist rate: thousands of bins below the first mode, where the doubly
    # integrated acceleration noise dwarfs the motion; unweighted, the springs came out 3-30x low
    fs = 1000.0
    u = 10 * np.random.default_rng(0).standard_normal((int(T * fs), 3))
    theta = _first_look(TABLE1, u, fs, 40.0)
    err = np.abs(theta / TABLE1.identifiable() - 1)
    assert err[:3].max() < 0.01 and err[6:].max() < 0.01 and err[3:6].max() < 0.05
    fn = natural_frequencies_hz(theta, 3, "fixed")
    np.testing.assert_allclose(fn, natural_frequencies_hz(TABLE1.identifiable(), 3, "fixed"), rtol=0.005)


def _one_force(chain, dof, motion="acceleration", T=20.0, fs=1000.0):
    """``chain`` under band-limited white forcing (0-20 Hz) on DOF ``dof`` alone, 40 dB."""
    from scipy.signal import butter, sosfiltfilt

    w = sosfiltfilt(butter(4, 20.0, fs=fs, output="sos"), np.random.default_rng(dof).standard_normal(int(T * fs)))
    u = np.zeros((w.size, chain.n))
    u[:, dof] = 10 * w / w.std()
    r = simulate(chain, u, T, fs, noise_db=40, noise_on=("accel", "force"), seed=dof)
    if motion == "velocity":
        return Recording(t=r.t, u=r.u, v=r.v)
    return Recording(t=r.t, u=r.u, a=r.a)


@pytest.mark.parametrize("chain", [TABLE1, Chain.random(4, np.random.default_rng(4))], ids=["table1", "random4"])
@pytest.mark.parametrize("dof", [0, 2], ids=["dof1", "dof3"])
def test_one_force_scales_the_whole_chain(chain, dof):
    # the weak form solves every DOF's equation jointly: a spring in two equations passes the
    # force's scale on, so every parameter is determined with one shaker (end or interior DOF)
    res = algid.identify(_one_force(chain, dof))
    n, truth = chain.n, chain.identifiable()
    assert res.plan.method == "weak_form" and res.valid, res.reasons
    err = np.abs(res.theta / truth - 1)
    assert err[:n].max() < 0.02 and err[2 * n :].max() < 0.02 and err[n : 2 * n].max() < 0.15
    assert np.max(np.abs(res.theta - truth) / res.sigma) < 5
    modal, why = res.modes()  # the modal table of the whole chain
    fn = np.sort(natural_frequencies_hz(truth, n, chain.boundary))
    np.testing.assert_allclose(modal.frequencies_hz, fn, rtol=0.005, err_msg=why)


def test_continuous_estimator_with_one_force_estimates_every_dof():
    # sample by sample too: the weak form's joint solve scales the unforced DOFs
    rec = _one_force(TABLE1, 0)
    out = algid.ContinuousEstimator(3, 1e-3).run(np.ascontiguousarray(rec.a), np.ascontiguousarray(rec.u))
    last = np.concatenate([out["mass"][-1], out["damping"][-1], out["stiffness"][-1]])
    err = np.abs(last / TABLE1.identifiable() - 1)
    assert err[:3].max() < 0.01 and err[6:].max() < 0.01 and err[3:6].max() < 0.1


def test_one_force_with_derived_accelerations_scales_the_whole_chain():
    # the algebraic windows estimate an unforced DOF's ratios (eq. 7 with its mass set to 1)
    # and take its scale from the spring it shares with a scaled neighbour; the bootstrap's
    # surrogates keep those DOFs without force (motion.unforced_consistent)
    res = algid.identify(_one_force(TABLE1, 0, motion="velocity"))
    truth = TABLE1.identifiable()
    assert res.plan.method == "algebraic" and res.valid, res.reasons
    err = np.abs(res.theta / truth - 1)
    assert err[:3].max() < 0.05 and err[6:].max() < 0.05 and err[3:6].max() < 0.3
    assert np.max(np.abs(res.theta - truth) / res.sigma) < 5


def test_replicates_carry_the_recordings_noise():
    rng = np.random.default_rng(1)
    T = 20000
    x, v, a = _sines(T, [2.0, 9.0], [1e-2, 1e-3])
    u = 3.0 * a + 50.0 * x
    sig_a, sig_u = 0.05, 0.02
    nm = analyse(
        u[:, None] + sig_u * rng.standard_normal((T, 1)),
        a[:, None] + sig_a * rng.standard_normal((T, 1)),
        DT,
        "acceleration",
    )
    mo = Motion(x[:, None], v[:, None], a[:, None])
    a_b, u_b = replicate_signals(mo, u[:, None], nm, rng, 5)
    assert np.std(a_b[:, 0] - a) == pytest.approx(sig_a, rel=0.1)
    assert np.std(u_b[:, 0] - u) == pytest.approx(sig_u, rel=0.1)
    q = 1e-6
    nm_x = analyse(u[:, None], (q * np.round(x / q))[:, None], DT, "displacement")
    a_q, _ = replicate_signals(mo, u[:, None], nm_x, rng, 5)
    # the derived acceleration's noise is that of quantisation (white, q^2/12) through the 5-point rule
    gain = np.sqrt(np.sum(np.array([-1, 16, -30, 16, -1]) ** 2)) / 12.0
    assert np.std(a_q[100:-100, 0] - a[100:-100]) == pytest.approx(gain * q / np.sqrt(12) / DT**2, rel=0.15)


# ---- plan and verdicts -----------------------------------------------------------------------


def test_plan_single_window_for_short_clean_records_else_continuous():
    t, a, u, _ = simulate_chain(TABLE1, multisine(3), 0.3)
    clean = analyse(u, a, DT)
    assert make_plan(clean, 0.3).estimator == "window"
    rng = np.random.default_rng(2)
    noisy = analyse(u, a + 0.01 * np.std(a) * rng.standard_normal(a.shape), DT)
    assert "too short" in make_plan(noisy, 0.2).reason
    plan = make_plan(noisy, 10.0, f_natural=TABLE1.natural_frequencies_hz())
    # weak-form windows (measured accelerations): one period of the lowest mode
    assert plan.estimator == "continuous" and plan.window_s == pytest.approx(1.0 / 2.2, rel=0.02)
    assert plan.method == "weak_form" and plan.window_basis.startswith("one period of the lowest natural")
    derived = analyse(u, np.cumsum(np.cumsum(a, axis=0), axis=0) * DT**2, DT, "displacement")
    plan = make_plan(derived, 10.0, f_natural=TABLE1.natural_frequencies_hz())  # the algebraic windows' guess
    assert plan.method == "algebraic" and plan.window_s == pytest.approx(0.5 / 2.2, rel=0.02)
    assert make_plan(noisy, 10.0, "window").estimator == "window"
    with pytest.raises(ValueError, match="estimator"):
        make_plan(noisy, 10.0, "kalman")
    np.testing.assert_allclose(
        natural_frequencies_hz(TABLE1.identifiable(), 3, "fixed"), TABLE1.natural_frequencies_hz(), rtol=1e-9
    )
    assert natural_frequencies_hz(np.r_[-1.0, TABLE1.identifiable()[1:]], 3, "fixed").size == 0


def _judge(theta, sigma, u_scale=1.0, misfit=""):
    """Verdicts for one DOF between walls whose regressors all have unit spread."""
    T = 1000
    rng = np.random.default_rng(3)
    mo = Motion(*(rng.standard_normal((T, 1)) for _ in range(3)))
    u = u_scale * rng.standard_normal((T, 1))
    nm = analyse(u, mo.a, DT)
    return {
        v.name: v
        for v in judge(
            np.array(theta, float), np.array(sigma, float), 1, "fixed", mo, u, np.array([True]), nm, misfit=misfit
        )
    }


def test_verdicts_of_impossible_undetermined_and_negligible_estimates():
    v = _judge([-0.5, 0.1, 0.5, np.nan], [0.01, 0.01, 0.01, np.nan])
    assert v["m1"].status == "inadmissible" and "algid diagnose" in v["m1"].reason
    v = _judge([0.002, 0.1, 0.5, np.nan], [0.01, 0.01, 0.01, np.nan])
    assert v["m1"].status == "not_identifiable" and "mass not identifiable" in v["m1"].reason
    v = _judge([0.5, -0.2, 0.5, np.nan], [0.01, 0.01, 0.01, np.nan])
    assert v["c1"].status == "inadmissible" and v["c1"].reason.startswith("negative damping")
    v = _judge([0.5, 0.1, -0.003, np.nan], [0.01, 0.01, 0.002, np.nan])
    assert v["k1"].status == "negligible" and v["k1"].valid
    v = _judge([0.5, 0.1, 0.05, np.nan], [0.01, 0.01, 0.1, np.nan])
    assert v["k1"].status == "not_identifiable"  # consistent with zero, but 3 sigma is 30 % of the force
    v = _judge([0.5, 0.1, 0.5, np.nan], [0.01, 0.01, 0.01, np.nan])
    assert all(v[k].status == "ok" for k in ("m1", "c1", "k1")) and v["k2"].status == "not_separable"
    v = _judge([0.5, 0.1, 0.5, np.nan], [0.01, 0.01, 0.01, np.nan], misfit="the gap is 4x the floor")
    assert all(v[k].status == "model_misfit" and not v[k].valid for k in ("m1", "c1", "k1"))
    assert v["k1"].reason == "stiffness biased: the gap is 4x the floor" and v["k2"].status == "not_separable"


# ---- whole records ---------------------------------------------------------------------------


def test_noise_free_short_record_keeps_the_papers_accuracy():
    t, a, u, _ = simulate_chain(TABLE1, multisine(3), 0.2)
    res = algid.identify(Recording(t=t, u=u, a=a))
    assert res.plan.estimator == "window" and res.valid
    assert relative_errors(TABLE1, res.mass, res.damping, res.stiffness).max() < 1e-6
    at = np.searchsorted(res.time_s, 0.1)
    h = res.history[at]
    assert relative_errors(TABLE1, h[:3], h[3:6], h[6:]).max() < 1e-6


@pytest.fixture(scope="module")
def table1_40db():
    r = simulate(TABLE1, multisine(3, seed=1), 10.0, 1000.0, noise_db=40, noise_on=("accel", "force"), seed=1)
    return Recording(t=r.t, u=r.u, a=r.a)


def test_noisy_record_continuous_within_the_issue_targets_and_sigma(table1_40db):
    res = algid.identify(table1_40db)
    assert res.plan.estimator == "continuous" and res.valid
    err = np.abs(res.theta / TABLE1.identifiable() - 1)
    assert err[:3].max() < 0.005 and err[3:6].max() < 0.02 and err[6:].max() < 0.005
    z = np.abs(res.theta - TABLE1.identifiable()) / res.sigma
    assert z.max() < 4.0 and 0.1 < np.median(z) < 2.0
    assert np.all(res.sigma > 0)


def test_weak_form_windows_for_measured_accelerations_algebraic_for_derived(table1_40db):
    res = algid.identify(table1_40db, replicates=2)
    assert res.plan.method == "weak_form"
    # the estimate is the joint weak-form solution; its history ends on it and is finite
    assert np.all(np.isfinite(res.history)) and res.history.shape[0] > 10
    np.testing.assert_allclose(res.history[-1], res.raw, rtol=0.02)
    axis = algid.identify(positioning_axis(seed=3, duration_s=20.0).recording, boundary="free", replicates=2)
    assert axis.plan.method == "algebraic" and axis.motion == "displacement"
    assert algid.identify(table1_40db, estimator="window", replicates=2).plan.method == ""


def test_sigma_counts_the_methods_own_error_near_the_sampling_rate():
    # a force band-limited to fs/5, noise-free: the quadrature of such content is off by about
    # 0.2 % on masses and springs; the noise-free surrogate measures it and sigma includes it
    from scipy.signal import butter, sosfiltfilt

    rng = np.random.default_rng(0)
    fs, T = 1000.0, 10.0
    u = sosfiltfilt(butter(6, 200.0, fs=fs, output="sos"), rng.standard_normal((int(T * fs), 3)), axis=0) * 20
    r = simulate(TABLE1, u, T, fs)
    res = algid.identify(Recording(t=r.t, u=r.u, a=r.a), replicates=2)
    truth = TABLE1.identifiable()
    err = res.theta - truth
    assert np.abs(err / truth).max() > 1e-3  # the effect is there ...
    assert np.all(np.abs(err) < 3 * res.sigma)  # ... and inside the uncertainty
    np.testing.assert_allclose(res.method_bias[:3], err[:3], rtol=0.3)
    assert res.to_json()["parameters"][0]["method_bias"] == pytest.approx(res.method_bias[0])


def test_white_force_up_to_the_nyquist_rate():
    # broadband forcing: every spectrum is flat, the force stands nowhere above "its floor"; the
    # coherence between forces and accelerations says the flat top is signal (noise.coherent_share)
    rng = np.random.default_rng(0)
    fs, T = 1000.0, 10.0
    r = simulate(TABLE1, 10 * rng.standard_normal((int(T * fs), 3)), T, fs, noise_db=40, seed=1)
    rec = Recording(t=r.t, u=r.u, a=r.a)
    nm = analyse(rec.u, rec.a, 1 / fs)
    assert nm.f_hi > 0.8 * nm.nyquist and nm.forces[0].snr_db > 30
    res = algid.identify(rec, replicates=2)
    assert res.plan.noise_rms[0] > 0  # the noise model's levels, not the fourth differences
    err = np.abs(res.theta / TABLE1.identifiable() - 1)
    assert res.valid and err[:3].max() < 0.005 and err[6:].max() < 0.005 and err[3:6].max() < 0.02


def test_single_window_on_a_long_noisy_record_is_flagged_by_its_uncertainty(table1_40db):
    res = algid.identify(table1_40db, estimator="window")
    assert res.plan.estimator == "window"
    # the growing window's error is large under noise; every parameter it gets wrong by more than
    # 5 % carries an uncertainty that says so (or is not valid)
    err = np.abs(res.theta / TABLE1.identifiable() - 1)
    for p, v in enumerate(res.verdicts):
        if err[p] > 0.05 and v.valid:
            assert res.sigma[p] > 0.01 * abs(TABLE1.identifiable()[p])


def test_slow_positioning_axis_from_encoder_counts():
    sc = positioning_axis(seed=3, duration_s=20.0)
    res = algid.identify(sc.recording)
    assert res.motion == "displacement" and res.noise.quantised
    assert res.mass[0] == pytest.approx(5.0, rel=0.05)
    assert res.damping[0] == pytest.approx(25.0, rel=0.10)
    for p, v in enumerate(res.verdicts):
        assert not (v.valid and np.isfinite(res.theta[p]) and res.theta[p] < -3 * res.sigma[p])
    assert res.verdict("k1").status == "negligible"  # no spring on the axis


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_axis_with_dry_friction_is_not_called_a_valid_chain():
    sc = positioning_axis(seed=4, duration_s=20.0, effects=FRICTION_AND_OFFSET)
    res = algid.identify(sc.recording)
    assert not res.valid
    assert any("algid diagnose" in r for r in res.reasons)


def test_quasi_static_device_mass_not_identifiable():
    res = algid.identify(displacement_driven(seed=0).recording)
    v = res.verdict("m1")
    assert v.status == "not_identifiable" and "quasi-static" in v.reason
    assert res.stiffness[0] == pytest.approx(2e4, rel=0.01)
    assert res.damping[0] == pytest.approx(200.0, rel=0.02)


def test_result_json_carries_sigma_status_and_the_choice(table1_40db):
    res = algid.identify(table1_40db, replicates=3)
    doc = res.to_json()
    assert doc["estimator"] == "continuous" and doc["estimator_reason"]
    assert len(doc["sigma_mass"]) == 3 and len(doc["sigma_stiffness"]) == 4
    assert [p["name"] for p in doc["parameters"]] == res.names
    assert {p["status"] for p in doc["parameters"]} <= {"ok", "negligible"}
    assert doc["noise_model"]["band_hz"][1] > 20.0
    assert repr(res).startswith("Identification(n=3, boundary='fixed', estimator='continuous'")


def test_velocity_only_record_like_a_laser_vibrometer():
    chain = Chain([2.0], [3.0], [800.0, 400.0])
    r = simulate(chain, multisine(1, seed=2), 10.0, 1000.0, noise_db=40, noise_on=("force",), seed=2)
    v = r.v + 0.01 * np.std(r.v) * np.random.default_rng(2).standard_normal(r.v.shape)  # 40 dB on the velocity
    res = algid.identify(Recording(t=r.t, u=r.u, v=v))
    assert res.motion == "velocity" and res.valid
    truth = chain.identifiable()
    assert np.all(np.abs(res.theta[:3] / truth[:3] - 1) < np.maximum(4 * res.sigma[:3] / truth[:3], 0.02))


def test_surrogate_motion_from_velocities_is_exactly_integrated():
    T = 4000
    x, v, a = _sines(T, [2.0, 13.0], [1e-2, 1e-3])
    mo = band_limited_motion((v + 0.05)[:, None], "velocity", DT, 100.0)
    inner = slice(200, T - 200)
    np.testing.assert_allclose(mo.a[inner, 0], a[inner], atol=2e-3 * np.abs(a).max())
    np.testing.assert_allclose(second_derivative(mo.x, DT, 7)[inner], mo.a[inner], atol=1e-6 * np.abs(a).max())
