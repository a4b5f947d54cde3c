"""``algid.identify(recording)``: the whole-record identification with uncertainty and
verdicts, in stages, each entered once:

0. Screen: finite samples far outside their channel's robust range are taken out and
   treated as missing (:mod:`.screen`).
1. Signals: mains hum notched out of every channel alike (:func:`algid.recording.noise.without_hum`);
   an impact record's hits found, its force cleaned and force and motion band-passed alike
   around the modes the chain is to hold (:mod:`algid.recording.transient`); the measured
   accelerations, or the derivatives of the velocities or displacements
   (:func:`algid.recording.accelerations`); the forces.
2. Noise model and signal band of the recording (:mod:`algid.recording.noise`).
3. Fit check (:func:`.augmented.fit_check`): the diagnosis's verdict on the record. Unless
   it is ``none``, the linear chain reported is the diagnosis's fit of it, the one linear
   fit of the record whichever command prints it
   (:func:`algid.diagnosis.corrected.linear_model`), its determined estimates
   ``model_misfit``, and stages 4-6 are skipped. (Not on an impact record: the diagnosis's
   windows do not yet fit a decay, so its own estimate is reported, ``model_misfit``.)
4. Plan (:mod:`.plan`): which estimator and its settings, from the recording's time scales
   and a first look at the chain (:func:`.motion.equation_error_fit`: eq. 1 on the DFT bins
   the forces excite), whose lowest natural frequency sets the window length; for an impact
   record, from the response's modes in the band.
5. Estimate: the plan run over the whole record (:mod:`.runner`); the algebraic windows'
   length is first chosen among multiples of the plan's by the error a bootstrap measures
   on each (:func:`.surrogate.select_window`).
6. Uncertainty (:mod:`.uncertainty`): the weak-form windows' own covariance, or a parametric
   bootstrap for the algebraic windows; the method's own error; the window results' scatter
   beyond what noise explains.
7. Verdicts per parameter and DOF (:mod:`.verdicts`).

A base-excited record (a support motion ``a0``) runs every stage on the chain whose DOF 0 is
the support, dropped at the end (:mod:`.base`); its fit check is skipped (:data:`.base.FIT_CHECK_SKIPPED`).

With ``effects``, stages 3-7 are the diagnosis's fit of eq. 1 with the effects and its check
(:mod:`.augmented`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Callable, Optional

import numpy as np

from ..diagnosis.corrected import linear_model
from ..recording import DEFAULT_DIFF_POINTS, Recording, accelerations, as_recording, parameter_units
from ..recording import motion as recording_motion
from ..recording.frf_file import is_frf_source
from ..recording.noise import analyse, without_hum
from ..recording.transient import transient_record
from .augmented import diagnosis_fields, fit_check, fit_with_effects
from .base import FIT_CHECK_SKIPPED, augment, reduce
from .frf_fit import identify_frf
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


def _estimate(rec, a, motion, nm, boundary, estimator, replicates, seed, missing, progress, joint=True, transient=None):
    """Stages 4-6: the plan, its run over the record and the run's uncertainty."""
    duration, forced = rec.t.size * rec.dt, np.any(rec.u != 0.0, axis=0)
    if transient is None:
        first = natural_frequencies_hz(equation_error_fit(rec.u, motion, nm, boundary), rec.n, boundary)
    else:
        first = np.array(transient.in_band_hz)
    plan = make_plan(nm, duration, estimator, first, joint, transient)
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


def _checked(boundary: str, replicates: int, effects) -> list:
    """The arguments of :func:`identify` checked; ``effects`` as a list."""
    if boundary not in ("fixed", "free"):
        raise ValueError(f"boundary must be 'fixed' or 'free', got {boundary!r}")
    if int(replicates) < 2:
        raise ValueError(f"replicates must be >= 2, got {replicates}")
    return [effects] if isinstance(effects, str) else list(effects)


def _recording_fields(rec, boundary, nm, kind, hum, screened, transient) -> dict:
    """The fields of an :class:`Identification` that describe the record (stages 0-2)."""
    return dict(
        n=rec.n,
        boundary=boundary,
        dt=float(rec.dt),
        samples=int(rec.t.size),
        noise=nm,
        motion=kind,
        path=rec.path,
        hum_hz=tuple(hum),
        units=parameter_units(rec),
        recording_notes=tuple(rec.notes),
        screened=screened,
        transient=transient,
    )


def identify(
    rec: Recording,
    boundary: str = "fixed",
    estimator: str = "auto",
    replicates: int = REPLICATES,
    seed: int = 0,
    progress: ProgressFn = None,
    effects: Sequence[str] = (),
    band_hz: tuple[float, float] | None = None,
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
    band_hz : (low, high) [Hz] or None
        Impact records: the band whose modes the chain holds (default: around the ``n`` lowest
        modes of the response, :mod:`algid.recording.transient`); the modes outside are filtered
        out and reported as residual modes.
    **reading
        How to read a path or a DataFrame, as ``algid identify``'s options say: ``time``,
        ``force``, ``accel``, ``velocity``, ``displacement`` (column names, ``"F1,F2"`` or a
        list), ``columns``, ``units`` (``"acceleration=g"`` or a dict), ``rate`` [Hz] or ``dt``
        [s], ``group`` (:func:`algid.recording.options.reading_options`).

    Returns
    -------
    Identification
        or, for FRFs (an FRF ``.npz``, a UFF file of function type 4, a mapping with ``frf``,
        :class:`~algid.recording.frf_file.FrfData`), the :class:`~.frf_result.FrfIdentification`
        of :func:`.frf_fit.identify_frf`, which prints and writes JSON alike.
    """
    if is_frf_source(rec):
        if effects or estimator != "auto":
            raise ValueError("--effect and --estimator apply to time recordings, not to FRFs")
        return identify_frf(rec, boundary)
    rec = as_recording(rec, **reading)
    scale, base = "", rec.base is not None
    if base:  # the support is DOF 0 of the chain estimated, dropped at the end (:mod:`.base`)
        if effects:
            raise ValueError("effects cannot be estimated on a base-excited record (a support motion a0)")
        rec, scale = augment(rec)
    effects = _checked(boundary, replicates, effects)
    rec, screened = screen(rec, reach=0 if rec.a is not None else DEFAULT_DIFF_POINTS // 2)
    missing = screened.rows
    rec, hum = without_hum(rec)
    raw, (rec, transient) = rec, transient_record(rec, band_hz)
    if transient is not None:
        missing = missing | transient.missing
    n, dt = rec.n, float(rec.dt)
    a = accelerations(rec, DEFAULT_DIFF_POINTS)
    kind, motion = recording_motion(rec)
    nm = analyse(rec.u, motion, dt, kind)
    forced = np.any(rec.u != 0.0, axis=0)
    common = _recording_fields(rec, boundary, nm, kind, hum, screened, transient)
    effect_note = ""
    if effects:
        _progress(progress, "diagnose", None)
        fitted, effect_note = fit_with_effects(rec, motion, kind, nm, boundary, effects)
        if fitted is not None:
            return Identification(**common, **fitted)
    _progress(progress, "withheld-window test", None)
    skipped = FIT_CHECK_SKIPPED if base else ""
    band = None if transient is None else transient.band_hz
    check, d = ({"misfit": ""}, None) if skipped else fit_check(raw, boundary, band)
    misfit = check.pop("misfit")
    if misfit and transient is None:  # one linear fit per record: the diagnosis's, whose gap is measured
        fields = diagnosis_fields(rec, motion, kind, nm, boundary, d, linear_model(d), "the linear chain", misfit)
        fields["model_fit"].update(check)
        return Identification(**common, **fields)
    # the support's equation of a base-excited record with a force stays out of the others' (:mod:`.base`)
    pooled = not (base and not scale)
    plan, run, unc = _estimate(
        rec, a, motion, nm, boundary, estimator, replicates, seed, missing, progress, pooled, transient
    )
    joint = True  # every estimator carries the scale along the springs (weak form: joint solve; else eq. 7 ratios)
    verdicts = judge(unc.theta, unc.sigma, n, boundary, unc.motion, rec.u, forced, nm, joint, misfit)
    # no value at all where the record has no scale for it (an unforced DOF) or the
    # estimator's systems were singular
    blank = np.array([v.status == "not_identifiable" and not np.isfinite(v.share) for v in verdicts])
    result = Identification(
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
    return reduce(result, scale, verdicts, skipped) if base else result
