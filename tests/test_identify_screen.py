"""The robust-range screen of ``algid identify`` (:mod:`algid.identification.screen`): a
finite sample 1e3-1e100 times its channel's signal is taken out and treated as missing, the
estimates stay within their uncertainty of the clean record's (or are not valid), never an
impossible estimate marked valid; a clean record screens nothing."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import algid
from algid.identification.screen import OUTLIER_RANGE, outliers, screen
from algid.model.chain import TABLE1
from algid.recording import Recording, save_recording
from algid.simulator.scenarios import impact_test
from signals import multisine, simulate_chain

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
#: (channel, row as a share of the record) of the outliers: one channel, then three.
LAYOUTS = {"one": [("a", 1, 0.55)], "several": [("u", 0, 0.31), ("a", 2, 0.62), ("a", 0, 0.8)]}


@pytest.fixture(scope="module")
def noisy():
    """Table 1 under the multisine, 6 s, 40 dB on forces and accelerations."""
    t, a, u, _ = simulate_chain(TABLE1, multisine(3), 6.0)
    rng = np.random.default_rng(7)
    a = a + 0.01 * a.std(axis=0) * rng.standard_normal(a.shape)
    u = u + 0.01 * u.std(axis=0) * rng.standard_normal(u.shape)
    return t, u, a


@pytest.fixture(scope="module")
def noisy_clean_result(noisy):
    t, u, a = noisy
    return algid.identify(Recording(t=t, u=u, a=a), replicates=4)


def _broken(t, u, a, layout, factor):
    u, a = u.copy(), a.copy()
    for role, j, share in LAYOUTS[layout]:
        arr = u if role == "u" else a
        arr[int(share * t.size), j] = factor * arr[:, j].std()
    return Recording(t=t, u=u, a=a)


def _no_impossible_valid(res) -> None:
    n = res.n
    for p, v in enumerate(res.verdicts):
        if v.valid:
            assert np.isfinite(res.theta[p])
            assert res.theta[p] > 0 if p < n else res.theta[p] >= 0, (v.name, res.theta[p])


def test_a_clean_record_screens_nothing(noisy, noisy_clean_result):
    t, u, a = noisy
    assert noisy_clean_result.screened.count == 0
    assert noisy_clean_result.to_json()["screened"]["count"] == 0
    assert "screened" not in noisy_clean_result.summary()
    # an impact-hammer test with a single 0.5-1.5 ms hit is the clean record closest to the
    # rule: its force is zero but for a handful of samples
    for seed in range(4):
        rec = impact_test(seed=seed, hits=1).recording
        assert screen(rec)[1].count == 0


@pytest.mark.parametrize("factor", [1e3, 1e10, 1e100])
@pytest.mark.parametrize("layout", ["one", "several"])
def test_outliers_are_screened_and_the_estimates_hold(noisy, noisy_clean_result, layout, factor):
    t, u, a = noisy
    res = algid.identify(_broken(t, u, a, layout, factor), replicates=4)
    assert res.screened.count == len(LAYOUTS[layout])
    assert sorted(res.screened.channels) == sorted(f"{r}{j + 1}" for r, j, _ in LAYOUTS[layout])
    clean = noisy_clean_result
    _no_impossible_valid(res)
    assert res.valid
    tol = 4 * np.hypot(res.sigma, clean.sigma) + 1e-9 * np.abs(clean.theta)
    assert np.all(np.abs(res.theta - clean.theta) <= tol), (res.theta, clean.theta, tol)


@pytest.mark.parametrize("factor", [1e3, 1e100])
def test_single_window_reseeds_after_a_screened_sample(factor):
    t, a, u, _ = simulate_chain(TABLE1, multisine(3), 1.0)
    mid, end = Recording(t=t, u=u, a=a.copy()), Recording(t=t, u=u.copy(), a=a.copy())
    mid.a[400, 0] = factor * a[:, 0].std()
    res = algid.identify(mid, estimator="window", replicates=4)
    assert res.screened.count == 1 and res.screened.samples[0] == 400
    assert res.valid
    truth = np.concatenate([TABLE1.mass, TABLE1.damping, TABLE1.stiffness])
    np.testing.assert_allclose(res.raw, truth, rtol=1e-7)  # the window after the reseed is exact
    assert np.all(np.abs(res.theta - truth) <= 3 * res.sigma + 1e-7 * truth)  # and the bootstrap's correction honest
    # an outlier two samples before the end leaves nothing to estimate from: not valid
    end.u[-3, 1] = -factor * u[:, 1].std()
    res = algid.identify(end, estimator="window", replicates=4)
    assert res.screened.count == 1 and not res.valid
    _no_impossible_valid(res)


def test_rule_on_one_channel():
    y = np.sin(np.linspace(0.0, 20.0, 1000))
    assert not outliers(y).any()
    y[100] = 1.1 * OUTLIER_RANGE  # beyond OUTLIER_RANGE x the sine's range (about 1)
    y[200] = 0.8 * OUTLIER_RANGE  # within
    assert np.flatnonzero(outliers(y)).tolist() == [100]
    flat = np.zeros(500)
    flat[7] = 1e-3  # an unforced channel with a glitch: everything off its constant
    assert np.flatnonzero(outliers(flat)).tolist() == [7]


def test_screened_samples_are_bridged_and_derivative_stencils_excluded():
    t = np.arange(200) * 1e-3
    x = np.sin(2 * np.pi * 5 * t)[:, None]
    x_bad = x.copy()
    x_bad[50] = 1e6
    rec, found = screen(Recording(t=t, u=np.cos(t)[:, None], x=x_bad), reach=2)
    assert found.samples.tolist() == [50] and found.channels == ("x1",)
    assert found.values[0] == 1e6 and found.times_s[0] == pytest.approx(0.05)
    assert np.flatnonzero(found.rows).tolist() == [48, 49, 50, 51, 52]
    assert rec.x[50, 0] == pytest.approx(0.5 * (x[49, 0] + x[51, 0]))
    assert np.array_equal(np.delete(rec.x, 50), np.delete(x, 50))


def test_command_line_reports_the_screened_samples(noisy, tmp_path):
    t, u, a = noisy
    path = save_recording(tmp_path / "glitch.csv", _broken(t, u, a, "several", 1e10))
    out = tmp_path / "est.json"
    proc = subprocess.run(
        [sys.executable, "-m", "algid.cli", "identify", str(path), "--json", str(out), "--replicates", "2"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(out.read_text())["screened"]
    assert doc["count"] == 3 and doc["rows_excluded"] == 3
    assert [s["channel"] for s in doc["samples"]] == ["u1", "a3", "a1"]
    assert doc["samples"][0]["sample"] == int(0.31 * t.size) and doc["samples"][0]["value"] > 1e10
    assert "screened 3 samples" in proc.stderr and "u1 at 1.86 s" in proc.stderr
    assert "screened 3 samples" in proc.stdout


@pytest.mark.skipif(not DATA.is_dir(), reason=f"measured data not present at {DATA}")
def test_measured_records_screen_nothing():
    from algid.recording.datasets import f16_chain_recording, silverbox_recording

    assert screen(silverbox_recording(DATA, "all"))[1].count == 0
    for level in (1, 3, 5, 7):
        assert screen(f16_chain_recording(DATA, level))[1].count == 0
