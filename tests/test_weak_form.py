"""Weak-form windows of the ContinuousEstimator against a plain numpy oracle (test functions
evaluated in the time domain, not through the C++ Fourier sums), their schedule, the bias
compensation under 20 dB noise, and the joint estimate's accuracy and calibration."""

from __future__ import annotations

import numpy as np
import pytest

import algid
from algid.model.chain import Chain
from test_continuous import CHAIN, DT, tone_record


def modulating_functions(L: int, dt: float, Q: int) -> list[np.ndarray]:
    """psi_f^(d)(t_l), d = 0, 1, 2: sin^4(pi t / W) times 1, cos(w_q t), sin(w_q t), q = 1..Q."""
    W, t = L * dt, np.arange(L) * dt
    a = np.pi / W
    s, c = np.sin(a * t), np.cos(a * t)
    w = [s**4, 4 * s**3 * c * a, 4 * a * a * (3 * s * s * c * c - s**4)]
    rows = [[w[0]], [w[1]], [w[2]]]
    for q in range(1, Q + 1):
        om = 2 * np.pi * q / W
        for g in (
            (np.cos(om * t), -om * np.sin(om * t), -om * om * np.cos(om * t)),
            (np.sin(om * t), om * np.cos(om * t), -om * om * np.sin(om * t)),
        ):
            rows[0].append(w[0] * g[0])
            rows[1].append(w[1] * g[0] + w[0] * g[1])
            rows[2].append(w[2] * g[0] + 2 * w[1] * g[1] + w[0] * g[2])
    return [np.array(r) for r in rows]


def oracle_window(a, u, dt, band_hz, sigma_a, boundary="fixed") -> np.ndarray:
    """Unweighted weak-form solution of one window, bias-compensated for white acceleration
    noise of RMS ``sigma_a`` on every channel: for DOF i the rows

        m_i int psi'' a_i - c_i int psi' a_i + k_i int psi (a_i - a_{i-1})
                                             + k_{i+1} int psi (a_i - a_{i+1}) = int psi'' u_i,

    normal equations summed over the DOFs, minus sigma_a^2 times the noise's expected
    contribution (traces of the test functions' Gram matrices)."""
    L, n = a.shape
    Q = int(np.floor(band_hz * L * dt + 1e-9))
    psi = modulating_functions(L, dt, Q)
    A = [dt * p @ a for p in psi]
    U2 = dt * psi[2] @ u
    tr = {(d, e): dt * dt * np.sum(psi[d] * psi[e]) for d in range(3) for e in range(3)}
    P = 3 * n + 1
    N, b = np.zeros((P, P)), np.zeros(P)
    for i in range(n):
        cols = [(i, A[2][:, i], 2, 1.0), (n + i, -A[1][:, i], 1, -1.0)]
        cols.append((2 * n + i, A[0][:, i] - (A[0][:, i - 1] if i > 0 else 0), 0, 1.0))
        if n > 1 and (i + 1 < n or boundary == "fixed"):
            cols.append((2 * n + i + 1, A[0][:, i] - (A[0][:, i + 1] if i + 1 < n else 0), 0, 1.0))
        for ca in cols:
            for cb in cols:
                N[ca[0], cb[0]] += ca[1] @ cb[1] - sigma_a**2 * ca[3] * cb[3] * tr[(ca[2], cb[2])]
            b[ca[0]] += ca[1] @ U2[:, i]
        if i > 0:  # neighbour channels in the spring columns
            N[2 * n + i, 2 * n + i] -= sigma_a**2 * tr[(0, 0)]
        if i + 1 < n:
            N[2 * n + i + 1, 2 * n + i + 1] -= sigma_a**2 * tr[(0, 0)]
    if n == 1 or boundary == "free":
        N[P - 1, P - 1] = 1.0
    theta = np.linalg.solve(N, b)
    if n == 1 and boundary == "fixed":
        theta[P - 1] = np.nan
    return theta


@pytest.mark.parametrize("boundary", ["fixed", "free"])
def test_windows_match_numpy_oracle(boundary):
    """Every window (unweighted rows, given noise level: deterministic) equals the oracle to
    1e-9, and the windows follow the schedule: L = 500 samples, one every L / 4, each result
    the same number of samples after its window's last sample, within three quarters of a hop
    (the window's work is spread over them, weak_form.hpp)."""
    chain = CHAIN
    if boundary == "free":
        chain = Chain(CHAIN.mass, CHAIN.damping, np.append(CHAIN.stiffness[:-1], 0.0), "free")
    a, u, _ = tone_record(chain, 3.0, seed=5, snr_db=30.0)
    sigma = 0.01
    est = algid.ContinuousEstimator(
        3, DT, boundary=boundary, gls=False, accel_noise=sigma, force_noise=0.0, detect=False, amortize=False
    )
    assert est.window_samples == 500 and est.hop_samples == 125
    out = est.run(a, u)
    L, H = 500, 125
    late = int(out["window_sample"][0]) - (L - 1)
    assert 0 < late < 3 * H // 4
    assert len(out["windows"]) == (a.shape[0] - L - late) // H + 1
    for r, done in enumerate(out["window_sample"]):
        start = r * H
        assert done == start + L - 1 + late
        expect = oracle_window(a[start : start + L], u[start : start + L], DT, 50.0, sigma, boundary)
        np.testing.assert_allclose(out["windows"][r], expect, rtol=1e-9)


def test_single_dof_matches_oracle():
    one = Chain(np.array([2.0]), np.array([5.0]), np.array([1000.0, 700.0]))
    a, u, _ = tone_record(one, 1.2, seed=4, snr_db=30.0)
    out = algid.ContinuousEstimator(1, DT, gls=False, accel_noise=0.02, detect=False).run(a, u)
    expect = oracle_window(a[:500], u[:500], DT, 50.0, 0.02)
    np.testing.assert_allclose(out["windows"][0][:3], expect[:3], rtol=1e-9)
    assert np.isnan(out["windows"][0][3])


def test_bias_compensation_removes_the_noise_bias():
    """20 dB on the accelerations, unweighted rows (where the noise bias is largest: the
    high-frequency rows carry mostly noise): without the correction the masses of the mean
    window come out several percent low (errors in the regressors), with it within 0.5 %.
    (The springs of this 8-tone record are too weakly informed at 20 dB to show it.)"""
    a, u, truth = tone_record(CHAIN, 20.0, seed=9)
    rng = np.random.default_rng(3)
    a = a + rng.standard_normal(a.shape) * 0.1 * np.sqrt((a**2).mean(0))
    low = {}
    for bc in (False, True):
        out = algid.ContinuousEstimator(3, DT, bias_compensation=bc, gls=False, detect=False).run(a, u, stride=1000)
        low[bc] = out["windows"][8:, :3].mean(0) / truth[0, :3] - 1
    assert low[False].min() < -0.05 and np.all(low[False] < 0)
    assert np.abs(low[True]).max() < 0.005


def test_noise_level_is_estimated():
    a, u, _ = tone_record(CHAIN, 3.0, seed=2)
    rng = np.random.default_rng(1)
    s = np.array([0.02, 0.05, 0.1])
    est = algid.ContinuousEstimator(3, DT)
    est.run(a + rng.standard_normal(a.shape) * s, u)
    np.testing.assert_allclose(est.noise_rms[:3], s, rtol=0.05)
    assert np.all(est.noise_rms[3:] < 1e-3)  # smooth forces: almost nothing


def test_joint_estimate_is_accurate_and_calibrated():
    """60 s at 40 dB on the accelerations: the joint estimate within 0.05 % on masses and
    springs, |error| / sigma of the order of one, no change event."""
    a, u, truth = tone_record(CHAIN, 30.0, seed=7)
    rng = np.random.default_rng(11)
    a = a + rng.standard_normal(a.shape) * 0.01 * np.sqrt((a**2).mean(0))
    out = algid.ContinuousEstimator(3, DT).run(a, u, stride=1000)
    assert out["events"] == []
    rel = np.abs(out["estimate"][-1] / truth[0] - 1)
    assert rel[:3].max() < 5e-4 and rel[6:].max() < 5e-4
    z = np.abs(out["estimate"][-1] - truth[0]) / out["sigma"][-1]
    assert 0.1 < np.median(z) < 2.0 and z.max() < 5.0


def test_misfit_is_the_noise_against_its_weights():
    """The window misfit (weighted residual per degree of freedom) is about 1 when the weights
    assume the noise there is, and about 4 when they assume half of it (W scales as 1/s^2):
    20 s of tones, white noise of 1 % of each acceleration's RMS, given to the estimator."""
    a, u, _ = tone_record(CHAIN, 20.0, seed=3)
    rng = np.random.default_rng(8)
    s = 0.01 * np.sqrt((a**2).mean(0)).min()
    noisy = a + rng.standard_normal(a.shape) * s
    median = {}
    for told in (s, s / 2):
        est = algid.ContinuousEstimator(3, DT, accel_noise=told, force_noise=0.0, detect=False)
        m = est.run(noisy, u, stride=1000)["window_misfit"]
        m = m[np.isfinite(m)]
        assert m.size > 100
        median[told] = np.median(m)
    assert 0.8 < median[s] < 1.25, median
    assert 3.2 < median[s / 2] < 5.0, median


@pytest.mark.parametrize(
    "value",
    [
        pytest.param(73.0, marks=pytest.mark.slow),
        pytest.param(1e3, marks=pytest.mark.slow),
        pytest.param(1e6, marks=pytest.mark.slow),
    ],
)
def test_one_absurd_sample_stays_out_of_the_joint(value):
    """Finding 9 of docs/reliability.md: one finite acceleration sample far off (73 m/s^2 is 13
    times a1's RMS, 1e6 is 1.8e5 times) that the sample screen lets through (`outlier_ratio`
    1e8) no longer biases the running estimates for good: its windows fit far worse than their
    neighbours and stay out of the joint; the noise estimate moves by at most 0.3 %. Table 1's
    chain under a multisine, noise-free, 30 s."""
    from algid.model.chain import TABLE1
    from signals import multisine, simulate_chain

    _, a, u, _ = simulate_chain(TABLE1, multisine(3, seed=4), 30.0, 1000.0)
    truth = TABLE1.identifiable()
    clean = algid.ContinuousEstimator(3, DT)
    clean.run(a, u, stride=1000)
    bad = a.copy()
    bad[1000, 0] = value
    est = algid.ContinuousEstimator(3, DT)
    out = est.run(bad, u, stride=1000)
    assert est.screened_windows >= 1
    assert np.abs(est.estimate / truth - 1).max() < 1e-4
    assert est.noise_rms[0] < 1.01 * clean.noise_rms[0]
    assert len(out["events"]) == 0
