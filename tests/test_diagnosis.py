"""Gap diagnosis (issue 6): building blocks against closed forms and plain numpy, the
whole pipeline against the simulator's hidden effects, and the CLI contract."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import welch

from algid.diagnosis import EFFECTS, MAIN_PARAM, diagnose
from algid.diagnosis.candidates import lowpass
from algid.diagnosis.core import (
    EqSpec,
    band_filter,
    cross_validate,
    detrend,
    integrals,
    prepare,
    signal_band,
    window_stats,
)
from algid.estimator.reference import iterated_integrals
from algid.model.chain import TABLE1, Chain
from algid.recording import Recording, save_recording

ROOT = Path(__file__).resolve().parents[1]


def multisine(n: int, duration: float, fs: float, seed: int, band=(0.5, 50.0), rms=10.0) -> np.ndarray:
    """Independent random-phase multisines, flat on the lines of ``band``, period = duration."""
    rng = np.random.default_rng(seed)
    T = int(round(duration * fs))
    k = np.arange(int(np.ceil(band[0] * duration)), int(band[1] * duration) + 1)
    U = np.zeros((T // 2 + 1, n), dtype=complex)
    U[k] = np.exp(2j * np.pi * rng.uniform(size=(k.size, n)))
    u = np.fft.irfft(U, n=T, axis=0)
    return u * rms / u.std(axis=0)


def simulate(chain, effects=(), duration=8.0, noise_db=55.0, seed=0):
    from algid.simulator import simulate as sim

    u = multisine(chain.n, duration, 1000.0, seed)
    return sim(chain, u, duration, 1000.0, effects=list(effects), noise_db=noise_db, seed=seed)


# ---------------------------------------------------------------------------- building blocks


def test_integrals_match_the_reference_quadrature():
    rng = np.random.default_rng(3)
    a = rng.standard_normal((400, 3))
    A1, A2 = integrals(a, 2e-3)
    for i in range(3):
        I = iterated_integrals(a[:, i], 2e-3, 6, 2)
        np.testing.assert_allclose(A1[:, i], I[1], rtol=0, atol=1e-15)
        np.testing.assert_allclose(A2[:, i], I[2], rtol=0, atol=1e-15)


def test_integrals_exact_on_a_quintic():
    t = 0.01 * np.arange(300)
    a = 1 - 2 * t + 0.5 * t**3 - 0.1 * t**5
    A1, A2 = integrals(a[:, None], 0.01)
    np.testing.assert_allclose(A1[:, 0], t - t**2 + 0.125 * t**4 - t**6 / 60, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(A2[:, 0], t**2 / 2 - t**3 / 3 + t**5 / 40 - t**7 / 420, rtol=1e-12, atol=1e-12)


def _prep(T=1200, L=100, n=1, seed=0):
    rng = np.random.default_rng(seed)
    return prepare(rng.standard_normal((T, n)), rng.standard_normal((T, n)), 1e-3, L)


def test_detrend_is_the_projection_orthogonal_to_lines_per_window():
    P = _prep()
    x = np.random.default_rng(1).standard_normal((P.nw * P.L, 2))
    tau = np.arange(P.L)
    lines = 3.0 + 0.2 * tau
    Z = detrend(P, x + np.tile(lines, P.nw)[:, None])
    np.testing.assert_allclose(Z, detrend(P, x), atol=1e-12)  # lines vanish
    np.testing.assert_allclose(Z.sum(axis=1), 0.0, atol=1e-10)  # orthogonal to 1
    np.testing.assert_allclose(np.einsum("wlc,l->wc", Z, tau - tau.mean()), 0.0, atol=1e-9)  # and to tau
    np.testing.assert_allclose(detrend(P, Z.reshape(-1, 2)), Z, atol=1e-12)  # idempotent


def test_gram_cross_validation_equals_explicit_least_squares():
    """Withheld errors from per-window Grams against plain lstsq on the training windows."""
    P = _prep(T=2400, L=120)
    rng = np.random.default_rng(5)
    N = P.nw * P.L
    X = rng.standard_normal((N, 3))
    y = X @ np.array([1.5, -2.0, 0.3]) + 0.1 * rng.standard_normal(N) + np.repeat(rng.standard_normal(P.nw), P.L)
    cv = cross_validate(P, window_stats(P, [EqSpec(e=0, X=X, y=y, E=None)]))
    Xd = detrend(P, X)
    yd = detrend(P, y[:, None])[..., 0]
    for k in range(P.nfolds):
        test = P.folds == k
        coef = np.linalg.lstsq(Xd[~test].reshape(-1, 3), yd[~test].ravel(), rcond=None)[0]
        np.testing.assert_allclose(cv.theta_folds[k], coef, rtol=1e-9)
        r = yd[test] - Xd[test] @ coef
        np.testing.assert_allclose(cv.test_sse[test], (r**2).sum(axis=1), rtol=1e-9)


def test_band_rule_finds_the_excited_band_and_the_noise_floor():
    """Forces flat on 0.5-50 Hz with white noise of known level: f_exc ~ 50 Hz, the noise
    floor (one-sided PSD 2 sigma^2 / fs) within 10 %, the edge at 3 f_exc, widened to the
    modes, the whole band for white noise alone; accelerations count as well as forces."""
    fs, dt, sig = 1000.0, 1e-3, 0.05
    rng = np.random.default_rng(7)
    u = multisine(2, 10.0, fs, seed=3) + sig * rng.standard_normal((10000, 2))
    a = rng.standard_normal((10000, 2))
    b = signal_band(a, u, dt, natural_hz=[12.0, 31.0])
    assert b.source in ("force 1", "force 2") and not np.isfinite(b.f_signals["acceleration 1"])
    assert 48.0 <= b.f_exc <= 51.0
    assert b.f_hi == pytest.approx(3 * b.f_exc)
    for fl in b.floors[:2]:  # the forces'
        assert fl == pytest.approx(2 * sig**2 / fs, rel=0.1)
    assert signal_band(a, u, dt, natural_hz=[140.0]).f_hi == pytest.approx(1.25 * 140.0)
    assert signal_band(a, u, dt, natural_hz=[450.0]).f_hi == 500.0  # capped at Nyquist
    b0 = signal_band(u, np.zeros_like(u), dt)
    assert b0.source.startswith("acceleration") and 48.0 <= b0.f_exc <= 51.0
    # A response with power up to 120 Hz widens the band beyond the forces' 3 x 50 Hz.
    a2 = a.copy()
    a2[:, 1] = multisine(1, 10.0, fs, seed=4, band=(0.5, 120.0))[:, 0] + sig * rng.standard_normal(10000)
    b2 = signal_band(a2, u, dt)
    assert b2.source == "acceleration 2" and 117.0 <= b2.f_exc <= 121.0 and b2.f_hi == pytest.approx(3 * b2.f_exc)
    bw = signal_band(a, np.zeros_like(a), dt)  # white noise: no bin 10x above its floor
    assert bw.full and bw.f_hi == 500.0


def test_noise_floor_is_the_sensor_noise_under_friction_jumps():
    """Equation errors of white noise (sigma known) plus a dry-friction force reversing with a
    multisine's velocity (steps 1000 sigma high, each over two samples) and a slow misfit: the
    floor is sigma within 10 %, where the steps' spectrum puts the upper band's level over ten
    times higher; white noise alone is left as it is."""
    from types import SimpleNamespace

    from algid.diagnosis.locate import noise_floor, without_jumps

    fs, sig, T = 1000.0, 1e-3, 20_000
    t = np.arange(T) / fs
    rng = np.random.default_rng(3)
    velocity = np.sin(2 * np.pi * 1.3 * t) + 0.6 * np.sin(2 * np.pi * 4.1 * t + 1.0)
    friction = 0.5 * np.convolve(np.sign(velocity), [0.5, 0.5], mode="same")
    noise = sig * rng.standard_normal((T, 2))
    resid = noise + np.column_stack([friction + 0.05 * np.sin(2 * np.pi * 2.0 * t), np.zeros(T)])
    P = SimpleNamespace(dt=1 / fs, L=250)
    assert noise_floor(P, resid) == pytest.approx([sig, sig], rel=0.1)
    f, S = welch(resid[:, 0], fs=fs, nperseg=250)
    assert np.median(S[f >= fs / 3]) > 10 * 2 * sig**2 / fs  # what the floor would be read on
    np.testing.assert_allclose(without_jumps(noise), noise, rtol=0, atol=1e-12)


def test_band_filter_is_an_orthogonal_projection():
    rng = np.random.default_rng(2)
    P = prepare(rng.standard_normal((2000, 1)), rng.standard_normal((2000, 1)), 1e-3, 200, band_hz=150.0)
    x, y = rng.standard_normal((2, P.nw, P.L, 3))
    Mx, My = band_filter(P, x), band_filter(P, y)
    np.testing.assert_allclose(band_filter(P, Mx), Mx, atol=1e-12)  # idempotent
    np.testing.assert_allclose(np.sum(Mx * y), np.sum(x * My), rtol=1e-10)  # symmetric
    # Kept bins 0..150 Hz of a 0.2 s window (5 Hz apart): 31 of 101, DC once, others twice.
    assert P.band_mask.sum() == 31 and P.band_fraction == pytest.approx(61 / 200)
    f = np.fft.rfftfreq(P.L, P.dt)
    F = np.fft.rfft(Mx, axis=1)
    assert np.abs(F[:, f > 150.0]).max() < 1e-10  # nothing left above the band


def test_in_band_withheld_error_equals_explicit_masked_residual_and_noise_fraction():
    """In-band withheld errors from the masked Grams against plain lstsq + FFT masking,
    and for white noise the in-band share of the withheld error is the band fraction."""
    rng = np.random.default_rng(5)
    T, L = 40000, 200
    P = prepare(rng.standard_normal((T, 1)), rng.standard_normal((T, 1)), 1e-3, L, band_hz=150.0)
    N = P.nw * P.L
    t = P.dt * np.arange(N)
    X = np.stack([np.sin(2 * np.pi * 7 * t), np.cos(2 * np.pi * 23 * t), np.sin(2 * np.pi * 41 * t) ** 3], axis=1)
    y = X @ np.array([1.5, -2.0, 0.3]) + rng.standard_normal(N)
    cv = cross_validate(P, window_stats(P, [EqSpec(e=0, X=X, y=y, E=None)]))
    Xd, yd = detrend(P, X), detrend(P, y[:, None])[..., 0]
    for k in range(P.nfolds):
        test = P.folds == k
        coef = np.linalg.lstsq(Xd[~test].reshape(-1, 3), yd[~test].ravel(), rcond=None)[0]
        r = (yd[test] - Xd[test] @ coef)[..., None]
        np.testing.assert_allclose(cv.test_sse[test], (band_filter(P, r) ** 2).sum(axis=(1, 2)), rtol=1e-8)
        np.testing.assert_allclose(cv.test_sub_full.sum(axis=(1, 2))[test], (r**2).sum(axis=(1, 2)), rtol=1e-8)
    # White residual: in-band / full-band withheld error = band fraction (61/200), within 3 %.
    ratio = cv.test_sse.sum() / cv.test_sub_full.sum()
    assert ratio == pytest.approx(P.band_fraction, rel=0.03)
    assert np.all(cv.test_sse <= cv.test_sub_full.sum(axis=(1, 2)) * (1 + 1e-12))


@pytest.mark.parametrize("fc", [20.0, 150.0, 450.0])
def test_lowpass_matches_the_steady_state_of_a_first_order_filter(fc):
    dt = 1e-3
    t = dt * np.arange(4000)
    for f, tol in ((5.0, 1e-7), (50.0, 3e-4)):
        x = np.sin(2 * np.pi * f * t)
        H = 1 / (1 + 1j * f / fc)
        exact = np.abs(H) * np.sin(2 * np.pi * f * t + np.angle(H))
        assert np.abs(lowpass(x, fc, dt) - exact)[1500:].max() < tol


# ---------------------------------------------------------------------------- the pipeline


def test_linear_fit_recovers_table1_without_noise():
    res = simulate(TABLE1, noise_db=None)
    d = diagnose(Recording(t=res.t, u=res.u, a=res.a))
    np.testing.assert_allclose(d.lin.mass, TABLE1.mass, rtol=1e-5)
    np.testing.assert_allclose(d.lin.damping(), TABLE1.damping, rtol=1e-4)
    np.testing.assert_allclose(d.lin.stiffness(), TABLE1.stiffness, rtol=1e-5)
    assert d.gap_before < 1e-5
    assert d.effect == "none"


CASES = [
    ("coulomb_friction", {"dof": 2}, {"force": 0.6}),
    ("quadratic_damping", {"dof": 1}, {"c_quadratic": 30.0}),
    ("cubic_stiffness", {"spring": 2}, {"k_cubic": 5e5}),
    ("clearance", {"spring": 3}, {"gap": 0.004, "k_contact": 300.0}),
    ("input_delay", {"dof": 3}, {"delay": 0.0015}),
    ("sensor_bias", {"dof": 2}, {"bias": 0.02}),
    ("sensor_lowpass", {"dof": 1}, {"cutoff_hz": 80.0}),
    ("parameter_drift", {"spring": 4}, {"rel_change": -0.15}),
]


@pytest.mark.parametrize("name,loc,params", CASES, ids=[c[0] for c in CASES])
def test_each_effect_is_found_located_and_sized(name, loc, params):
    res = simulate(TABLE1, [{"name": name, "location": loc, "params": params}], seed=11)
    d = diagnose(Recording(t=res.t, u=res.u, a=res.a))
    assert (d.effect, d.location) == (name, loc)
    main = MAIN_PARAM[name]
    assert d.params[main] == pytest.approx(params[main], rel=0.05)
    assert d.gap_after < 0.8 * d.gap_before
    # In-band gaps never exceed the full-band ones; the effect shrinks both.
    assert d.gap_before <= d.gap_before_full and d.gap_after <= d.gap_after_full
    assert d.gap_after_full < d.gap_before_full
    assert d.band.f_hi == pytest.approx(min(500.0, max(3 * d.band.f_exc, 1.25 * d.band.f_modes)))
    assert 48.0 <= d.band.f_exc <= 51.0
    # The jackknife standard deviation is an honest scale of the error (within 5 sigma).
    assert abs(d.params[main] - params[main]) < 5 * d.params_std[main] + 0.01 * abs(params[main])


def test_no_false_alarm_on_a_linear_chain_with_noise():
    for seed in (1, 2):
        res = simulate(Chain.random(3, np.random.default_rng(seed)), noise_db=45.0, seed=seed)
        d = diagnose(Recording(t=res.t, u=res.u, a=res.a))
        assert d.effect == "none"
        assert d.gap_after == d.gap_before
        assert (
            max(s.z for s in d.ranking if np.isfinite(s.z)) < 4.0 if any(np.isfinite(s.z) for s in d.ranking) else True
        )


def test_one_dof_reports_spring_one_for_the_second_spring():
    ch = Chain([2.0], [4.0], [800.0, 600.0])
    res = simulate(ch, [{"name": "cubic_stiffness", "location": {"spring": 2}, "params": {"k_cubic": 8e5}}], seed=4)
    d = diagnose(Recording(t=res.t, u=res.u, a=res.a))
    assert d.effect == "cubic_stiffness" and d.location == {"spring": 1}
    assert d.params["k_cubic"] == pytest.approx(8e5, rel=0.05)  # an odd law: the same on either side
    from algid.diagnosis.core import to_physical

    # With the effect, the linear part is the parallel sum k1 + k2 (the linear-only fit
    # absorbs part of the cubic spring and is stiffer).
    m, c, k = to_physical(d.P, 0, d.best.fit.thetas[0])
    assert (m, c, k) == pytest.approx((2.0, 4.0, 1400.0), rel=2e-2)
    assert d.lin.stiffness()[0] > 1400.0


def test_displacement_only_recording_gives_the_same_diagnosis():
    res = simulate(
        TABLE1,
        [{"name": "quadratic_damping", "location": {"dof": 3}, "params": {"c_quadratic": 40.0}}],
        noise_db=None,
        seed=2,
    )
    d = diagnose(Recording(t=res.t, u=res.u, x=res.x))
    assert (d.effect, d.location) == ("quadratic_damping", {"dof": 3})
    assert d.params["c_quadratic"] == pytest.approx(40.0, rel=0.02)


def test_unforced_dof_has_parameters_per_unit_mass():
    res = simulate(TABLE1, noise_db=None, seed=3)
    u = res.u.copy()
    # Same motion, but DOF 3's force is not recorded: its equation loses its scale.
    d_full = diagnose(Recording(t=res.t, u=u, a=res.a))
    u[:, 2] = 0.0
    d = diagnose(Recording(t=res.t, u=u, a=res.a))
    assert d.lin.mass[2] == 1.0 and not d.lin.forced[2]
    # Without its force the equation of DOF 3 is wrong: the diagnosis must not call it linear.
    assert d.gap_before > 10 * d_full.gap_before


# ---------------------------------------------------------------------------- CLI


def _run_cli(*argv):
    """The installed ``algid`` command line, as a user runs it."""
    return subprocess.run(
        [sys.executable, "-m", "algid.cli", *argv], capture_output=True, text=True, cwd=ROOT, timeout=300
    )


@pytest.mark.slow  # one of the longest cases of the fast tier
def test_cli_json_contract_and_figures(tmp_path):
    res = simulate(
        TABLE1,
        [{"name": "cubic_stiffness", "location": {"spring": 3}, "params": {"k_cubic": 6e5}}],
        duration=6.0,
        seed=8,
    )
    rec = save_recording(tmp_path / "rec.csv", Recording(t=res.t, u=res.u, a=res.a))
    out = tmp_path / "diag.json"
    p = _run_cli("diagnose", str(rec), "--json", str(out), "--plots", str(tmp_path / "figs"))
    assert p.returncode == 0, p.stderr
    js = json.loads(out.read_text())
    for key in ("effect", "location", "params", "gap_before", "gap_after", "metric", "ranking"):
        assert key in js
    assert js["effect"] == "cubic_stiffness" and js["location"] == {"spring": 3}
    assert set(js["ranking"][0]) >= {"effect", "location", "params", "gap_after"}
    assert js["gap_after"] < js["gap_before"]
    assert js["gap_before"] <= js["gap_before_fullband"] and js["gap_after"] <= js["gap_after_fullband"]
    assert js["gap_after_fullband"] < js["gap_before_fullband"]
    assert js["band"]["band_hz"][0] == 0.0 and 140.0 < js["band"]["band_hz"][1] <= 500.0
    assert "in_band" in js["metric"] and "gap_after_fullband" in js["ranking"][0]
    assert "signal band" in p.stdout
    assert "cubic_stiffness" in p.stdout and "Where the linear model fails" in p.stdout
    pngs = sorted(f.name for f in (tmp_path / "figs").iterdir())
    assert pngs == sorted(
        [
            "residuals_time.png",
            "residuals_spectrum.png",
            "restoring_force.png",
            "damping_force.png",
            "window_parameters.png",
            "ranking.png",
            "prediction.png",
        ]
    )


@pytest.mark.parametrize(
    "content,needle",
    [
        ("t,u1\n0,1\n", "missing columns a1"),
        ("t,u1,a1\n" + "".join(f"{k}e-3,1,{'nan' if k >= 3 else 2}\n" for k in range(20)), "misses 17 samples"),
        ("", "empty file"),
    ],
)
def test_cli_bad_input_is_one_line_and_exit_2(tmp_path, content, needle):
    rec = tmp_path / "bad.csv"
    rec.write_text(content)
    p = _run_cli("diagnose", str(rec), "--json", str(tmp_path / "o.json"))
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0] and "Traceback" not in p.stderr


def test_cli_too_short_record_is_a_clean_error(tmp_path):
    t = 1e-3 * np.arange(50)
    rec = save_recording(tmp_path / "short.npz", Recording(t=t, u=np.sin(t), a=np.cos(t)))
    p = _run_cli("diagnose", str(rec), "--json", str(tmp_path / "o.json"), "--quiet")
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1


def test_effect_names_are_the_simulators():
    from algid.simulator import EFFECT_NAMES

    # a constant force on a mass is annihilated with the initial conditions by the windowed
    # equations (as by the algebraic estimator): no gap to diagnose
    assert set(EFFECTS) == set(EFFECT_NAMES) - {"force_offset"}


def _two_dof_record(effects, seed: int = 0) -> Recording:
    """A 2-DOF chain under independent broadband multisines (0.5-50 Hz, period of the
    10 s record), accelerometers at 50 dB."""
    from algid.simulator import simulate as sim

    chain = Chain([2.0, 2.5], [5.5, 5.0], [1000.0, 900.0, 700.0])
    rng = np.random.default_rng(seed)
    T = 10000
    k = np.arange(5, 501)
    U = np.zeros((T // 2 + 1, 2), dtype=complex)
    U[k] = np.exp(2j * np.pi * rng.uniform(size=(k.size, 2)))
    u = np.fft.irfft(U, n=T, axis=0)
    r = sim(chain, u * 10.0 / u.std(axis=0), 10.0, 1000.0, effects=effects, noise_db=50, seed=seed)
    return Recording(t=r.t, u=r.u, a=r.a)


@pytest.mark.parametrize("fc", [0.5, 2.0])
def test_ac_coupled_accelerometer_is_a_sensor_highpass(fc):
    hp = {"name": "sensor_highpass", "location": {"dof": 2}, "params": {"cutoff_hz": fc}}
    d = diagnose(_two_dof_record([hp]))
    assert (d.effect, d.location) == ("sensor_highpass", {"dof": 2})
    assert d.params["cutoff_hz"] == pytest.approx(fc, rel=0.2)
    assert d.gap_after < 0.2 * d.gap_before


def test_no_highpass_without_one():
    assert diagnose(_two_dof_record([])).effect == "none"
    lp = {"name": "sensor_lowpass", "location": {"dof": 2}, "params": {"cutoff_hz": 60.0}}
    d = diagnose(_two_dof_record([lp], seed=1))
    assert (d.effect, d.location) == ("sensor_lowpass", {"dof": 2})
