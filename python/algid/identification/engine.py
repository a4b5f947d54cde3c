"""``algid.identify(recording)``: the whole-record identification with uncertainty and
verdicts, in stages, each entered once:

0. Screen: finite samples far outside their channel's robust range are taken out and
   treated as missing (:mod:`.screen`).
1. Signals: mains hum notched out of every channel alike (:func:`algid.noise.without_hum`);
   the measured accelerations, or the derivatives of the velocities or displacements
   (:func:`algid.recording.accelerations`); the forces.
2. Noise model and signal band of the recording (:mod:`algid.noise`).
3. Plan (:mod:`.plan`): which estimator and its settings, from the recording's time scales
   and a first look at the chain (:func:`.motion.equation_error_fit`: eq. 1 on the DFT bins
   the forces excite), whose lowest natural frequency sets the window length.
4. Estimate: the plan run over the whole record (:mod:`.runner`); the algebraic windows'
   length is first chosen among multiples of the plan's by the error a bootstrap measures
   on each (:func:`.surrogate.select_window`).
5. Uncertainty (:mod:`.uncertainty`): the weak-form windows' own covariance, or a parametric
   bootstrap for the algebraic windows; the method's own error; the window results' scatter
   beyond what noise explains.
6. Fit check (:func:`.augmented.fit_check`): the diagnosis's verdict on the record; unless
   it is ``none``, the linear chain's determined estimates are ``model_misfit``.
7. Verdicts per parameter and DOF (:mod:`.verdicts`).

With ``effects``, stages 3-6 are the diagnosis's fit of eq. 1 with the effects and its check
(:mod:`.augmented`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Callable, Optional

import numpy as np

from ..noise import analyse, without_hum
from ..recording import DEFAULT_DIFF_POINTS, Recording, accelerations, as_recording, parameter_units
from ..recording import motion as recording_motion
from .augmented import fit_check, fit_with_effects
from .motion import equation_error_fit
from .plan import make_plan, natural_frequencies_hz
from .result import Identification
from .runner import run_plan
from .screen import screen
from .surrogate import REPLICATES, select_window
from .uncertainty import estimate_uncertainty
from .verdicts import judge

ProgressFn = Optional[Callable[[str, float], None]]


def _progress(cb: ProgressFn, stage: str, fraction: float) -> None:
    if cb is not None:
        cb(stage, fraction)


def _estimate(rec, a, motion, nm, boundary, estimator, replicates, seed, missing, progress):
    """Stages 3-5: the plan, its run over the record and the run's uncertainty."""
    duration, forced = rec.t.size * rec.dt, np.any(rec.u != 0.0, axis=0)
    first = natural_frequencies_hz(equation_error_fit(rec.u, motion, nm, boundary), rec.n, boundary)
    plan = make_plan(nm, duration, estimator, first)
    _progress(progress, "estimate", 0.0)
    if plan.method == "algebraic":
        plan, run = select_window(
            a,
            rec.u,
            motion,
            nm,
            plan,
            boundary,
            forced,
            duration,
            seed,
            missing,
            lambda f: _progress(progress, "estimate", f),
        )
    else:
        run = run_plan(a, rec.u, float(rec.dt), boundary, plan, missing=missing)
    _progress(progress, "estimate", 1.0)
    unc = estimate_uncertainty(
        run,
        motion,
        nm,
        plan,
        boundary,
        forced,
        int(replicates),
        seed,
        DEFAULT_DIFF_POINTS,
        missing,
        progress=lambda f: _progress(progress, "uncertainty", f),
    )
    return plan, run, unc


def identify(
    rec: Recording,
    boundary: str = "fixed",
    estimator: str = "auto",
    replicates: int = REPLICATES,
    seed: int = 0,
    progress: ProgressFn = None,
    effects: Sequence[str] = (),
    **reading,
) -> Identification:
    """Identify the chain of a whole recording, with one standard deviation per parameter
    and a verdict on each.

    Parameters
    ----------
    rec : Recording, path or DataFrame
        Forces and accelerations or displacements (:class:`algid.recording.Recording`), or
        what :func:`algid.load_recording` reads with its default column names and units.
    boundary : {"fixed", "free"}
        Right end of the chain.
    estimator : {"auto", "window", "continuous"}
        ``auto`` chooses from the recording (:mod:`algid.identification.plan`).
    replicates : int
        Surrogate replicates of the bootstrap (>= 2) that gives the uncertainty of the single
        window and of the algebraic windows (weak-form windows carry their own).
    seed : int
        Seed of the surrogates' noise (the result is reproducible).
    progress : callable ``(stage, fraction)`` or None
        Called as the work proceeds.
    effects : sequence of ``NAME[:LOCATION]``, or ``["auto"]``
        Unmodelled effects to estimate with eq. 1 (:mod:`.augmented`): ``coulomb_friction:1``,
        ``cubic_stiffness:2``...; ``auto`` takes the effect the diagnosis reports. The
        estimator is then the diagnosis's integral equations, and ``estimator`` and
        ``replicates`` do not apply.
    **reading
        How to read a path or a DataFrame, as ``algid identify``'s options say: ``time``,
        ``force``, ``accel``, ``velocity``, ``displacement`` (column names, ``"F1,F2"`` or a
        list), ``columns``, ``units`` (``"acceleration=g"`` or a dict), ``rate`` [Hz] or ``dt``
        [s], ``group`` (:func:`algid.recording.options.reading_options`).

    Returns
    -------
    Identification
    """
    rec = as_recording(rec, **reading)
    if boundary not in ("fixed", "free"):
        raise ValueError(f"boundary must be 'fixed' or 'free', got {boundary!r}")
    if int(replicates) < 2:
        raise ValueError(f"replicates must be >= 2, got {replicates}")
    if isinstance(effects, str):
        effects = [effects]
    rec, screened = screen(rec, reach=0 if rec.a is not None else DEFAULT_DIFF_POINTS // 2)
    missing = screened.rows
    rec, hum = without_hum(rec)
    n, dt = rec.n, float(rec.dt)
    a = accelerations(rec, DEFAULT_DIFF_POINTS)
    kind, motion = recording_motion(rec)
    nm = analyse(rec.u, motion, dt, kind)
    forced = np.any(rec.u != 0.0, axis=0)
    common = dict(
        n=n,
        boundary=boundary,
        dt=dt,
        samples=int(rec.t.size),
        noise=nm,
        motion=kind,
        path=rec.path,
        hum_hz=tuple(hum),
        units=parameter_units(rec),
        recording_notes=tuple(rec.notes),
        screened=screened,
    )
    effect_note = ""
    if effects:
        _progress(progress, "diagnose", None)
        fitted, effect_note = fit_with_effects(rec, motion, kind, nm, boundary, effects)
        if fitted is not None:
            return Identification(**common, **fitted)
    plan, run, unc = _estimate(rec, a, motion, nm, boundary, estimator, replicates, seed, missing, progress)
    joint = True  # every estimator carries the scale along the springs (weak form: joint solve; else eq. 7 ratios)
    _progress(progress, "withheld-window test", None)
    check = fit_check(rec, boundary)
    verdicts = judge(unc.theta, unc.sigma, n, boundary, unc.motion, rec.u, forced, nm, joint, check.pop("misfit"))
    # no value at all where the record has no scale for it (an unforced DOF) or the
    # estimator's systems were singular
    blank = np.array([v.status == "not_identifiable" and not np.isfinite(v.share) for v in verdicts])
    return Identification(
        **common,
        plan=plan,
        theta=np.where(blank, np.nan, unc.theta),
        sigma=np.where(blank, np.nan, unc.sigma),
        raw=run.theta,
        bias=unc.bias,
        method_bias=unc.method_bias,
        verdicts=verdicts,
        time_s=run.time_s,
        history=run.history,
        history_sigma=unc.history_sigma,
        windows=run.windows,
        replicates=unc.replicates,
        model_fit={**check, **({"source": effect_note} if effect_note else {})},
    )
