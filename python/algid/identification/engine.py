"""``algid.identify(recording)``: the whole-record identification with uncertainty and
verdicts, in stages, each entered once and each in one module; between them the record and
the results pass as small dataclasses:

1. Screen (:func:`.screen.screened_signals` -> :class:`.screen.Signals`): finite samples far
   outside their channel's robust range taken out and treated as missing, mains hum notched
   out of every channel alike, an impact record's hits found, its force cleaned and force and
   motion band-passed alike around the modes the chain is to hold
   (:mod:`algid.recording.transient`), the accelerations the estimators read.
2. Noise model and signal band of the recording (:func:`algid.recording.noise.analyse` ->
   :class:`~algid.recording.noise.NoiseModel`).

   Model check (:func:`.augmented.model_check` -> :class:`.augmented.ModelCheck`), before any
   estimator runs: with ``effects``, the diagnosis's fit of eq. 1 with them is the result;
   otherwise the fit check, the diagnosis's verdict on the record. Unless it is ``none``, the
   linear chain reported is the diagnosis's fit of it, the one linear fit of the record
   whichever command prints it (:func:`algid.diagnosis.corrected.linear_model`), its
   determined estimates ``model_misfit``, and stages 3-6 are skipped. Not on an impact
   record (the diagnosis's windows do not fit a decay): its fit check is the output error of
   the chain stage 5 gives, driven by the measured force over the hits (:mod:`.impact_fit`),
   before the verdicts.
3. Plan (:func:`.plan.plan_record` -> :class:`.plan.Plan`): which estimator and its settings,
   from the recording's time scales and a first look at the chain, whose lowest natural
   frequency sets the window length; for an impact record, from the response's modes in the band.
4. Estimate (:func:`.estimate.estimate` -> :class:`.estimate.Estimate`): the plan run over the
   whole record; the algebraic windows' length is first chosen among candidates by the error a
   bootstrap measures on each.
5. Uncertainty (:func:`.uncertainty.estimate_uncertainty` -> :class:`.uncertainty.Uncertainty`):
   the weak-form windows' own covariance, or a parametric bootstrap for the algebraic windows;
   the method's own error; the window results' scatter beyond what noise explains.
6. Verdicts per parameter and DOF (:func:`.verdicts.judge_estimate` -> :class:`.verdicts.Judged`).

A base-excited record (a support motion ``a0``) runs every stage on the chain whose DOF 0 is
the support, dropped at the end (:mod:`.base`); its fit check is skipped (:data:`.base.FIT_CHECK_SKIPPED`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Callable, Optional

from ..model.network import Network
from ..model.network import topology as network_of
from ..recording import Recording, as_recording, parameter_units
from ..recording.frf_file import is_frf_source
from ..recording.noise import analyse
from .augmented import model_check
from .base import FIT_CHECK_SKIPPED, augment, reduce
from .estimate import Estimate, estimate
from .frf_fit import identify_frf
from .impact_fit import impact_fit
from .network import identify_network, refuse_chain_options
from .plan import plan_record
from .result import Identification
from .screen import Signals, screened_signals
from .surrogate import REPLICATES
from .uncertainty import Uncertainty, estimate_uncertainty
from .verdicts import Judged, judge_estimate

ProgressFn = Optional[Callable[[str, float], None]]


def _progress(cb: ProgressFn, stage: str, fraction: float) -> None:
    if cb is not None:
        cb(stage, fraction)


def _at(cb: ProgressFn, stage: str) -> Callable[[float], None]:
    """``fraction -> cb(stage, fraction)`` for one stage."""
    return lambda fraction: _progress(cb, stage, fraction)


def _checked(boundary: str, replicates: int, effects) -> list:
    """The arguments of :func:`identify` checked; ``effects`` as a list."""
    if boundary not in ("fixed", "free"):
        raise ValueError(f"boundary must be 'fixed' or 'free', got {boundary!r}")
    if int(replicates) < 2:
        raise ValueError(f"replicates must be >= 2, got {replicates}")
    return [effects] if isinstance(effects, str) else list(effects)


def _recording_fields(sig: Signals, boundary: str, nm) -> dict:
    """The fields of an :class:`Identification` that describe the record (stages 1-2)."""
    rec = sig.rec
    return dict(
        n=rec.n,
        boundary=boundary,
        dt=float(rec.dt),
        samples=int(rec.t.size),
        noise=nm,
        motion=sig.kind,
        path=rec.path,
        hum_hz=sig.hum_hz,
        channel_timing=sig.timing,
        units=parameter_units(rec),
        recording_notes=tuple(rec.notes),
        screened=sig.screened,
        transient=sig.transient,
    )


def _identification(common: dict, est: Estimate, unc: Uncertainty, judged: Judged, fit: dict) -> Identification:
    """The :class:`Identification` of stages 3-6 (``fit``: the model check's ``model_fit``)."""
    run = est.run
    return Identification(
        **common,
        plan=est.plan,
        theta=judged.theta,
        sigma=judged.sigma,
        raw=run.theta,
        bias=unc.bias,
        method_bias=unc.method_bias,
        verdicts=judged.verdicts,
        time_s=run.time_s,
        history=run.history,
        history_sigma=unc.history_sigma,
        windows=run.windows,
        replicates=unc.replicates,
        model_fit=fit,
    )


def _identify_network(rec: Recording, topology, boundary: str, estimator: str, effects, progress) -> Identification:
    """:func:`identify` of a record on a spring network (:mod:`.network`)."""
    refuse_chain_options(boundary, estimator, effects)
    net = network_of(rec.n, topology if isinstance(topology, Network) else Network.from_json(topology))
    fields = identify_network(rec, net, lambda stage: _progress(progress, stage, None))
    sig, nm = fields.pop("sig"), fields.pop("noise")
    return Identification(**_recording_fields(sig, net, nm), **fields)


def identify(
    rec: Recording,
    boundary: str = "fixed",
    estimator: str = "auto",
    replicates: int = REPLICATES,
    seed: int = 0,
    progress: ProgressFn = None,
    effects: Sequence[str] = (),
    band_hz: tuple[float, float] | None = None,
    topology: Network | str | None = None,
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
    if topology is not None:
        return _identify_network(rec, topology, boundary, estimator, effects, progress)
    scale, base = "", rec.base is not None
    if base:  # the support is DOF 0 of the chain estimated, dropped at the end (:mod:`.base`)
        if effects:
            raise ValueError("effects cannot be estimated on a base-excited record (a support motion a0)")
        rec, scale = augment(rec)
    effects = _checked(boundary, replicates, effects)
    sig = screened_signals(rec, band_hz)  # 1. screen
    nm = analyse(sig.rec.u, sig.motion, sig.dt, sig.kind)  # 2. noise model
    skipped = FIT_CHECK_SKIPPED if base else ""
    check = model_check(sig, nm, boundary, effects, skipped, lambda stage: _progress(progress, stage, None))
    sig = check.sig  # realigned when the check found a converter's channel skew
    common = _recording_fields(sig, boundary, nm)
    if check.result is not None:  # the diagnosis's fit: with the effects, or of a record the linear chain misfits
        return Identification(**common, **check.result)
    # the support's equation of a base-excited record with a force stays out of the others' (:mod:`.base`)
    plan = plan_record(sig, nm, boundary, estimator, joint=not (base and not scale))  # 3. plan
    est = estimate(sig, nm, plan, boundary, seed, _at(progress, "estimate"))  # 4. estimate
    unc = estimate_uncertainty(est, sig, nm, boundary, replicates, seed, _at(progress, "uncertainty"))  # 5. uncertainty
    fit, misfit = check.fit, check.misfit
    if sig.transient is not None:  # an impact record's fit check judges the chain estimated
        fit = {**fit, **impact_fit(sig, unc.theta, boundary)}
        misfit = fit.pop("misfit")
    judged = judge_estimate(unc, sig, nm, boundary, misfit)  # 6. verdicts
    result = _identification(common, est, unc, judged, fit)
    return reduce(result, scale, judged.verdicts, skipped) if base else result
