"""``algid.identify(recording)``: the whole-record identification with uncertainty and
verdicts.

0. Screen: finite samples far outside their channel's robust range are taken out and
   treated as missing (:mod:`.screen`).
1. Signals: mains hum notched out of every channel alike (:func:`algid.noise.without_hum`);
   the measured accelerations, or the derivatives of the velocities or displacements
   (:func:`algid.recording.accelerations`); the forces.
2. Noise model and signal band of the recording (:mod:`algid.noise`).
3. Plan (:mod:`.plan`): which estimator; for the continuous estimator, a first run with a
   window from the force's median frequency gives a first chain, whose lowest natural
   frequency gives the first guess of the window; every multiple of it in
   :data:`~.plan.WINDOW_MULTIPLES` is then run and scored by the root-mean-square error the
   bootstrap measures on :data:`SELECT_REPLICATES` surrogates (in shares of the force, mean
   over the parameters), and the best is kept. Longer windows average more but integrate
   more noise (their bias grows); which wins depends on the record, so the record decides.
4. Uncertainty and bias by parametric bootstrap on surrogates of the recording
   (:mod:`.surrogate`). A bias larger than three times its own standard error is taken off
   the estimate (the noise bias of the iterated integrals, errors-in-variables), and the
   uncertainty then includes the bias's standard error. Where the recording's window
   results scatter more than the surrogates' (1.4826 MAD, like for like), the record varies
   in a way its noise cannot explain (an effect outside eq. 1 that the windows see
   differently, friction at the motion's reversals for instance), and the uncertainty is
   scaled up by that ratio.
5. Verdicts per parameter and DOF (:mod:`.verdicts`).
"""

from __future__ import annotations

import warnings
from dataclasses import replace
from typing import Callable, Optional

import numpy as np

from ..noise import NoiseModel, analyse, without_hum
from ..recording import DEFAULT_DIFF_POINTS, Recording, accelerations, parameter_units
from ..recording import motion as recording_motion
from .plan import Plan, make_plan, natural_frequencies_hz, window_candidates, window_limits
from .result import Identification
from .runner import Run, run_plan
from .screen import screen
from .surrogate import REPLICATES, bootstrap
from .verdicts import judge, scales

#: A bootstrap bias is taken off the estimate when it exceeds this many of its standard
#: errors (3: a correction by chance on 0.3 % of the parameters).
BIAS_Z = 3.0
#: Replicates per candidate window when the window length is chosen.
SELECT_REPLICATES = 4
#: When the best window is the longest (shortest) tried, longer (shorter) ones by this
#: factor are tried, at most this many times, while they score better.
EXTEND_FACTOR = 1.4
EXTEND_STEPS = 4

ProgressFn = Optional[Callable[[str, float], None]]


def _progress(cb: ProgressFn, stage: str, fraction: float) -> None:
    if cb is not None:
        cb(stage, fraction)


def _surrogate_band(nm: NoiseModel, theta: np.ndarray, n: int, boundary: str) -> float:
    """Band edge [Hz] of the surrogate motion: the signal band, widened to hold every
    natural frequency of the estimate with a margin."""
    return max([nm.f_hi] + [1.25 * float(f) for f in natural_frequencies_hz(theta, n, boundary)])


def _select_window(
    a,
    u,
    motion,
    nm: NoiseModel,
    plan: Plan,
    boundary: str,
    forced,
    duration: float,
    seed: int,
    progress: ProgressFn,
    missing: np.ndarray,
) -> tuple[Plan, Run]:
    """Try the window candidates of ``plan``; keep the one with the lowest bootstrap error
    (``missing``: the screened instants, :mod:`.screen`)."""
    n = u.shape[1]
    cands = window_candidates(plan, nm, duration)

    def score(cand: Plan) -> tuple[float, Run]:
        run = run_plan(a, u, nm.dt, boundary, cand, missing=missing)
        boot = bootstrap(
            run.theta,
            motion,
            nm,
            cand,
            boundary,
            _surrogate_band(nm, run.theta, n, boundary),
            forced,
            SELECT_REPLICATES,
            seed,
            history=False,
            missing=missing,
        )
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns: parameters not estimated
            rmse = np.sqrt(np.nanmean((boot.replicates - run.theta) ** 2, axis=0))
        share = rmse * scales(n, boundary, boot.motion, u, forced)[0]
        return (float(np.nanmean(share)) if np.any(np.isfinite(share)) else np.inf), run

    scored = []
    for q, cand in enumerate(cands):
        scored.append(score(cand))
        _progress(progress, "window length", (q + 1) / (len(cands) + EXTEND_STEPS))
    best = min(range(len(cands)), key=lambda q: scored[q][0])
    lengths = sorted(c.window_s for c in cands)
    lo, hi = window_limits(nm, duration)
    step = (
        EXTEND_FACTOR
        if cands[best].window_s == lengths[-1]
        else (1.0 / EXTEND_FACTOR if cands[best].window_s == lengths[0] else None)
    )
    for _ in range(EXTEND_STEPS if step else 0):  # the best is at an end of the range: look beyond
        L = float(np.clip(cands[best].window_s * step, lo, hi))
        if abs(L / cands[best].window_s - 1.0) < 0.05:
            break
        cand = replace(cands[best], window_s=L, window_basis=f"{L / plan.window_s:.3g} x ({plan.window_basis})")
        result = score(cand)
        _progress(progress, "window length", (len(scored) + 1) / (len(cands) + EXTEND_STEPS))
        if not result[0] < scored[best][0]:
            break
        cands.append(cand)
        scored.append(result)
        best = len(cands) - 1
    _progress(progress, "window length", 1.0)
    return cands[best], scored[best][1]


def identify(
    rec: Recording,
    boundary: str = "fixed",
    estimator: str = "auto",
    replicates: int = REPLICATES,
    seed: int = 0,
    progress: ProgressFn = None,
) -> Identification:
    """Identify the chain of a whole recording, with one standard deviation per parameter
    and a verdict on each.

    Parameters
    ----------
    rec : Recording
        Forces and accelerations or displacements (:class:`algid.recording.Recording`).
    boundary : {"fixed", "free"}
        Right end of the chain.
    estimator : {"auto", "window", "continuous"}
        ``auto`` chooses from the recording (:mod:`algid.identification.plan`).
    replicates : int
        Surrogate replicates of the bootstrap (>= 2).
    seed : int
        Seed of the surrogates' noise (the result is reproducible).
    progress : callable ``(stage, fraction)`` or None
        Called as the work proceeds.

    Returns
    -------
    Identification
    """
    if boundary not in ("fixed", "free"):
        raise ValueError(f"boundary must be 'fixed' or 'free', got {boundary!r}")
    if int(replicates) < 2:
        raise ValueError(f"replicates must be >= 2, got {replicates}")
    rec, screened = screen(rec, reach=0 if rec.a is not None else DEFAULT_DIFF_POINTS // 2)
    missing = screened.rows
    rec, hum = without_hum(rec)
    n, dt = rec.n, float(rec.dt)
    a = accelerations(rec, DEFAULT_DIFF_POINTS)
    kind, motion = recording_motion(rec)
    nm = analyse(rec.u, motion, dt, kind)
    duration = rec.t.size * dt
    forced = np.any(rec.u != 0.0, axis=0)
    plan = make_plan(nm, duration, estimator)
    _progress(progress, "first estimate", 0.0)
    run = run_plan(a, rec.u, dt, boundary, plan, history=False, missing=missing)
    _progress(progress, "first estimate", 1.0)
    if plan.estimator == "continuous":
        plan = make_plan(nm, duration, estimator, natural_frequencies_hz(run.theta, n, boundary))
        plan, run = _select_window(a, rec.u, motion, nm, plan, boundary, forced, duration, seed, progress, missing)
    boot = bootstrap(
        run.theta,
        motion,
        nm,
        plan,
        boundary,
        _surrogate_band(nm, run.theta, n, boundary),
        forced,
        int(replicates),
        seed,
        DEFAULT_DIFF_POINTS,
        progress=lambda f: _progress(progress, "uncertainty", f),
        missing=missing,
    )
    stderr_bias = boot.sigma / np.sqrt(replicates)
    correct = np.isfinite(boot.bias) & (np.abs(boot.bias) > BIAS_Z * stderr_bias)
    theta = np.where(correct, run.theta - np.nan_to_num(boot.bias), run.theta)
    sigma = np.where(correct, np.sqrt(boot.sigma**2 + stderr_bias**2), boot.sigma)
    method_bias = np.where(np.isfinite(boot.method_bias), boot.method_bias, 0.0)
    sigma = np.sqrt(sigma**2 + method_bias**2)  # the method's own error on this spectrum, not removed
    with np.errstate(invalid="ignore", divide="ignore"):
        excess = np.where(np.isfinite(run.spread / boot.spread), run.spread / boot.spread, 1.0)
    sigma = sigma * np.maximum(excess, 1.0)
    verdicts = judge(theta, sigma, n, boundary, boot.motion, rec.u, forced, nm, excess)
    # no value at all where the record has no scale for it (an unforced DOF) or the
    # estimator's systems were singular
    blank = np.array([v.status == "not_identifiable" and not np.isfinite(v.share) for v in verdicts])
    theta, sigma = np.where(blank, np.nan, theta), np.where(blank, np.nan, sigma)
    return Identification(
        n=n,
        boundary=boundary,
        dt=dt,
        samples=int(rec.t.size),
        plan=plan,
        noise=nm,
        theta=theta,
        sigma=sigma,
        raw=run.theta,
        bias=np.where(correct, boot.bias, 0.0),
        method_bias=method_bias,
        verdicts=verdicts,
        time_s=run.time_s,
        history=run.history,
        history_sigma=boot.history_sigma,
        windows=run.windows,
        replicates=int(replicates),
        motion=kind,
        path=rec.path,
        hum_hz=tuple(hum),
        units=parameter_units(rec),
        recording_notes=tuple(rec.notes),
        screened=screened,
    )
