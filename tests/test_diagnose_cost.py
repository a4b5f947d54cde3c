"""``diagnose`` in memory linear in the record: the pieces that replaced all-at-once arrays
give what those gave (scipy's ``csd`` of every pair, a grid search that holds every grid
point's Grams, stacked Gram matrices), and the memory grows in proportion to the record."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from scipy.signal import csd

from algid.diagnosis import diagnose
from algid.diagnosis.core import EqSpec, prepare, window_stats
from algid.diagnosis.gram import cross_validate_grid, fold_fits, solve_gram, sse
from algid.diagnosis.model import cross_spectra
from algid.model.chain import TABLE1
from algid.recording import Recording
from algid.simulator import simulate


@pytest.mark.parametrize("T, c, nper", [(30000, 6, 256), (2000, 5, 64), (1001, 3, 33)])
def test_cross_spectra_are_scipy_csd_of_every_pair(T, c, nper):
    X = np.random.default_rng(T).standard_normal((T, c)) + np.arange(c)
    f, S = csd(X[:, :, None], X[:, None, :], fs=500.0, nperseg=nper, axis=0)
    f2, S2 = cross_spectra(X, 1 / 500.0, nper, chunk=7)
    np.testing.assert_array_equal(f, f2)
    np.testing.assert_allclose(S2, S, rtol=0, atol=1e-13 * np.abs(S).max())


def _stacked_model(seed: int, band_hz):
    """Two equations sharing one effect column, on 24 windows: (P, specs of grid value g)."""
    rng = np.random.default_rng(seed)
    T, dt = 24 * 40, 1e-3
    a = rng.standard_normal((T, 2))
    P = prepare(a, rng.standard_normal((T, 2)), dt, 40, band_hz=band_hz)
    X = [rng.standard_normal((P.y.shape[0], p)) for p in (3, 2)]
    base = rng.standard_normal(P.y.shape[0])

    def specs(g):
        effect = np.tanh(base / g)[:, None]
        return [
            EqSpec(e=e, X=X[e], y=X[e] @ np.arange(1.0, X[e].shape[1] + 1) + 0.3 * effect[:, 0], E=effect)
            for e in (0, 1)
        ]

    return P, specs


@pytest.mark.parametrize("band_hz", [None, 100.0])
def test_gram_blocks_are_the_stacked_matrices(band_hz):
    P, specs = _stacked_model(1, band_hz)
    st = window_stats(P, specs(0.7))
    theta = np.random.default_rng(2).standard_normal(st.G.shape[-1] - 1)
    dense = np.zeros(st.sub_shape + st.G.shape[-2:])  # (nw, S, E, P+1, P+1), as the stacked model has them
    for k, ix in enumerate(st.index):
        dense[:, :, k][..., ix[:, None], ix[None, :]] = st.blocks_band[k] if band_hz else st.blocks[k]
    np.testing.assert_allclose(st.sub_sse(np.arange(P.nw), theta, band=True), sse(dense, theta), rtol=1e-12)
    if not P.fit_band:
        full = np.zeros_like(dense)
        for k, ix in enumerate(st.index):
            full[:, :, k][..., ix[:, None], ix[None, :]] = st.blocks[k]
        np.testing.assert_allclose(st.G, full.sum(axis=(1, 2)), rtol=1e-12)


@pytest.mark.parametrize("band_hz", [None, 100.0])
def test_the_fitting_grams_need_no_scoring_blocks(band_hz):
    """window_stats without scoring gives the same fitting Grams, from whole windows, without
    the sub-block and band-projected blocks."""
    P, specs = _stacked_model(1, band_hz)
    full, fit_only = window_stats(P, specs(0.7)), window_stats(P, specs(0.7), scoring=False)
    np.testing.assert_allclose(fit_only.G, full.G, rtol=1e-12, atol=1e-12 * np.abs(full.G).max())
    assert fit_only.blocks == [] and fit_only.blocks_band == []


def test_one_pass_grid_search_is_the_all_at_once_search():
    P, specs = _stacked_model(3, 100.0)
    grid = np.geomspace(0.1, 10.0, 17)
    res = cross_validate_grid(P, lambda g, scoring: window_stats(P, specs(g), scoring), grid)
    # every grid point at once, the reference: the fitting Grams choose, the scoring ones score
    member = np.array([P.folds == k for k in range(P.nfolds)], dtype=float)
    fits = [fold_fits(window_stats(P, specs(g), scoring=False).G, member) for g in grid]
    stats = [window_stats(P, specs(g)) for g in grid]
    for k in range(P.nfolds):
        mask = P.folds == k
        gb = int(np.argmin([err[k + 1] for _, err in fits]))
        assert res.extra["g_index_folds"][k] == gb
        np.testing.assert_allclose(res.theta_folds[k], fits[gb][0][k + 1], rtol=1e-12)
        np.testing.assert_allclose(
            res.test_sub[mask], stats[gb].sub_sse(mask, fits[gb][0][k + 1], band=True), rtol=1e-12
        )
    best = int(np.argmin([err[0] for _, err in fits]))
    assert res.extra["g_index"] == best
    np.testing.assert_allclose(res.theta, solve_gram(stats[best].G.sum(axis=0)), rtol=1e-12)


def _peak_mb(duration_s: float) -> tuple[float, float]:
    r = simulate(TABLE1, lambda t: 5.0 * np.sin(2 * np.pi * np.array([1.3, 2.9, 7.1]) * t), duration_s, 1000.0)
    rng = np.random.default_rng(0)
    rec = Recording(t=r.t, u=r.u + 0.01 * rng.standard_normal(r.u.shape), a=r.a + 0.01 * rng.standard_normal(r.a.shape))
    data_mb = (rec.u.nbytes + rec.a.nbytes + rec.t.nbytes) / 2**20
    tracemalloc.start()
    try:
        diagnose(rec)
        return tracemalloc.get_traced_memory()[1] / 2**20, data_mb
    finally:
        tracemalloc.stop()


@pytest.mark.slow
def test_diagnose_memory_grows_with_the_record_not_faster():
    (p1, d1), (p2, d2) = _peak_mb(8.0), _peak_mb(24.0)
    per_mb = (p2 - p1) / (d2 - d1)
    # about 17 MB per MB of float64 data traced (numpy arrays); about 150 before the
    # grid search, the candidates' Grams and columns and the stacked matrices were cut
    assert per_mb < 30, (p1, p2, per_mb)


def test_an_empty_grid_is_refused_like_before():
    """A candidate whose grid is empty (an all-zero record's deformation quantiles) is skipped
    by the candidate loop, which catches ValueError."""
    P, specs = _stacked_model(4, None)
    with pytest.raises(ValueError, match="empty grid"):
        cross_validate_grid(P, lambda g, scoring: window_stats(P, specs(g), scoring), np.array([]))
