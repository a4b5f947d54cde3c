"""ContinuousEstimator through Python: algebraic window results against the numpy reference,
the running estimate of the block-median path against an independent median / block-median
computation, per-sample vs batch, tracking of a stiffness step and no alarm on a constant
system under 40 dB noise (default weak-form windows), argument checking. The weak-form
windows against their numpy oracle: test_weak_form.py."""

from __future__ import annotations

import numpy as np
import pytest

import algid
from algid.estimator import reference
from algid.model.chain import Chain

DT = 1e-3


def tone_record(
    chain: Chain,
    duration_s: float,
    seed: int,
    snr_db: float | None = None,
    step: tuple[float, int, float] | None = None,
):
    """Closed-form record: prescribed trajectories (8 tones log-spaced over 1-20 Hz, displacement
    amplitudes falling as 1/f), forces from eq. 1 with the chain's parameters, optionally a
    spring step ``(time_s, spring index j (0-based), factor)``, and white noise of ``snr_db``
    on accelerations and forces. Returns (a, u, truth (T, 3n+1))."""
    rng = np.random.default_rng(seed)
    n, T = chain.n, int(round(duration_s / DT))
    t = np.arange(T) * DT
    w = 2 * np.pi * 20.0 ** ((np.arange(8) + rng.uniform(0, 1, 8)) / 8)
    amp = 1e-3 * (w[0] / w)[None, :] * rng.uniform(0.5, 1.5, (n, 8))
    ph = rng.uniform(0, 2 * np.pi, (n, 8))
    arg = w[None, None, :] * t[:, None, None] + ph[None]
    x = (amp[None] * np.sin(arg)).sum(-1)
    v = (amp[None] * w * np.cos(arg)).sum(-1)
    a = -(amp[None] * w**2 * np.sin(arg)).sum(-1)
    k = np.tile(chain.stiffness, (T, 1))
    if step is not None:
        ts, j, factor = step
        k[t >= ts, j] *= factor
    xp = np.concatenate([np.zeros((T, 1)), x, np.zeros((T, 1))], axis=1)
    spring = k[:, :n] * (xp[:, 1:-1] - xp[:, :-2]) + k[:, 1:] * (xp[:, 1:-1] - xp[:, 2:])
    u = chain.mass * a + chain.damping * v + spring
    truth = np.concatenate([np.tile(chain.mass, (T, 1)), np.tile(chain.damping, (T, 1)), k], axis=1)
    if snr_db is not None:
        g = np.random.default_rng(seed + 1)
        r = 10 ** (-snr_db / 20)
        a = a + g.standard_normal(a.shape) * r * np.sqrt((a**2).mean(0))
        u = u + g.standard_normal(u.shape) * r * np.sqrt((u**2).mean(0))
    return a, u, truth


CHAIN = Chain(np.array([2.0, 2.5, 3.0]), np.array([5.5, 5.0, 4.5]), np.array([1000.0, 900.0, 900.0, 700.0]))


@pytest.fixture(scope="module")
def noisy_record():
    return tone_record(CHAIN, 6.0, seed=1, snr_db=40.0)


def test_window_results_match_numpy_reference(noisy_record):
    a, u, _ = noisy_record
    est = algid.ContinuousEstimator(3, DT, method="algebraic", detect=False, amortize=False, prefilter_hz=0.0)
    out = est.run(a, u)
    M, K, d, n = est.window_samples, 4, 6, 3
    assert M == 300
    checked = 0
    for r, s_end in enumerate(out["window_sample"][:8]):
        start = s_end - M + 1
        assert (start - (M * (r % K)) // K) % M == 0  # the staggered schedule
        ref = reference.estimate(a[start : s_end + 1], u[start : s_end + 1], DT)["theta_ratio"][M - 1 - d]
        k = np.full(n + 1, np.nan)
        for j in range(n + 1):
            votes = ([ref[j - 1, 3]] if j > 0 else []) + ([ref[j, 2]] if j < n else [])
            k[j] = np.mean(votes)
        expect = np.concatenate([ref[:, 0], ref[:, 1], k])
        np.testing.assert_allclose(out["windows"][r], expect, rtol=1e-8)
        checked += 1
    assert checked == 8


def test_prefilter_matches_scipy_butterworth(noisy_record):
    """Default prefilter = scipy's 4th-order Butterworth at fs/20 on both channels, windows
    starting after the settle time; window results against the numpy reference on the
    scipy-filtered signals."""
    from scipy.signal import butter, lfilter

    a, u, _ = noisy_record
    est = algid.ContinuousEstimator(3, DT, method="algebraic", detect=False, amortize=False)
    assert est.prefilter_hz == pytest.approx(50.0) and est.settle_samples == 115
    out = est.run(a, u)
    b, den = butter(4, 50.0 / 500.0)
    af, uf = lfilter(b, den, a, axis=0), lfilter(b, den, u, axis=0)
    M, d, n = est.window_samples, 6, 3
    for r, s_end in enumerate(out["window_sample"][:6]):
        start = s_end - M + 1
        assert start == 115 + (M * (r % 4)) // 4 + M * (r // 4)
        ref = reference.estimate(af[start : s_end + 1], uf[start : s_end + 1], DT)["theta_ratio"][M - 1 - d]
        k = [np.mean(([ref[j - 1, 3]] if j > 0 else []) + ([ref[j, 2]] if j < n else [])) for j in range(n + 1)]
        np.testing.assert_allclose(out["windows"][r], np.concatenate([ref[:, 0], ref[:, 1], k]), rtol=1e-7)


def test_running_estimate_is_median_then_block_mean(noisy_record):
    a, u, _ = noisy_record
    est = algid.ContinuousEstimator(3, DT, method="algebraic", detect=False, amortize=False, block=16)
    out = est.run(a, u)
    W, samples = out["windows"], out["window_sample"]
    assert len(W) > 60
    for r in range(len(W)):
        got = out["estimate"][samples[r]]
        seen = W[: r + 1]
        blocks = (r + 1) // 16
        if blocks == 0:
            expect = np.median(seen, axis=0)
        else:
            expect = np.mean([np.median(seen[16 * b : 16 * b + 16], axis=0) for b in range(blocks)], axis=0)
        np.testing.assert_allclose(got, expect, rtol=1e-12)
    # sigma: MAD of the ring (last 64), scaled to the estimate
    assert np.all(out["sigma"][-1] > 0) and np.all(np.isfinite(out["sigma"][-1]))


def test_update_matches_run(noisy_record):
    a, u, _ = noisy_record
    a, u = a[:2500], u[:2500]
    batch = algid.ContinuousEstimator(3, DT).run(a, u)
    est = algid.ContinuousEstimator(3, DT)
    hist = np.empty_like(batch["estimate"])
    for s in range(a.shape[0]):
        est.update(a[s], u[s])
        hist[s] = est.estimate
    np.testing.assert_array_equal(np.isnan(hist), np.isnan(batch["estimate"]))
    np.testing.assert_allclose(hist[~np.isnan(hist)], batch["estimate"][~np.isnan(hist)], rtol=0, atol=0)
    assert est.ready and est.window_results == len(batch["windows"])


def test_constant_system_accuracy_and_no_alarm():
    a, u, truth = tone_record(CHAIN, 60.0, seed=7, snr_db=40.0)
    out = algid.ContinuousEstimator(3, DT).run(a, u, stride=100)
    assert out["events"] == []
    rel10 = np.abs(out["estimate"][100] / truth[0] - 1)  # row 100 = sample 10000
    assert rel10[:3].max() < 0.005 and rel10[6:].max() < 0.005  # masses and springs
    assert rel10[3:6].max() < 0.05  # dampings are weakly excited by prescribed tones
    z = np.abs(out["estimate"][-1] - truth[0]) / out["sigma"][-1]
    assert z.max() < 6.0


def test_step_is_tracked_within_a_second():
    spring = 1  # k2 drops 20 % at 20 s
    a, u, truth = tone_record(CHAIN, 30.0, seed=3, snr_db=40.0, step=(20.0, spring, 0.8))
    est = algid.ContinuousEstimator(3, DT)
    out = est.run(a, u)
    p = 2 * 3 + spring
    steps = [e for e in out["events"] if e.param == p and e.kind == "step"]
    assert steps and 20.0 <= steps[0].time_s < 21.0
    assert steps[0].name == "k2" and steps[0].before > steps[0].after
    assert all(e.param == p for e in out["events"]), out["events"]  # no false alarm elsewhere
    rel = np.abs(out["estimate"][:, p] / truth[:, p] - 1)
    bad_after = np.nonzero(rel[20000:] > 0.02)[0]
    settle = (bad_after[-1] + 1) * DT if bad_after.size else 0.0
    assert settle < 1.0


def test_free_end_and_single_dof():
    chain = Chain(np.array([2.0, 3.0]), np.array([5.0, 4.0]), np.array([1000.0, 800.0, 0.0]), "free")
    a, u, truth = tone_record(chain, 3.0, seed=2)
    out = algid.ContinuousEstimator(2, DT, boundary="free").run(a, u)
    assert out["estimate"][-1, -1] == 0.0 and out["sigma"][-1, -1] == 0.0
    np.testing.assert_allclose(out["estimate"][-1, :-1], truth[0, :-1], rtol=1e-6)
    one = Chain(np.array([2.0]), np.array([5.0]), np.array([1000.0, 700.0]))
    a, u, truth = tone_record(one, 2.0, seed=4)
    out = algid.ContinuousEstimator(1, DT).run(a, u)
    assert np.isnan(out["estimate"][-1, 3])  # k2 alone is not identifiable
    np.testing.assert_allclose(out["estimate"][-1, 2], 1700.0, rtol=1e-6)


def test_bad_sample_drops_windows_keeps_estimate(noisy_record):
    a, u, _ = noisy_record
    a = a.copy()
    a[3000, 1] = np.nan
    for method, first in (("algebraic", 115 + 300), ("weak_form", 500)):  # (prefilter settling and) a window
        out = algid.ContinuousEstimator(3, DT, method=method).run(a, u)
        assert out["status"][3000] == int(algid.Status.BAD_INPUT)
        assert np.all(np.isfinite(out["estimate"][3001]))
        # the schedule restarts: no window is harvested during the first window after it
        after = out["window_sample"][out["window_sample"] > 3000 + 5]
        assert after[0] >= 3000 + first


def test_runtime_size_and_instruction_sets_agree(noisy_record):
    """Every n runs the run-time sized estimator (its equality with ContinuousEstimator<N> to
    the bit is the C++ test's dynamic_equals_fixed); the ContinuousEstimator of every
    instruction-set build agrees with the baseline's to rounding."""
    from algid.estimator import chain_core

    for n in (3, 11):
        est = algid.ContinuousEstimator(n, DT)
        assert type(est._impl).__name__ == "WeakFormContinuousEstimatorDynamic" and est.estimate.shape == (3 * n + 1,)
    a, u, _ = noisy_record
    cfg = algid.ContinuousConfig()
    wide = chain_core().ContinuousEstimatorDynamic(cfg, 3).run(a, u)
    base = chain_core("x86-64").ContinuousEstimatorDynamic(cfg, 3).run(a, u)
    late = slice(len(base["estimate"]) // 2, None)
    np.testing.assert_allclose(base["estimate"][late], wide["estimate"][late], rtol=1e-6)
    assert algid.ContinuousConfig().window_s == -1 and est.options["stagger"] == 4
    assert est.options["method"] == "weak_form" and est.window_samples == 500


def test_arguments_are_checked():
    with pytest.raises(ValueError, match="boundary"):
        algid.ContinuousEstimator(3, DT, boundary="wall")
    with pytest.raises(TypeError, match="unknown option"):
        algid.ContinuousEstimator(3, DT, window=0.3)
    with pytest.raises(ValueError, match="window_s"):
        algid.ContinuousEstimator(3, DT, window_s=0.01)
    with pytest.raises(ValueError, match="prefilter"):
        algid.ContinuousEstimator(3, DT, method="algebraic", prefilter_hz=600.0)
    with pytest.raises(ValueError, match="stagger"):
        algid.ContinuousEstimator(3, DT, stagger=8)
    with pytest.raises(ValueError, match="method"):
        algid.ContinuousEstimator(3, DT, method="kalman")
    with pytest.raises(ValueError, match="band_hz"):
        algid.ContinuousEstimator(3, DT, band_hz=1.0)
    with pytest.raises(ValueError, match="noise"):
        algid.ContinuousEstimator(3, DT, accel_noise=-3.0)
    for bad in (0.5, float("inf"), float("nan")):
        with pytest.raises(ValueError, match="misfit_ratio"):
            algid.ContinuousEstimator(3, DT, misfit_ratio=bad)
    est = algid.ContinuousEstimator(3, DT)
    with pytest.raises(ValueError, match=r"\(T, 3\)"):
        est.run(np.zeros((10, 2)), np.zeros((10, 2)))
    with pytest.raises(ValueError, match="stride"):
        est.run(np.zeros((10, 3)), np.zeros((10, 3)), stride=0)
    with pytest.raises(ValueError, match="3 entries"):
        est.update(np.zeros(2), np.zeros(3))
