"""Run a :class:`~algid.identification.plan.Plan` over whole signals: one estimate of the
3n+1 parameters and its history.

* Single window: :class:`algid.ChainEstimator` from the first sample to the last; the
  estimate is eq. 7 at the end, the history its value after every sample.
* Continuous: :class:`algid.ContinuousEstimator` with the plan's window, prefilter and
  window method. Weak-form windows: the estimate is the estimator's own, the solution of
  the summed normal equations of every window of the record, and the history its running
  value at up to :data:`HISTORY_ROWS` instants. Algebraic windows: the estimate aggregates
  *every* window result of the record (:func:`aggregate`, an interquartile mean per
  parameter: the window results are heavy-tailed ratios of random determinants, so the
  middle half is averaged and the tails are dropped, which costs little against the mean
  on Gaussian results and is immune to the odd wild window), the history that aggregate
  over the window results harvested up to each history instant. Either way ``spread`` is
  the scatter of the window results.

Parameters are packed ``m1..mn, c1..cn, k1..k{n+1}`` (interior springs fused as the
estimators do; n = 1 with walls: k1 holds k1 + k2, k2 is NaN; free end: k_{n+1} = 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..estimator import ChainEstimator
from ..estimator.continuous import ContinuousEstimator
from .plan import Plan

#: Most rows of a continuous history.
HISTORY_ROWS = 200
#: Share of the window results dropped at each end before averaging.
TRIM = 0.25


@dataclass
class Run:
    """One estimate and its history.

    theta : (3n+1,) packed estimate; ``time_s`` (R,) history instants [s] (end of the data
    described); ``history`` (R, 3n+1); ``windows`` number of window results used
    (0 for the single window); ``spread`` (3n+1,) the window results' scatter, 1.4826 times
    their median absolute deviation (NaN for the single window). Weak-form windows also give
    their generalised least squares uncertainty: ``sigma`` (3n+1,) of the estimate,
    ``history_sigma`` (R, 3n+1) of the history rows, and ``scatter`` (3n+1,), 1.4826 times the
    median absolute deviation of the window results from the estimate in units of each
    window's own standard deviation (about 1 when eq. 1 and white noise explain the windows);
    NaN otherwise.
    """

    theta: np.ndarray
    time_s: np.ndarray
    history: np.ndarray
    windows: int
    spread: np.ndarray = None
    sigma: np.ndarray = None
    history_sigma: np.ndarray = None
    scatter: np.ndarray = None

    def __post_init__(self) -> None:
        nan = np.full(self.theta.shape, np.nan)
        self.spread = nan if self.spread is None else self.spread
        self.sigma = nan if self.sigma is None else self.sigma
        self.scatter = nan if self.scatter is None else self.scatter
        if self.history_sigma is None:
            self.history_sigma = np.full(self.history.shape, np.nan)


def aggregate(results: np.ndarray) -> np.ndarray:
    """Interquartile mean of every column over its finite entries (NaN if none)."""
    S = np.sort(np.asarray(results, dtype=float), axis=0)  # NaN sorts last
    count = np.sum(np.isfinite(S), axis=0)
    cut = np.floor(TRIM * count).astype(int)
    cum = np.vstack([np.zeros(S.shape[1]), np.cumsum(np.where(np.isfinite(S), S, 0.0), axis=0)])
    lo, hi = cut, count - cut
    cols = np.arange(S.shape[1])
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, (cum[hi, cols] - cum[lo, cols]) / (hi - lo), np.nan)


def _column_median(W: np.ndarray) -> np.ndarray:
    """Median of every column over its finite entries, NaN for a column without any
    (numpy's nanmedian warns there, and warnings filters are not safe across threads)."""
    out = np.full(W.shape[1], np.nan)
    for j in range(W.shape[1]):
        col = W[np.isfinite(W[:, j]), j]
        if col.size:
            out[j] = np.median(col)
    return out


def run_window(a: np.ndarray, u: np.ndarray, dt: float, boundary: str) -> Run:
    """The paper's single growing window over the whole record."""
    est = ChainEstimator(a.shape[1], dt, boundary=boundary)
    out = est.run(a, u)
    hist = np.concatenate([out["mass"], out["damping"], out["stiffness"]], axis=1)
    hist[~np.repeat(np.all(out["valid"], axis=1, keepdims=True), hist.shape[1], axis=1)] = np.nan
    theta = np.concatenate([est.mass, est.damping, est.stiffness])
    theta[np.concatenate([~est.valid, ~est.valid, _spring_validity(est.valid, boundary)])] = np.nan
    return Run(theta=theta, time_s=out["time_s"], history=hist, windows=0)


def _spring_validity(valid: np.ndarray, boundary: str) -> np.ndarray:
    """Springs without a valid neighbouring DOF: their estimate is not reported."""
    n = valid.size
    ok = np.zeros(n + 1, bool)
    ok[:n] |= valid
    ok[1:] |= valid
    return ~ok


def run_continuous(a: np.ndarray, u: np.ndarray, dt: float, boundary: str, plan: Plan, history: bool = True) -> Run:
    """Reseeded staggered windows of the plan over the whole record, with (``history``) the
    estimate's course or (without) its final value only."""
    T = a.shape[0]
    weak = plan.method == "weak_form"
    est = ContinuousEstimator(
        a.shape[1],
        dt,
        boundary=boundary,
        method=plan.method or "algebraic",
        window_s=plan.window_s,
        prefilter_hz=plan.prefilter_hz,
        stagger=plan.stagger,
        detect=False,
        **_band(plan, dt),
        **({"accel_noise": plan.noise_rms[0], "force_noise": plan.noise_rms[1]} if plan.noise_rms[0] >= 0 else {}),
        # derived accelerations repeat exactly while an encoder's axis stands still: not a dead sensor
        **({} if plan.method == "weak_form" else {"stuck_samples": 0, "clip_samples": 0}),
    )
    out = est.run(a, u, stride=max(1, T // HISTORY_ROWS) if (weak and history) else T)
    W, at = out["windows"], out["window_sample"]
    keep = np.any(np.isfinite(W), axis=1)
    W, at = W[keep], at[keep]
    if W.shape[0] == 0:
        nan = np.full(a.shape[1] * 3 + 1, np.nan)
        return Run(theta=nan, time_s=np.array([T * dt]), history=nan[None, :], windows=0)
    spread = 1.4826 * _column_median(np.abs(W - _column_median(W)))
    if weak:
        theta, sigma = np.asarray(est.estimate, float), np.asarray(est.sigma, float)
        with np.errstate(invalid="ignore", divide="ignore"):
            z = (W - theta) / np.sqrt(out["window_variance"][keep])
        scatter = 1.4826 * _column_median(np.abs(z))
        # rows where every parameter finite at the end is (they join one by one)
        final = np.isfinite(theta)
        rows = np.all(np.isfinite(out["estimate"][:, final]), axis=1) if history else np.zeros(0, bool)
        if rows.any():
            at_s, hist, hist_sigma = out["time_s"][rows], out["estimate"][rows], out["sigma"][rows]
        else:  # no history asked for, or none complete: the final estimate alone
            at_s, hist, hist_sigma = np.array([T * dt]), theta[None, :], sigma[None, :]
        return Run(
            theta=theta,
            time_s=at_s,
            history=hist,
            windows=int(W.shape[0]),
            spread=spread,
            sigma=sigma,
            history_sigma=hist_sigma,
            scatter=scatter,
        )
    rows = min(HISTORY_ROWS, W.shape[0]) if history else 1
    stops = np.unique(np.linspace(1, W.shape[0], rows).round().astype(int))
    hist = np.array([aggregate(W[:s]) for s in stops])
    return Run(theta=aggregate(W), time_s=at[stops - 1] * dt, history=hist, windows=int(W.shape[0]), spread=spread)


def _band(plan: Plan, dt: float) -> dict:
    """Weak-form windows: test functions up to the plan's prefilter cut-off (1.25 x the top of
    the signal band and of the modes), as the algebraic windows' low-pass; the estimator's
    default (fs/20) when the plan has no prefilter."""
    if plan.method != "weak_form" or not plan.prefilter_hz > 0:
        return {}
    L = round(plan.window_s / dt)  # the estimator's limits: 2 <= Q = band L dt, 2 Q + 1 <= L / 2, band < 0.45 fs
    Q = int(np.clip(np.floor(plan.prefilter_hz * L * dt), 2, (L // 2 - 1) // 2))
    return {"band_hz": min((Q + 0.5) / (L * dt), 0.449 / dt)}


def run_plan(
    a: np.ndarray, u: np.ndarray, dt: float, boundary: str, plan: Plan, history: bool = True, missing=None
) -> Run:
    """Run ``plan`` on accelerations ``a`` [m/s^2] and forces ``u`` [N], both (T, n); without
    ``history`` a continuous run keeps only its final row. ``missing``: (T,) bool or None,
    instants the estimators see as not a number in every channel (screened samples,
    :mod:`.screen`): the single window reseeds there, the continuous one drops its windows
    in flight."""
    if missing is not None and np.any(missing):
        a, u = np.where(missing[:, None], np.nan, a), np.where(missing[:, None], np.nan, u)
    if plan.estimator == "window":
        return run_window(a, u, dt, boundary)
    return run_continuous(a, u, dt, boundary, plan, history)
