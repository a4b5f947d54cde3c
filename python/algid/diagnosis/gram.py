"""Per-window Gram matrices of stacked equations and the fits and cross-validation
built on them (a fit on any set of windows is a sum of Grams and a small solve)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .windows import N_SUB, Prepared, band_filter, detrend

__all__ = [
    "CVResult",
    "EqSpec",
    "WindowStats",
    "cross_validate",
    "GridWalk",
    "cross_validate_grid",
    "fold_fits",
    "score_walk",
    "walk_grid",
    "jackknife_std",
    "refine_min",
    "solve_gram",
    "sse",
    "window_stats",
]


@dataclass
class EqSpec:
    """One equation of a (possibly augmented) model.

    X : (N, p) own columns; y : (N,) target (:func:`target`); E : (N, q) columns of the
    shared effect parameters (None if none); w : weight of the equation.
    """

    e: int
    X: np.ndarray
    y: np.ndarray
    E: np.ndarray | None
    w: float = 1.0
    key: object = None  # when set, the detrended X and its Gram are cached under it


@dataclass
class WindowStats:
    """Per-window Gram matrices of a stacked model ``[theta_e1 .. theta_eE, gamma | y]``.

    G : (nw, P+1, P+1); the last row/column is the target. ``slices[k]`` are the
    parameter indices of equation k; ``shared`` those of the shared effect parameters.
    ``blocks[k]`` : (nw, S, m_k, m_k) contribution of equation k on each sub-block, over its
    own parameters, the shared ones and the target (``index[k]``: their places in
    ``0..P``; m_k = p_k + q + 1: an equation's Gram is zero elsewhere, so the blocks take
    ``E m^2`` numbers a sub-block where the stacked matrices would take ``E (P+1)^2``);
    ``blocks_band`` : the same for the band-projected columns (:func:`band_filter`; the
    scoring Grams; ``blocks`` itself when the band is the whole spectrum).
    """

    G: np.ndarray
    slices: list[slice]
    shared: slice
    eqs: list[int]
    blocks: list[np.ndarray]
    blocks_band: list[np.ndarray]
    index: list[np.ndarray]

    def eq_gram(self, k: int) -> np.ndarray:
        """(nw, m_k, m_k) Gram of equation ``k`` on every window (over ``index[k]``)."""
        return self.blocks[k].sum(axis=1)

    def sub_sse(self, rows: np.ndarray, theta: np.ndarray, band: bool) -> np.ndarray:
        """(len(rows), S, E) squared error of ``theta`` (P,) on every sub-block and
        equation of the windows ``rows`` (mask or indices), in band or over the whole band."""
        th = np.append(theta, -1.0)
        blocks = self.blocks_band if band else self.blocks
        return np.stack([sse(b[rows], th[ix], extended=True) for b, ix in zip(blocks, self.index)], axis=-1)

    @property
    def sub_shape(self) -> tuple[int, int, int]:
        """(nw, S, E)."""
        return (self.G.shape[0], N_SUB, len(self.eqs))

    def slim(self) -> WindowStats:
        """The layout (``slices``, ``shared``, ``eqs``) without the Grams, for a model whose
        cross-validation is done."""
        return WindowStats(
            G=np.zeros((0,)), slices=self.slices, shared=self.shared, eqs=self.eqs, blocks=[], blocks_band=[], index=[]
        )


def window_stats(P: Prepared, specs: list[EqSpec], scoring: bool = True) -> WindowStats:
    """Detrend and accumulate the per-window Grams of a stacked model; without ``scoring``
    only what a fit needs, ``G`` (no sub-block or band-projected blocks, unless the fit itself
    is in band)."""
    q = 0 if specs[0].E is None else specs[0].E.shape[1]
    sizes = [s.X.shape[1] for s in specs]
    Ptot = sum(sizes) + q
    slices, off = [], 0
    for p in sizes:
        slices.append(slice(off, off + p))
        off += p
    shared = slice(off, off + q)
    if not scoring and not (P.fit_band and not P.full_band):
        return _fitting_grams(P, specs, sizes, slices, shared)
    S = N_SUB
    band = not P.full_band

    def sub(Z):  # (nw, L, c) -> (nw, S, L/S, c)
        return Z.reshape(P.nw, S, P.L // S, Z.shape[-1])

    def block(p, gxx, gxr, grr):  # own | shared and target
        blk = np.empty((P.nw, S, p + q + 1, p + q + 1))
        blk[:, :, :p, :p] = gxx
        blk[:, :, :p, p:] = gxr
        blk[:, :, p:, :p] = gxr.swapaxes(-1, -2)
        blk[:, :, p:, p:] = grr
        return blk

    blocks, blocks_band, index = [], [], []
    G = np.zeros((P.nw, Ptot + 1, Ptot + 1))
    for k, s in enumerate(specs):
        rest = np.concatenate(([s.E] if q else []) + [s.y[:, None]], axis=1) * s.w
        Zr_w = detrend(P, rest)  # (nw, L, q+1)
        Zr = sub(Zr_w)  # (nw, S, L/S, q+1)
        cached = P._cache.get((s.key, s.w, band)) if s.key is not None else None
        if cached is None:
            Zx_w = detrend(P, s.X * s.w)
            Zx = sub(Zx_w)
            Zxb = sub(band_filter(P, Zx_w)) if band else Zx
            cached = (
                Zx,
                np.matmul(Zx.swapaxes(-1, -2), Zx),
                Zxb,
                np.matmul(Zxb.swapaxes(-1, -2), Zxb) if band else None,
            )
            if s.key is not None:
                P._cache[(s.key, s.w, band)] = cached
        Zx, gxx, Zxb, gxxb = cached
        p = sizes[k]
        ix = np.r_[np.arange(slices[k].start, slices[k].stop), np.arange(shared.start, shared.stop), Ptot]
        blocks.append(block(p, gxx, np.matmul(Zx.swapaxes(-1, -2), Zr), np.matmul(Zr.swapaxes(-1, -2), Zr)))
        if band:
            Zrb = sub(band_filter(P, Zr_w))
            blocks_band.append(
                block(p, gxxb, np.matmul(Zxb.swapaxes(-1, -2), Zrb), np.matmul(Zrb.swapaxes(-1, -2), Zrb))
            )
        index.append(ix)
        G[:, ix[:, None], ix[None, :]] += (blocks_band[-1] if band and P.fit_band else blocks[-1]).sum(axis=1)
    return WindowStats(
        G=G,
        slices=slices,
        shared=shared,
        eqs=[s.e for s in specs],
        blocks=blocks,
        blocks_band=blocks_band if band else (blocks if P.full_band else []),
        index=index,
    )


def _fitting_grams(
    P: Prepared, specs: list[EqSpec], sizes: list[int], slices: list[slice], shared: slice
) -> WindowStats:
    """:func:`window_stats` without ``scoring`` on a fit over the whole band: the per-window
    Grams ``G`` of whole detrended windows (no sub-blocks), the only statistics a fit needs.

    The detrended own columns ``Zx`` are orthogonal to each window's line, so ``Zx' Zr = Zx' R``
    and ``Zr' Zr = R' R - (B' R)' (B' R)`` (``B`` the window's orthonormal line basis): the shared
    and target columns ``R`` are never detrended themselves."""
    q = shared.stop - shared.start
    Ptot = shared.stop
    G = np.zeros((P.nw, Ptot + 1, Ptot + 1))
    for k, s in enumerate(specs):
        R = P.windows(np.concatenate(([s.E] if q else []) + [s.y[:, None]], axis=1) * s.w)  # (nw, L, q+1)
        p = sizes[k]
        if s.key is None:  # columns of this model alone
            Zx = detrend(P, s.X * s.w)
            gxx, gxr, C = np.matmul(Zx.swapaxes(-1, -2), Zx), np.matmul(Zx.swapaxes(-1, -2), R), P.basis.T @ R
        else:
            cached = P._cache.get((s.key, s.w, "window"))
            if cached is None:  # shared columns: [Zx | B]' row-major, one product with R gives Zx' R and B' R
                Zx = detrend(P, s.X * s.w)
                lhs = np.concatenate([Zx, np.broadcast_to(P.basis, (P.nw, P.L, 2))], axis=2).swapaxes(-1, -2)
                cached = P._cache[(s.key, s.w, "window")] = (np.ascontiguousarray(lhs), Zx.swapaxes(-1, -2) @ Zx)
            lhs, gxx = cached
            M = lhs @ R  # (nw, p+2, q+1)
            gxr, C = M[:, :p], M[:, p:]
        grr = np.matmul(R.swapaxes(-1, -2), R) - np.matmul(C.swapaxes(-1, -2), C)
        own, other = slices[k], slice(shared.start, Ptot + 1)  # the shared columns, then the target
        G[:, own, own] += gxx
        G[:, own, other] += gxr
        G[:, other, own] += gxr.swapaxes(-1, -2)
        G[:, other, other] += grr
    return WindowStats(G=G, slices=slices, shared=shared, eqs=[s.e for s in specs], blocks=[], blocks_band=[], index=[])


def solve_gram(G: np.ndarray) -> np.ndarray:
    """Least-squares parameters from Gram(s) (..., P+1, P+1) (target last) -> (..., P)
    (:func:`scaled_solve`)."""
    return scaled_solve(G[..., :-1, :-1], G[..., :-1, -1])


def scaled_solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``A^-1 b`` for normal matrices ``A`` (..., P, P) and right sides ``b`` (..., P),
    column-scaled, with a 1e-12 relative ridge against exactly collinear columns."""
    d = np.sqrt(np.clip(np.diagonal(A, axis1=-2, axis2=-1), 1e-300, None))
    As = A / d[..., :, None] / d[..., None, :]
    eye = np.eye(A.shape[-1])
    z = np.linalg.solve(As + 1e-12 * eye, (b / d)[..., None])[..., 0]
    return z / d


def sse(G: np.ndarray, theta: np.ndarray, extended: bool = False) -> np.ndarray:
    """Squared error of ``theta`` under Gram(s) ``G`` (..., P+1, P+1) -> (...);
    ``extended``: ``theta`` already ends with the target's -1. At least 0: the quadratic
    form of a Gram is, but rounding makes it slightly negative where the fit is exact
    (noise-free records)."""
    th = theta if extended else np.append(theta, -1.0)
    return np.maximum(np.einsum("...i,i->...", np.einsum("...ij,j->...i", G, th), th), 0.0)


@dataclass
class CVResult:
    """Cross-validated fit of a stacked model.

    theta : (P,) fit on all windows; theta_folds : (K, P) fits with fold k withheld;
    test_sub : (nw, S, E) in-band squared error (the metric of :mod:`.core`)
    of every sub-block and equation under the fit that withheld its window;
    test_sub_full : the same over the whole band; fit_sse : (nw,) in-sample error of
    ``theta``; extra : model-specific values (e.g. the nonlinear parameter).
    """

    theta: np.ndarray
    theta_folds: np.ndarray
    test_sub: np.ndarray
    fit_sse: np.ndarray
    stats: WindowStats
    extra: dict = field(default_factory=dict)
    test_sub_full: np.ndarray | None = None

    @property
    def test_sse_eq(self) -> np.ndarray:
        """(nw, E) withheld squared error per window and equation."""
        return self.test_sub.sum(axis=1)

    @property
    def test_sse(self) -> np.ndarray:
        """(nw,) withheld (in-band) squared error per window."""
        return self.test_sub.sum(axis=(1, 2))

    @property
    def test_sse_eq_full(self) -> np.ndarray:
        """(nw, E) withheld full-band squared error per window and equation."""
        return self.test_sub_full.sum(axis=1)


def cross_validate(P: Prepared, st: WindowStats) -> CVResult:
    """Fit on all windows and, for every fold, on the others; score withheld windows."""
    K = P.nfolds
    Gsum = st.G.sum(axis=0)
    theta = solve_gram(Gsum)
    thetas = np.zeros((K, theta.size))
    test = np.zeros(st.sub_shape)
    full = np.zeros_like(test)
    for k in range(K):
        mask = P.folds == k
        th = solve_gram(Gsum - st.G[mask].sum(axis=0))
        thetas[k] = th
        full[mask] = st.sub_sse(mask, th, band=False)
        test[mask] = full[mask] if st.blocks_band is st.blocks else st.sub_sse(mask, th, band=True)
    return CVResult(
        theta=theta, theta_folds=thetas, test_sub=test, fit_sse=sse(st.G, theta), stats=st, test_sub_full=full
    )


def fold_fits(G: np.ndarray, member: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The fit on all windows of per-window Grams ``G`` (nw, P+1, P+1) and, for every fold k of
    ``member`` (K, nw) (1 on the fold's windows), the fit on the other windows, in one solve:
    their parameters (K+1, P) and in-sample squared errors (K+1,), the all-window fit first."""
    Gsum = G.sum(axis=0)
    Gfit = np.concatenate([Gsum[None], Gsum - np.einsum("kw,wij->kij", member, G)])
    ths = solve_gram(Gfit)
    ext = np.concatenate([ths, -np.ones((ths.shape[0], 1))], axis=1)
    return ths, np.einsum("kij,ki,kj->k", Gfit, ext, ext)


def _first_min(new: float, old: float) -> bool:
    """``new`` takes the place of ``old`` as the running minimum, as ``np.argmin`` would
    choose: the first NaN wins, else the first strictly smaller value."""
    if np.isnan(old):
        return False
    return bool(np.isnan(new) or new < old)


@dataclass
class GridWalk:
    """The choices of a walk over ``grid`` (:func:`walk_grid`): ``pick`` (K+1,) the grid index
    every fold's training fit chose, then the all-window fit's; ``picked_theta`` (K, P) those
    fits; ``train_sse`` (K, ng) and ``fit_sse`` (ng,) their errors along the grid."""

    grid: np.ndarray
    pick: list[int]
    picked_theta: np.ndarray
    train_sse: np.ndarray
    fit_sse: np.ndarray


def walk_grid(P: Prepared, stats_of: Callable[[float, bool], WindowStats], grid: np.ndarray) -> GridWalk:
    """Walk ``grid`` once with the fitting Grams alone (``stats_of(g, False)``): every fold's
    grid value chosen by the (full-band) error on its training windows, as the fit itself,
    and the all-window fit's by its error."""
    K = P.nfolds
    ng = len(grid)
    if ng == 0:  # e.g. the quantiles of a deformation that is zero throughout
        raise ValueError("cross_validate_grid: empty grid")
    member = np.array([P.folds == k for k in range(K)], dtype=float)  # (K, nw): fold k's windows
    fit_all = np.zeros(ng)
    tr = np.zeros((K, ng))
    pick = [-1] * (K + 1)  # the running choice of every fold, then of the all-window fit
    picked_theta: list = [None] * K
    for g in range(ng):
        ths, err = fold_fits(stats_of(grid[g], False).G, member)
        fit_all[g], tr[:, g] = err[0], err[1:]
        for k in range(K):
            if pick[k] < 0 or _first_min(tr[k, g], tr[k, pick[k]]):
                pick[k], picked_theta[k] = g, ths[k + 1]
        if pick[K] < 0 or _first_min(fit_all[g], fit_all[pick[K]]):
            pick[K] = g
    return GridWalk(np.asarray(grid), pick, np.array(picked_theta), tr, fit_all)


def score_walk(P: Prepared, stats_of: Callable[[float, bool], WindowStats], walk: GridWalk) -> CVResult:
    """The cross-validation of a walk: the withheld windows of every fold scored at the grid
    point the fold chose (refined by a parabola through the three best neighbours, reported
    in ``extra["g_folds"]``); the all-window fit at the best grid point (``extra["g"]``
    refined, ``extra["g_index"]``). The scoring statistics are built for the chosen grid
    points only: memory of at most ``K + 1`` models' Grams, whatever the grid's size."""
    K, grid, pick = P.nfolds, walk.grid, walk.pick
    kept = {i: stats_of(grid[i], True) for i in set(pick)}
    best = pick[K]
    res = cross_validate(P, kept[best])
    test = np.zeros(kept[best].sub_shape)
    full = np.zeros_like(test)
    g_folds = np.zeros(K)
    for k in range(K):
        mask, gb = P.folds == k, pick[k]
        g_folds[k] = refine_min(grid, walk.train_sse[k], gb)
        test[mask] = kept[gb].sub_sse(mask, walk.picked_theta[k], band=True)
        full[mask] = kept[gb].sub_sse(mask, walk.picked_theta[k], band=False)
    res.theta_folds = walk.picked_theta.copy()
    res.test_sub = test
    res.test_sub_full = full
    res.extra = {
        "g": refine_min(grid, walk.fit_sse, best),
        "g_index": best,
        "g_folds": g_folds,
        "g_index_folds": np.array(pick[:K], dtype=int),
        "grid_sse": walk.fit_sse,
    }
    return res


def cross_validate_grid(P: Prepared, stats_of: Callable[[float, bool], WindowStats], grid: np.ndarray) -> CVResult:
    """Cross-validation of a model with one nonlinear parameter known on ``grid``;
    ``stats_of(g, scoring)`` gives the model's :class:`WindowStats` at grid value ``g``
    (``scoring``: :func:`window_stats`): :func:`walk_grid`, then :func:`score_walk`."""
    return score_walk(P, stats_of, walk_grid(P, stats_of, grid))


def refine_min(grid: np.ndarray, f: np.ndarray, i: int) -> float:
    """Vertex of the parabola through the grid minimum and its neighbours."""
    if i == 0 or i == len(grid) - 1:
        return float(grid[i])
    x0, x1, x2 = grid[i - 1 : i + 2]
    y0, y1, y2 = f[i - 1 : i + 2]
    den = (x0 - x1) * (x0 - x2) * (x1 - x2)
    A = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / den
    B = (x2**2 * (y0 - y1) + x1**2 * (y2 - y0) + x0**2 * (y1 - y2)) / den
    if A <= 0:
        return float(grid[i])
    return float(np.clip(-B / (2 * A), x0, x2))


def jackknife_std(estimates: np.ndarray) -> np.ndarray:
    """Delete-a-group jackknife standard deviation from the K fold-withheld estimates."""
    est = np.asarray(estimates, dtype=float)
    K = est.shape[0]
    if K < 2:
        return np.full(est.shape[1:], np.nan)
    return np.sqrt((K - 1) / K * ((est - est.mean(axis=0)) ** 2).sum(axis=0))
