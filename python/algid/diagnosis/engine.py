"""The diagnosis pipeline: linear fit, candidate search, noise-aware selection.

1. Accelerations (measured, or derived from displacements), their integrals, windows of
   half the lowest natural period (from a first fit on 0.5 s windows); the first
   ``max(0.1 s, 100 samples)`` are kept out of the windows as lead-in for delays and
   filters.
2. The signal band of the recording (:func:`.band.signal_band`, from the forces, the
   accelerations and the natural frequencies of the first fit), the linear chain, cross-validated
   (``gap_before``, in-band; ``gap_before_fullband``), and the states it reconstructs. When
   its gap is above the noise floor, a multiplexed converter's channel skew is looked for and,
   found, undone, and steps 1-2 run again on the realigned record (:mod:`.timing`).
3. Every candidate effect at every location (:mod:`.candidates`), cross-validated, scored
   by its withheld error reduction and tested against noise (:func:`noise_z`); the
   state-dependent leaders are refitted with the states reconstructed under them.
4. The best significant candidate by withheld gap, unless it leaves most of a large gap
   unexplained (``unknown``); ``none`` when nothing is beyond noise and the gap is at the
   noise floor.
5. Location indicators (:mod:`.locate`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from ..messages.display import Displayed, number
from ..model.chain import Chain
from ..model.network import Network, NetworkModel, topology
from ..parallel import parallel_map
from ..recording import Recording, RecordingError, accelerations, as_recording, derivative
from ..recording import motion as recording_motion
from ..recording.noise import channel, white_floor, without_hum
from ..recording.transient import transient_record
from .band import Band, signal_band
from .candidates import (
    ADDITIVE,
    EFFECTS,
    N_GRID,
    QUICK_GRID,
    CandidateFit,
    Context,
    all_candidates,
    fit_candidate,
    fit_combination,
    lead_in,
    physical,
    raw_residual,
)
from .core import METRIC
from .equations import force_form, linear_design, target
from .integrals import integrals
from .linear import LinearFit, fit_linear, force_scale, reconstruct_states
from .locate import locate, noise_floor
from .model import ModelVerdict, inertia, model_verdict, physical_uncertainty, transient_response
from .timing import Timing, on_time, realign
from .units import SI, diagnosis_units
from .windows import Prepared, detrend, parseval_weights, prepare, window_length

#: Threshold on the noise-referenced z score of the withheld error reduction (see
#: :func:`noise_z`).
Z_CRIT = 4.0
#: Smallest relative reduction of the withheld squared error that is reported.
MIN_REL_REDUCTION = 0.01
#: A sensor bias is reported only beyond this many times the bias that the sample mean
#: of the white sensor noise itself puts in the record (sigma / sqrt(N)).
BIAS_NOISE_FACTOR = 10.0
#: A gap left this many times above the sensor-noise floor counts as unexplained: the
#: diagnosis is ``unknown`` when the best candidate leaves it and explains less than
#: :data:`MIN_EXPLAINED` of the excess ``gap_before^2 - floor^2`` (it is then still listed
#: first in the ranking).
UNKNOWN_FLOOR_RATIO = 3.0
#: A model explains a record to its noise when its withheld gap is at most this many times the
#: noise floor: with no candidate beyond noise the diagnosis is ``none`` only then, and
#: :func:`algid.identify` calls a fit valid only then (the floor is itself an estimate: a
#: linear record's own gap scatters above it).
FIT_FLOOR_RATIO = 3.0
MIN_EXPLAINED = 0.5
#: A linear gap below this (0.01 % NRMS) is numerical resolution (quadrature, the
#: integrator of a simulation): reported as ``none`` whatever the candidates say.
GAP_RESOLUTION = 1e-4
#: A forced DOF whose inertia force is below this share of its force in the band makes
#: the analysis solve the forced equations for the force (:func:`_form`).
QUASI_STATIC = 0.05
#: Candidates tried with the best one, and the share of the best single candidate's
#: remaining withheld error a pair must remove to be reported.
COMBINATION_LEADERS = 4
COMBINATION_GAIN = 0.2
#: Verdicts a converter's skew left in the record can take (:func:`_timing_with_effect`).
SKEW_LIKE = ("unknown", "input_delay", "sensor_lowpass")
#: Effects whose regressors depend on the reconstructed states (refitted once with
#: states reconstructed under the candidate model).
SPRING_EFFECTS = ("cubic_stiffness", "clearance", "parameter_drift", "amplitude_damping")
#: Candidates that read what another one found at the same location (Stribeck friction: the
#: Coulomb fit's velocity scale at its DOF): fitted right after it, on the same thread.
AFTER = {"stribeck_friction": "coulomb_friction"}
#: Most refits of a state-dependent candidate with states reconstructed under it.
STATE_REFITS = 4
STATE_EFFECTS = (
    "coulomb_friction",
    "stribeck_friction",
    "quadratic_damping",
    "amplitude_damping",
    "cubic_stiffness",
    "clearance",
    "parameter_drift",
)


@dataclass
class Scored:
    """A candidate fit with its withheld-data score."""

    fit: CandidateFit
    gap_after: float
    gap_after_full: float
    reduction: np.ndarray  # (nw * S,) per-sub-block reduction of the withheld squared error
    t_stat: float
    rel_reduction: float
    z: float = float("nan")
    noise_param_ok: bool = True
    physical: bool = True

    @property
    def significant(self) -> bool:
        return bool(
            self.z >= Z_CRIT and self.rel_reduction >= MIN_REL_REDUCTION and self.noise_param_ok and self.physical
        )


@dataclass
class Diagnosis:
    """Result of :func:`diagnose` (see :func:`.report.to_json` for the published fields).

    ``units`` names the unit of every number by its name (``m``, ``c``, ``k``, ``force``,
    ``acceleration``, ``k_cubic``, ...: :func:`.units.diagnosis_units`), in the units the
    recording declares (``recording_units``, by role); ``recording_notes`` are what the
    reader did (columns ignored, units converted)."""

    effect: str
    location: dict | None
    params: dict[str, float]
    params_std: dict[str, float]
    gap_before: float
    gap_after: float
    gap_before_full: float
    gap_after_full: float
    band: Band
    ranking: list[Scored]
    P: Prepared
    lin: LinearFit
    best: Scored | None
    timings: dict[str, float] = field(default_factory=dict)
    where: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)
    units: dict = field(default_factory=lambda: dict(SI))
    recording_units: dict = field(default_factory=dict)
    recording_notes: list = field(default_factory=list)

    @property
    def metric(self) -> str:
        return METRIC

    # ---- display: one-line repr, notebook table (algid.messages.display) -------------------------
    def _display_fields(self) -> dict:
        parts = (self.location or {}).get("parts", [self.location] if self.location else [])
        where = "+".join(f"{'DOF' if 'dof' in p else 'spring'} {next(iter(p.values()))}" for p in parts)
        return {
            "effect": repr(self.effect),
            "location": repr(where) if where else None,
            "gap_before": number(self.gap_before, 4),
            "gap_after": number(self.gap_after, 4),
            "candidates": len(self.ranking),
        }

    __repr__ = Displayed.__repr__
    _repr_html_ = Displayed._repr_html_

    def residuals(self) -> tuple[np.ndarray, np.ndarray]:
        """In-sample equation errors (N, n) of the linear model and of the model with the
        reported effect, in each equation's target units (acceleration, or force in the force
        form: ``units``) (the same array twice for ``none``/``unknown``)."""
        before = self.lin.resid
        if self.best is None:
            return before, before
        raw = raw_residual(self.extra["ctx"], self.best.fit)
        return before, detrend(self.P, raw).reshape(raw.shape)


def _progress(cb: Callable[[str], None] | None, msg: str) -> None:
    if cb is not None:
        cb(msg)


def score(P: Prepared, lin: LinearFit, fit: CandidateFit, denom: float) -> Scored:
    """Withheld-error reduction (in-band) of a candidate against the linear model."""
    # Per sub-block reduction of the withheld error over the candidate's equations.
    red = (lin.cv.test_sub[:, :, fit.eqs].sum(axis=2) - fit.cv.test_sub.sum(axis=2)).ravel()
    total_lin = lin.cv.test_sse.sum()
    after = total_lin - red.sum()
    after_full = lin.cv.test_sub_full.sum() - (lin.cv.test_sub_full[:, :, fit.eqs].sum() - fit.cv.test_sub_full.sum())
    sd = red.std(ddof=1)
    t = float(red.mean() / (sd / np.sqrt(red.size))) if sd > 0 else (np.inf if red.mean() > 0 else 0.0)
    return Scored(
        fit=fit,
        gap_after=float(np.sqrt(max(after, 0.0) / denom)),
        gap_after_full=float(np.sqrt(max(after_full, 0.0) / denom)),
        reduction=red,
        t_stat=t,
        rel_reduction=float(red.sum() / total_lin),
    )


def _assess(P: Prepared, lin: LinearFit, fit: CandidateFit, denom: float, floor: np.ndarray) -> Scored:
    """Score a candidate and test it against noise; its Grams and equations are dropped
    (the scores and fold parameters keep what the ranking needs; the equations are rebuilt
    for the few candidates that need them again)."""
    s = score(P, lin, fit, denom)
    s.physical = physical(fit)
    if s.rel_reduction >= MIN_REL_REDUCTION:
        s.z = noise_z(P, lin, fit)
    if fit.effect == "sensor_bias":
        i = fit.location["dof"] - 1
        s.noise_param_ok = bool(abs(fit.params["bias"]) >= BIAS_NOISE_FACTOR * floor[i] / np.sqrt(P.y.shape[0]))
    fit.cv.stats = fit.cv.stats.slim()
    fit.release()
    return s


def noise_z(P: Prepared, lin: LinearFit, fit: CandidateFit) -> float:
    """How far the withheld error reduction of a candidate exceeds what noise explains.

    On withheld window w the candidate changes the linear model's prediction by
    ``Delta_w`` (fitted without that window) and the error reduction is
    ``d_w = |r_lin|^2 - |r_lin - Delta_w|^2 = 2 r_lin.Delta_w - |Delta_w|^2``. If the
    candidate only fitted noise, ``r_lin`` on w is noise independent of ``Delta_w``:
    ``sum_w d_w`` then has mean ``-sum |Delta_w|^2 <= 0`` and variance
    ``4 sum_w Delta_w' Sigma Delta_w``, evaluated in the frequency domain with the
    noise spectrum estimated from the candidate's own withheld errors (Bartlett over the
    windows, per equation; whatever the candidate leaves unexplained counts as noise,
    coloured or not). Returns ``z = sum_w d_w / (2 sqrt(var))``.

    Everything is on the DFT bins of the signal band (the metric's projection ``M``,
    ``P.band_mask``): ``d_w = |M r_lin|^2 - |M r_lin - M Delta_w|^2``, whose noise-only
    variance is ``4 sum_w (M Delta_w)' Sigma (M Delta_w)``, i.e. the same frequency-domain
    sums restricted to the band bins.
    """
    K = P.nfolds
    st = fit.cv.stats
    total_d = 0.0
    var = 0.0
    for _k_eq, (spec, sl) in enumerate(zip(fit.equations(), st.slices)):
        e = spec.e
        cols = [spec.X] + ([spec.E] if spec.E is not None and spec.E.shape[1] else [])
        Zc = detrend(P, np.concatenate(cols, axis=1))  # (nw, L, p+q)
        yd = detrend(P, spec.y[:, None])[..., 0]  # (nw, L)
        yl = detrend(P, target(P, e)[:, None])[..., 0]  # the linear model's target (a delay moves a force target)
        Zl = detrend(P, linear_design(P, e))
        rc = np.empty_like(yd)
        rl = np.empty_like(yd)
        lsl = lin.cv.stats.slices[e]
        for k in range(K):
            mask = P.folds == k
            th = fit.cv.theta_folds[k]
            coef = np.concatenate([th[sl], th[st.shared]])
            rc[mask] = yd[mask] - Zc[mask] @ coef
            rl[mask] = yl[mask] - Zl[mask] @ lin.cv.theta_folds[k][lsl]
        RC = np.fft.rfft(rc, axis=1)
        RL = np.fft.rfft(rl, axis=1)
        # Parseval weights of the one-sided spectrum (interior bins count twice), zero
        # outside the band.
        wts = parseval_weights(P.L) * P.band_mask
        total_d += float(np.sum(wts * (np.abs(RL) ** 2 - np.abs(RC) ** 2)) / P.L)
        S = np.mean(np.abs(RC) ** 2, axis=0) / P.L  # noise spectrum per bin
        D2 = np.abs(RL - RC) ** 2  # (nw, L//2+1) spectrum of delta
        var += float(np.sum(wts * S * D2) / P.L)
    if var <= 0:
        return float("inf") if total_d > 0 else 0.0
    return float(total_d / (2.0 * np.sqrt(var)))


def lowest_frequency_hz(lin: LinearFit, boundary: str) -> float:
    """Lowest undamped natural frequency [Hz] of the fitted chain (nan if unphysical)."""
    f = natural_frequencies(lin, boundary)
    return float(f[f > 0].min()) if np.any(f > 0) else float("nan")


@dataclass
class Setup:
    """The record prepared for the candidates: windows, band, equation form, linear fit,
    per-DOF noise floors (target units, full band and in band) and the model verdict."""

    P: Prepared
    lin: LinearFit
    band: Band
    denom: float
    floor: np.ndarray
    floor_band: np.ndarray
    model: ModelVerdict
    timings: dict
    measured: tuple | None = None  # (x, v) on the analysed samples when the record gives them
    hum: list = field(default_factory=list)  # mains lines notched out [Hz]
    transient: object = None  # an impact record's hits and band (algid.recording.transient)
    noise: NoiseLevels | None = None  # the sensor noise behind ``floor`` (:func:`noise_floors`)
    shapes: np.ndarray | None = (
        None  # accelerometer noise carried through the analysis, for the verdict's floor (:func:`noise_shapes`)
    )
    timing: Timing | None = None  # the channels' skew found, and whether it was undone (:mod:`.timing`)
    rec: Recording | None = None  # the record as prepared (notched; realigned when it was)


def _form(a, u, dt, L, boundary, skip, A, band: Band) -> str:
    """The force form when some forced DOF is quasi-static: a first force-form fit puts its
    inertia force below :data:`QUASI_STATIC` of the force in the band, or does not find its
    mass above zero by three sigma (its acceleration-form equation, solved for an
    acceleration that carries no information, would be noise)."""
    P = prepare(a, u, dt, L, boundary, skip, A=A, band_hz=_band_hz(band), form="force", fit_band=True)
    lin = fit_linear(P)
    dofs = inertia(P, lin, physical_uncertainty(P, lin), band.f_hi).values()
    quasi_static = [d["inertia_share"] < QUASI_STATIC or not d["mass"] > 3 * d["mass_sigma"] for d in dofs]
    return "force" if any(quasi_static) else "acceleration"


def _prepare(rec: Recording, boundary: str | Network, progress, notch: bool = True, band_hz=None) -> Setup:
    """Windows, band and form (module docstring, steps 1-2), linear fit, noise, model; when
    the linear chain leaves a gap above the noise floor, the channels' timing first
    (:mod:`.timing`: a record realigned is prepared again)."""
    clock = time.perf_counter()
    rec, hum = without_hum(rec) if notch else (rec, [])
    rec, tr = transient_record(rec, band_hz)
    st = replace(_setup(rec, tr, hum, boundary, progress, clock), rec=rec)
    if tr is not None or not _above_floor(st):
        return st
    _progress(progress, f"{rec.n} DOF: the channels' timing")
    on_time_rec, timing = on_time(rec, boundary, st.P.L, _band_hz(st.band))
    if timing is not None and timing.realigned:
        st = replace(_setup(on_time_rec, tr, hum, boundary, progress, clock), rec=on_time_rec)
    return replace(st, timing=timing)


def _timing_with_effect(st: Setup, scored: list[Scored], boundary, effects, progress, clock: float) -> Setup | None:
    """The record prepared again once realigned, when the channels' timing, estimated with the
    chain fitted together with the leading significant additive candidate's force columns,
    finds a converter's skew that the linear chain alone did not (an effect biases the
    latenesses the chain alone finds); None when it finds none (:mod:`.timing`). When no
    additive candidate is significant but the chain alone found a converter's pattern (short
    of its gain: the effect's share of the gap), the candidate is the leading one of the
    record realigned as that pattern says."""
    if st.timing is None or st.timing.realigned or st.transient is not None:
        return None
    if st.P.skip != lead_in(st.rec.u.shape[0], float(st.rec.dt)):  # the effect's columns start there
        return None
    lead = _additive_lead(scored)
    if lead is None and st.timing.pattern:
        tentative = _setup(realign(st.rec, st.timing.late), st.transient, st.hum, boundary, progress, clock)
        lead = _additive_lead(_candidates(tentative, _context(tentative), effects, progress))
    if lead is None:
        return None
    _progress(progress, f"{st.rec.n} DOF: the channels' timing with {lead.fit.effect}")
    effect = {sp.e: sp.E for sp in lead.fit.specs if sp.E is not None}
    on_time_rec, timing = on_time(st.rec, boundary, st.P.L, _band_hz(st.band), effect)
    if timing is None or not timing.realigned:
        return None
    st2 = _setup(on_time_rec, st.transient, st.hum, boundary, progress, clock)
    return replace(st2, timing=timing, rec=on_time_rec)


def _additive_lead(scored: list[Scored]) -> Scored | None:
    """The best significant candidate that only adds a force (:data:`.candidates.ADDITIVE`)."""
    return next((s for s in scored if s.significant and s.fit.effect.split("+")[0] in ADDITIVE), None)


def _band_hz(band: Band) -> float | None:
    """The upper edge of the signal band, None when it is the whole spectrum."""
    return None if band.full else band.f_hi


def _above_floor(st: Setup) -> bool:
    """Whether the linear chain's withheld gap exceeds the floor of white and 1/f noise on the
    equations themselves (:func:`coloured_floor` without the shapes of accelerometer noise
    carried through the integrals: the lower floor, so that a skew under a sensor's coloured
    noise is still looked for; the timing's own tests decide)."""
    gap = float(np.sqrt(st.lin.cv.test_sse.sum() / st.denom))
    return gap > relative_floors(st.P, st.floor_band, st.denom, st.lin.resid)[1]


def _setup(rec: Recording, tr, hum: list, boundary: str, progress, clock: float) -> Setup:
    """:func:`_prepare` on a record notched and, for a transient, band-passed (``tr``)."""
    dt, T = float(rec.dt), rec.u.shape[0]
    skip = lead_in(T, dt)
    if tr is not None:  # the first hit carries the scale: no lead-in past it
        skip = min(skip, tr.hits[0].start)
    a, u = accelerations(rec), rec.u
    _progress(progress, f"{rec.n} DOF, {T} samples at {1 / dt:g} Hz: linear fit")
    A = integrals(a, dt)
    L0 = window_length(dt, 1.0, T - skip)
    lin0 = fit_linear(prepare(a, u, dt, L0, boundary, skip, A=A))
    kind, motion = recording_motion(rec)
    order = {"acceleration": 0, "velocity": 1, "displacement": 2}[kind]
    band = signal_band(a, u, dt, natural_frequencies(lin0, boundary), derived=(motion, order) if order else None)
    form = _form(a, u, dt, L0, boundary, skip, A, band)
    if form == "force":
        lows = [channel("u", u[:, i], dt).f_low for i in np.nonzero(np.any(u != 0.0, axis=0))[0]]
        f_low = min([f for f in lows if np.isfinite(f) and f > 0], default=1.0)
        L = window_length(dt, f_low, T - skip, periods=1.0, max_s=np.inf)
    else:
        f_low = lowest_frequency_hz(lin0, boundary)
        L = window_length(dt, f_low if np.isfinite(f_low) else 1.0, T - skip)
    P = prepare(a, u, dt, L, boundary, skip, A=A, band_hz=_band_hz(band), form=form, fit_band=order > 0)
    lin = fit_linear(P)
    floor, floor_band, levels = noise_floors(P, lin, motion if order else None, order)
    measured = None
    if kind == "displacement":  # positions and their derivative, in band: no states to reconstruct
        xb = band_limited(rec.x, dt, band.f_hi)
        measured = (xb[P.sl], derivative(xb, dt, 1)[P.sl])
    states = measured if measured is not None else (lin.x, lin.v)
    denom = float(np.sum(P.y**2))
    # the gap the noise on the equations explains, on the linear fit
    noise_gap = FIT_FLOOR_RATIO * relative_floors(P, floor_band, denom, lin.resid)[1]
    drive = int(np.argmax(np.max(np.abs(u), axis=0)))  # the hammer's DOF
    response = None if tr is None else transient_response(u[:, drive], motion[:, drive], tr)
    model = model_verdict(P, lin, band.f_hi, states, noise_gap=noise_gap, denom=denom, response=response)
    # the verdict's floor carries accelerometer noise through the integrals, unless the record has
    # more modes than the chain: the error of a model short of modes is structure, broadband and
    # rising towards low frequencies as carried 1/f noise does, and a noise fit would call it noise
    shapes = noise_shapes(P, lin) if order == 0 and model.verdict != "more_modes_than_dof" else None
    return Setup(
        P=P,
        lin=lin,
        band=band,
        denom=denom,
        floor=floor,
        floor_band=floor_band,
        model=model,
        timings={"linear": time.perf_counter() - clock},
        measured=measured,
        hum=hum,
        transient=tr,
        noise=levels,
        shapes=shapes,
    )


def band_limited(x: np.ndarray, dt: float, f_hi: float) -> np.ndarray:
    """Columns of ``x`` without their content above ``f_hi`` (FFT; the line through the
    first and last samples is kept aside, so the periodic extension does not jump)."""
    T = x.shape[0]
    t = np.arange(T)[:, None] / (T - 1)
    line = x[:1] + t * (x[-1:] - x[:1])
    X = np.fft.rfft(x - line, axis=0)
    X[np.fft.rfftfreq(T, dt) > f_hi] = 0.0
    return line + np.fft.irfft(X, T, axis=0)


def noise_floors(P: Prepared, lin: LinearFit, motion: np.ndarray | None, order: int):
    """Per-DOF noise RMS of the equation errors in each equation's target units, over the
    full band and in the signal band, and the :class:`NoiseLevels` behind them.

    Measured accelerations: the white floor of the equation errors (:func:`.locate.noise_floor`),
    its band share ``band_fraction`` in band. Derived accelerations: the motion's white floor
    (read on the derived accelerations' PSD divided by the derivative stencil's gain, where
    differentiation has lifted the noise far above the leakage of a large slow motion; for
    encoder counts at least the quantisation floor
    ``q^2 / 12 / (fs / 2)``, :func:`algid.recording.noise.quantisation_psd`) carried through the
    analysis itself: white noise of that level on every motion channel, differentiated
    ``order`` times as the recording's accelerations were, integrated, put into each
    equation with the linear fit's parameters, detrended and projected on the band of every
    window (fixed seed; enough draws for about :data:`FLOOR_DOF` in-band degrees of freedom).
    On short windows the noise differentiated twice, rising like ``f^4`` to the Nyquist rate,
    leaks into a window's few in-band bins far beyond its in-band integral. The force sensor's
    white floor adds ``(theta_u^2) S_u f_hi`` to a forced equation (``theta_u`` = 1/m in the
    acceleration form, 1 in the force form)."""
    floor = noise_floor(P, lin.resid)
    band = floor * np.sqrt(P.band_fraction)
    if motion is None and P.form != "force":
        return floor, band, NoiseLevels()
    from scipy.signal import welch

    from ..recording.derivatives import DEFAULT_DIFF_POINTS, derivative_weights
    from ..recording.noise import quantisation_psd
    from .windows import band_filter

    fs = 1.0 / P.dt
    n = P.n
    f_hi = P.band_hz if P.band_hz is not None else 0.5 * fs
    f, S = welch(
        np.column_stack([P.u_full] + ([motion] if motion is not None else [])), fs=fs, nperseg=min(P.L, 1024), axis=0
    )
    white = white_floor(f, S)
    power = band**2 if motion is None else np.zeros(n)
    if motion is not None:
        # the motion's floor read where the derivative has lifted its noise far above the
        # leakage of the signal (short segments leak a large, slow motion into the upper
        # third of its own spectrum): the recording's accelerations' PSD over the stencil's gain
        _, Sa = welch(P.a_full, fs=fs, nperseg=min(P.L, 1024), axis=0)
        w_st = derivative_weights(DEFAULT_DIFF_POINTS, order, DEFAULT_DIFF_POINTS // 2)
        lags = np.arange(DEFAULT_DIFF_POINTS) - DEFAULT_DIFF_POINTS // 2
        gain = np.abs(np.exp(2j * np.pi * np.outer(f * P.dt, lags)) @ w_st) / P.dt**order
        Sm = S[:, n:].copy()
        Sm[1:] = Sa[1:] / np.maximum(gain[1:, None] ** 2, 1e-300)
        white[n:] = white_floor(f, Sm)
        if order == 2:  # encoder counts: at least their quantisation noise
            white[n:] = np.maximum(white[n:], [quantisation_psd(motion[:, i], P.dt) for i in range(n)])
        sigma = np.sqrt(white[n:] * 0.5 * fs)
        dof = P.nw * max(int(np.sum(P.band_mask)), 1)
        draws = int(np.clip(np.ceil(FLOOR_DOF / dof), 1, 8))
        rng = np.random.default_rng(0)
        for _ in range(draws):
            E = equation_noise(P, lin, sigma, order, rng)
            power += np.sum(band_filter(P, P.windows(E)) ** 2, axis=(0, 1)) / E.shape[0] / draws
    for e in range(n):
        if P.forced[e]:
            theta_u = 1.0 if force_form(P, e) else float(lin.theta_a[e][0])
            band[e] = np.sqrt(power[e] + theta_u**2 * white[e] * f_hi)
        else:
            band[e] = np.sqrt(power[e])
    sigma = sigma if motion is not None else None
    return floor, band, NoiseLevels(order=order, motion_sigma=sigma, force_psd=white[:n])


@dataclass(frozen=True)
class NoiseLevels:
    """The sensor noise the floors of :func:`noise_floors` carry through the analysis:
    ``motion_sigma`` (n,) white-noise standard deviation of the motion channels [their
    unit], differentiated ``order`` times into accelerations (None: measured accelerations,
    whose floor is read off the equation errors); ``force_psd`` (n,) the forces' white
    floors [N^2/Hz] (None: likewise)."""

    order: int = 0
    motion_sigma: np.ndarray | None = None
    force_psd: np.ndarray | None = None


def equation_noise(P: Prepared, lin: LinearFit, sigma: np.ndarray, order: int, rng: np.random.Generator):
    """(N, n) one draw of white noise of standard deviation ``sigma`` (n,) on the motion
    channels carried through the analysis (:func:`carried`), differentiated ``order`` times as
    the recording's accelerations were."""
    return carried(P, lin, derivative(rng.standard_normal(P.a_full.shape) * sigma, P.dt, order))


def carried(P: Prepared, lin: LinearFit, a_n: np.ndarray) -> np.ndarray:
    """(N, n) accelerometer noise ``a_n`` (as ``P.a_full``) carried through the analysis:
    integrated, put into each equation with the linear fit's parameters and detrended per
    window (each equation's target units; the force sensor's noise apart)."""
    from .equations import base_design

    N, sl = P.y.shape[0], P.sl
    A1n, A2n = integrals(a_n, P.dt)
    a_n, A1n, A2n = a_n[sl], A1n[sl], A2n[sl]
    out = np.empty((N, P.n))
    for e in range(P.n):
        X = base_design(P, e, A1n, A2n, u=np.zeros(N), a=a_n[:, e])
        y = np.zeros(N) if force_form(P, e) else a_n[:, e]
        out[:, e] = detrend(P, y - X @ lin.theta_a[e]).reshape(N)
    return out


def noise_shapes(P: Prepared, lin: LinearFit) -> np.ndarray:
    """(2, F, n) mean power per DFT bin of a window (as :func:`coloured_floor` reads the
    equation errors) of unit white and unit ``1/f`` accelerometer noise (PSD ``1/f`` times the
    white one's, ``f`` in Hz) carried through the analysis (:func:`carried`): the integrals
    lift a sensor's low-frequency noise into the equations far above its own ``1/f``, and the
    windows' detrending takes the lowest bins back. Fixed seed; draws for about
    :data:`FLOOR_DOF` in-band degrees of freedom."""
    T = P.a_full.shape[0]
    f = np.fft.rfftfreq(T, P.dt)
    tilt = 1.0 / np.sqrt(np.maximum(f, f[1]))[:, None]
    draws = int(np.clip(np.ceil(FLOOR_DOF / (P.nw * max(int(np.sum(P.band_mask)), 1))), 1, 8))
    rng = np.random.default_rng(0)
    out = np.zeros((2,) + _bin_power(P, P.y).shape)
    for _ in range(draws):
        white = rng.standard_normal(P.a_full.shape)
        pink = np.fft.irfft(np.fft.rfft(white, axis=0) * tilt, T, axis=0)
        out += [_bin_power(P, carried(P, lin, x)) / draws for x in (white, pink)]
    return out


def _bin_power(P: Prepared, resid: np.ndarray) -> np.ndarray:
    """(F, n) mean power per DFT bin of a window of the equation errors ``resid`` (N, n) (Parseval
    weights: the bins sum to the windows' mean square)."""
    R = P.windows(resid)  # (nw, L, n)
    return parseval_weights(P.L)[:, None] * np.mean(np.abs(np.fft.rfft(R, axis=1)) ** 2, axis=0) / P.L


#: In-band degrees of freedom (windows times band bins) of the simulated noise of
#: :func:`noise_floors` (a few percent on the floor's RMS).
FLOOR_DOF = 2000


def _context(st: Setup, quick: bool = False) -> Context:
    """The states the candidates are built from: measured when the record has positions,
    else reconstructed by the linear fit; ``quick``: the coarse grids alone."""
    x, v = (st.lin.x, st.lin.v) if st.measured is None else st.measured
    return Context(P=st.P, lin=st.lin, x=x, v=v, grid=QUICK_GRID if quick else N_GRID, refine=not quick)


def _candidates(st: Setup, ctx: Context, effects, progress) -> list[Scored]:
    """Fit and score every candidate at every location (module docstring, step 3)."""
    P, lin = st.P, st.lin
    todo = [(e, loc) for e, loc in all_candidates(P) if e in effects]

    done = [0]

    def one(item: tuple[str, int]) -> Scored | None:
        eff, loc = item
        try:
            fit = fit_candidate(ctx, eff, loc)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError):
            fit = None
        done[0] += 1
        return None if fit is None else _assess(P, lin, fit, st.denom, st.floor)

    def tick(_groups: int) -> None:
        _progress(progress, f"candidate {done[0]}/{len(todo)}")

    groups = _dependency_groups(todo)
    scored = [s for group in parallel_map(lambda g: [one(c) for c in g], groups, tick) for s in group if s is not None]
    return sorted(_refit_leaders(st, ctx, sorted(scored, key=lambda s: s.gap_after)), key=lambda s: s.gap_after)


def parse_effect(spec: str, n: int, boundary: str) -> tuple[str, int]:
    """``NAME[:LOCATION]`` (``coulomb_friction:1``, ``cubic_stiffness:2``) as ``(effect,
    loc)``, ``loc`` 0-based for a DOF effect and 1-based for a spring effect (as
    :func:`.candidates.fit_candidate` takes it); the location may be left out on one DOF.
    Raises ``ValueError`` naming the nearest effect or the locations there are."""
    import difflib

    name, _, where = str(spec).strip().partition(":")
    if name not in EFFECTS:
        near = difflib.get_close_matches(name, EFFECTS, n=3, cutoff=0.5)
        hint = f"did you mean {' or '.join(near)}?" if near else f"effects: {', '.join(EFFECTS)}"
        raise ValueError(f"unknown effect {name!r}: {hint}")
    spring = name in SPRING_EFFECTS
    places = topology(n, boundary).identifiable_springs() if spring else list(range(1, n + 1))
    what = "spring" if spring else "DOF"
    if not where:
        if len(places) != 1:
            raise ValueError(
                f"{name} needs a location on this {n}-DOF chain: {name}:{what} with {what} in "
                f"{', '.join(map(str, places))}"
            )
        where = str(places[0])
    try:
        loc = int(where)
    except ValueError:
        raise ValueError(f"{spec}: the location must be a {what} number, got {where!r}") from None
    if loc not in places:
        raise ValueError(f"{spec}: no {what} {loc} on this {n}-DOF chain ({what}s: {', '.join(map(str, places))})")
    return name, loc if spring else loc - 1


def _given(st: Setup, ctx: Context, given: list[tuple[str, int]], progress) -> Scored:
    """The effects the user names, fitted (together when several: :func:`.candidates.fit_combination`)
    and scored whether or not they are significant; a state-dependent one refitted with the
    states reconstructed under it. A Stribeck fit starts from the Coulomb fit at its place."""
    if len({(e, loc) for e, loc in given}) < len(given):
        raise ValueError("an effect is given twice at the same place")
    if len(given) > 1 and not all(e in ADDITIVE for e, _ in given):
        raise ValueError(f"only these effects can be fitted together: {', '.join(ADDITIVE)}")
    fits = []
    for k, (eff, loc) in enumerate(given):
        _progress(progress, f"fitting {eff} ({k + 1}/{len(given)})")
        if eff in AFTER:
            fit_candidate(ctx, AFTER[eff], loc)
        fits.append(fit_candidate(ctx, eff, loc))
    scored = _refit_leaders(st, ctx, [_assess(st.P, st.lin, f, st.denom, st.floor) for f in fits], every=True)
    if len(scored) == 1:
        return scored[0]
    return _assess(st.P, st.lin, fit_combination(ctx, [s.fit for s in scored]), st.denom, st.floor)


def _dependency_groups(todo: list[tuple[str, int]]) -> list[list[tuple[str, int]]]:
    """The candidates in groups a thread fits in order: each one that reads another's result
    (:data:`AFTER`) right after that one at its location; the longest groups first, so that
    the threads finish together."""
    groups = {c: [c] for c in todo if not (c[0] in AFTER and (AFTER[c[0]], c[1]) in todo)}
    for c in todo:
        if c not in groups:
            groups[(AFTER[c[0]], c[1])].append(c)
    return sorted(groups.values(), key=len, reverse=True)


def _refit_leaders(st: Setup, ctx: Context, scored: list[Scored], every: bool = False) -> list[Scored]:
    """Refit the three leading state-dependent candidates (``every``: all of them, significant
    or not) with states reconstructed under them (a strong effect biases the states
    reconstructed by the linear model), repeated while the withheld gap keeps shrinking."""
    P, lin = st.P, st.lin
    if st.measured is not None:  # the states are measured, not reconstructed
        return scored
    for idx in range(len(scored) if every else min(3, len(scored))):
        s = scored[idx]
        if s.fit.effect not in STATE_EFFECTS or not (s.significant or every):
            continue
        loc = s.fit.location.get("dof", s.fit.location.get("spring"))
        loc = loc - 1 if "dof" in s.fit.location else loc
        for _ in range(STATE_REFITS):
            thetas = list(lin.theta_a)
            for e, th in zip(s.fit.eqs, s.fit.thetas):
                thetas[e] = th
            x, v = reconstruct_states(P, thetas, raw_residual(ctx, s.fit))
            refit = _assess(
                P,
                lin,
                fit_candidate(replace(ctx, x=x, v=v), s.fit.effect, loc),
                st.denom,
                st.floor,
            )
            if refit.gap_after >= 0.999 * s.gap_after:
                break
            s = refit
        scored[idx] = s
    return scored


def _combination(st: Setup, ctx: Context, scored: list[Scored]) -> Scored | None:
    """The best single candidate (when additive) fitted together with one of the next
    :data:`COMBINATION_LEADERS` physical additive candidates of another effect or place
    (an effect masked by a stronger one rarely stands out alone), kept when the pair
    beats the single candidate beyond noise: its per-sub-block withheld error reduction
    over the single one's has a t statistic of at least :data:`Z_CRIT` and removes at least
    :data:`COMBINATION_GAIN` of the single one's remaining withheld error; both parts
    physical. Dry friction twice (Coulomb and Stribeck) is one effect, not a pair."""
    best = next((s for s in scored if s.significant), None)
    if best is None or best.fit.effect not in ADDITIVE:
        return None
    others = [
        s
        for s in scored
        if s.fit.effect in ADDITIVE
        and s is not best
        and s.physical
        and not (s.fit.effect == best.fit.effect and s.fit.location == best.fit.location)
        and not {s.fit.effect, best.fit.effect} <= {"coulomb_friction", "stribeck_friction"}
    ]
    left = best.gap_after**2 * st.denom
    found = None
    for other in others[:COMBINATION_LEADERS]:
        try:
            pair = _assess(st.P, st.lin, fit_combination(ctx, [best.fit, other.fit]), st.denom, st.floor)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError):
            continue
        diff = pair.reduction - best.reduction
        sd = diff.std(ddof=1)
        t = diff.mean() / (sd / np.sqrt(diff.size)) if sd > 0 else 0.0
        if (
            pair.physical
            and t >= Z_CRIT
            and diff.sum() >= COMBINATION_GAIN * left
            and (found is None or pair.gap_after < found.gap_after)
        ):
            found = pair
    return found


def force_gap(P: Prepared, lin: LinearFit, test_sse_eq: np.ndarray) -> float:
    """The force-domain gap: RMS of the withheld force-equation errors over the RMS of the
    forces, from per-equation withheld squared errors in target units (forced DOFs)."""
    scale = force_scale(P, lin.theta)
    forced = P.forced
    num = float(np.sum(test_sse_eq[..., forced] * scale[forced] ** 2))
    den = float(np.sum(P.u[:, forced] ** 2))
    return float(np.sqrt(num / den)) if den > 0 else float("nan")


def diagnose(
    rec: Recording,
    boundary: str = "fixed",
    progress: Callable[[str], None] | None = None,
    effects: tuple[str, ...] = EFFECTS,
    given: list[str] | None = None,
    quick: bool = False,
    notch: bool = True,
    band_hz: tuple[float, float] | None = None,
    **reading,
) -> Diagnosis:
    """Locate and explain the gap between a recording and the linear chain.

    Parameters
    ----------
    rec : Recording, path or DataFrame
        Forces and accelerations (or velocities, or displacements) of every DOF, in SI or in
        the units ``rec.units`` declares (the result's ``units`` are built from them); a path
        or a DataFrame is read by :func:`algid.load_recording`.
    boundary : {"fixed", "free"}, the right end of the chain, or a
        :class:`~algid.model.network.Network`: the record's spring network.
    progress : callable or None, called with a short message at every stage.
    effects : candidate effects to try (default: all of :data:`EFFECTS`).
    given : list of ``NAME[:LOCATION]`` or None
        Fit these effects (together when several) instead of searching: the result reports
        them, significant or not, with the gap they leave (:func:`parse_effect`).
    quick : bool
        Search every candidate's parameter on a coarse grid alone
        (:data:`.candidates.QUICK_GRID` points, no refinement): the verdict, a few times
        faster, with rougher parameters (:func:`algid.identify`'s fit check).
    notch : bool
        Notch the mains hum out first (False: the caller has, as :func:`algid.identify` does).
    band_hz : (low, high) [Hz] or None
        Impact records: the band of the modes the chain holds (:mod:`algid.recording.transient`).
    **reading
        How to read a path or a DataFrame, as ``algid diagnose``'s options say (``force``,
        ``accel``, ``units``, ``rate``...: :func:`algid.recording.options.reading_options`).

    Returns
    -------
    Diagnosis
    """
    rec = as_recording(rec, **reading)
    if rec.base is not None:
        raise RecordingError(
            "a base-excited record (support motion a0): the diagnosis's equations have the wall at rest; "
            "run `algid identify`, which takes the support's motion"
        )
    if not isinstance(boundary, Network) and boundary not in ("fixed", "free"):
        raise ValueError(f"boundary must be 'fixed', 'free' or a Network, got {boundary!r}")
    topology(rec.n, boundary)  # a network of the record's DOFs
    clock = time.perf_counter()
    named = None if given is None else [parse_effect(g, rec.n, boundary) for g in given]
    st = _prepare(rec, boundary, progress, notch, band_hz)
    d = _analyse(rec, st, boundary, progress, effects, named, quick, clock)
    if named is None and d.effect in SKEW_LIKE:
        again = _timing_with_effect(st, d.ranking, boundary, effects, progress, clock)
        d = d if again is None else _analyse(rec, again, boundary, progress, effects, named, quick, clock)
    return d


def _analyse(rec: Recording, st: Setup, boundary, progress, effects, named, quick: bool, clock: float) -> Diagnosis:
    """Steps 3-5 of the module docstring on the prepared record ``st`` (:func:`diagnose`'s
    arguments; ``named`` the given effects parsed, None to search)."""
    P, lin, denom = st.P, st.lin, st.denom
    gap_before = float(np.sqrt(lin.cv.test_sse.sum() / denom))
    gap_before_full = float(np.sqrt(lin.cv.test_sub_full.sum() / denom))
    ctx = _context(st, quick)
    scored = _candidates(st, ctx, effects, progress) if named is None else [_given(st, ctx, named, progress)]
    combo = _combination(st, ctx, scored) if named is None else None
    st.timings["candidates"] = time.perf_counter() - clock - st.timings["linear"]

    _progress(progress, "locating the gap")
    natural = natural_frequencies(lin, boundary)
    where = locate(P, lin, natural, st.floor)
    floor_rel_full = float(np.sqrt(np.sum(st.floor**2) * P.y.shape[0] / denom))
    best = scored[0] if named is not None else next((s for s in scored if s.significant), None)
    if gap_before < GAP_RESOLUTION and named is None:
        best = None
    final = lin.resid if best is None else detrend(P, raw_residual(ctx, best.fit)).reshape(lin.resid.shape)
    floor_white, floor_rel = relative_floors(P, st.floor_band, denom, final, st.shapes)
    verdict = (
        _verdict(gap_before, gap_before_full, floor_rel, best, st.model, floor_white)
        if named is None
        else {"effect": best.fit.effect, "best": best, "explained": _explained(gap_before, best.gap_after, floor_rel)}
    )
    effect, best, explained = verdict["effect"], verdict["best"], verdict["explained"]
    gap_after = best.gap_after if best is not None else gap_before
    gap_after_full = best.gap_after_full if best is not None else gap_before_full
    lin_sse = lin.cv.test_sse_eq.sum(axis=0)
    force = {"gap_before": force_gap(P, lin, lin_sse)}
    force["gap_after"] = force["gap_before"] if best is None else force_gap(P, lin, _candidate_sse_eq(lin, best))
    st.timings["total"] = time.perf_counter() - clock
    return Diagnosis(
        effect=effect,
        location=best.fit.location if best else None,
        params=best.fit.params if best else {},
        params_std=best.fit.params_std if best else {},
        gap_before=gap_before,
        gap_after=gap_after,
        gap_before_full=gap_before_full,
        gap_after_full=gap_after_full,
        band=st.band,
        ranking=scored,
        P=P,
        lin=lin,
        best=best,
        timings=st.timings,
        where=where,
        extra={
            "natural_hz": natural.tolist(),
            "noise_floor": floor_rel,
            "noise_floor_full": floor_rel_full,
            "explained_excess": explained,
            "ctx": ctx,
            "model": st.model,
            "force": force,
            "form": P.form,
            "combination": combo if best is not None else None,
            "mains_hz": st.hum,
            "noise_levels": st.noise,
            "given": named is not None,
            "transient": st.transient.to_json() if st.transient is not None else None,
            "timing": st.timing.to_json() if st.timing is not None else None,
        },
        units=diagnosis_units(rec.units, recording_motion(rec)[0]),
        recording_units=dict(rec.units),
        recording_notes=list(rec.notes),
    )


def relative_floors(
    P: Prepared, floor_band: np.ndarray, denom: float, resid: np.ndarray, shapes: np.ndarray | None = None
) -> tuple[float, float]:
    """The in-band noise floor relative to the targets (the scale of the withheld gap,
    ``denom`` their squared sum): white (from the noise model's in-band ``floor_band``, at
    least :data:`GAP_RESOLUTION` / :data:`UNKNOWN_FLOOR_RATIO`), and with the 1/f part of the
    detrended equation errors ``resid`` (N, n) of the final model (:func:`coloured_floor`:
    the noise of a sensor may be coloured; ``shapes``: :func:`noise_shapes`)."""
    white = float(np.sqrt(np.sum(floor_band**2) * P.y.shape[0] / denom))
    white = max(white, GAP_RESOLUTION / UNKNOWN_FLOOR_RATIO)
    return white, max(white, float(np.sqrt(coloured_floor(P, resid, shapes).sum() / denom)))


def coloured_floor(P: Prepared, resid: np.ndarray, shapes: np.ndarray | None = None) -> np.ndarray:
    """(n,) in-band noise power of detrended equation errors ``resid`` (N, n), summed over
    the analysed samples, under a white plus 1/f noise model: per DFT bin of a window, the
    mean power over the windows; the white level ``w`` from the bins above the band
    (:func:`algid.recording.noise.white_floor`); the 1/f level ``p`` the median over the band's
    bins of what the white noise leaves, over the 1/f noise's shape (a median: an effect's
    power on a few bins does not move it); the floor the sum of both over the band. The
    shapes are those of accelerometer noise carried through the analysis (``shapes``,
    :func:`noise_shapes`), else flat and ``1/f`` (noise on the equation itself). For white
    noise ``p`` is about 0 and this is the white floor's band share."""
    pw = _bin_power(P, resid)
    fk = np.fft.rfftfreq(P.L, P.dt)
    band = P.band_mask & (fk > 0)
    if P.full_band or band.sum() < 4:  # no bins above the band to tell the white level
        return np.zeros(P.n)
    above = ~P.band_mask
    flat = (np.ones_like(pw), np.broadcast_to(1.0 / np.maximum(fk, fk[1])[:, None], pw.shape))
    g0, g1 = flat if shapes is None else shapes
    if above.sum() >= 2:
        w = white_floor(fk[above], pw[above]) / white_floor(fk[above], g0[above])
    else:
        w = np.median(pw / g0, axis=0)
    p = np.median(np.maximum(pw[band] - w * g0[band], 0.0) / g1[band], axis=0)
    return P.nw * np.sum(w * g0[band] + p * g1[band], axis=0)


def _candidate_sse_eq(lin: LinearFit, s: Scored) -> np.ndarray:
    """(n,) withheld in-band squared error per equation with the candidate's equations."""
    out = lin.cv.test_sse_eq.sum(axis=0).copy()
    cand = s.fit.cv.test_sub.sum(axis=(0, 1))  # (E,) over the candidate's equations
    for k, e in enumerate(s.fit.eqs):
        out[e] = cand[k]
    return out


def _verdict(
    gap_before: float,
    gap_before_full: float,
    floor_rel: float,
    best: Scored | None,
    model: ModelVerdict,
    floor_white: float | None = None,
) -> dict:
    """Effect verdict (module docstring, step 4): the best significant candidate unless it
    leaves most of a large gap unexplained (``unknown``), or, on a record with more modes
    than the chain, unless it brings the gap to the white noise floor; ``none`` only when
    nothing is beyond noise, the gap is at the noise floor, the linear fit is admissible
    and the record has no more modes than the chain (:mod:`.model`); else ``unknown``."""
    if model.verdict == "no_force_response":  # nothing to explain an effect of
        return {"effect": "unknown", "best": None, "explained": 0.0}
    if best is None:
        at_floor = gap_before <= FIT_FLOOR_RATIO * floor_rel
        fits = model.admissible and model.verdict != "more_modes_than_dof"
        return {"effect": "none" if at_floor and fits else "unknown", "best": None, "explained": 0.0}
    explained = _explained(gap_before, best.gap_after, floor_rel)
    if best.gap_after > UNKNOWN_FLOOR_RATIO * floor_rel and explained < MIN_EXPLAINED:
        return {"effect": "unknown", "best": None, "explained": explained}
    white = floor_rel if floor_white is None else floor_white
    if model.verdict == "more_modes_than_dof" and best.gap_after > UNKNOWN_FLOOR_RATIO * white:
        # a chain short of modes leaves a gap no effect of the chain closes: only an effect
        # that brings it to the white noise floor is an explanation
        return {"effect": "unknown", "best": None, "explained": explained}
    return {"effect": best.fit.effect, "best": best, "explained": explained}


def _explained(gap_before: float, gap_after: float, floor_rel: float) -> float:
    """Share of the gap's excess over the noise floor that an effect removes."""
    excess = gap_before**2 - floor_rel**2
    return float((gap_before**2 - gap_after**2) / excess) if excess > 0 else 1.0


def fitted_chain(lin: LinearFit, boundary) -> Chain | NetworkModel | None:
    """The chain (or the network, ``boundary`` a Network) of the linear fit's magnitudes
    (None if unphysical)."""
    n = len(lin.theta)
    k = np.nan_to_num(lin.stiffness().copy())
    if isinstance(boundary, Network):
        try:
            return NetworkModel(boundary, np.abs(lin.mass), np.abs(lin.damping()), np.abs(k))
        except ValueError:
            return None
    if n == 1:
        k = np.array([k[0], 0.0])
    try:
        return Chain(np.abs(lin.mass), np.abs(lin.damping()), np.abs(k), boundary if n > 1 else "fixed")
    except ValueError:
        return None


def natural_frequencies(lin: LinearFit, boundary: str) -> np.ndarray:
    """Undamped natural frequencies [Hz] of the fitted chain (empty if unphysical)."""
    ch = fitted_chain(lin, boundary)
    return ch.natural_frequencies_hz() if ch is not None else np.array([])
