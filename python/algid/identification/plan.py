"""How to estimate from a recording: the single window or the continuous estimator, and
their settings, from the recording's own time scales. Identify's plan stage is
:func:`plan_record`: a first look at the chain's time scales, then the rules below.

Rules (every threshold named below):

* **Which estimator.** The paper's single growing window is exact on clean signals and
  needs no settings, but the iterated integrals of sensor noise grow with the window, so
  its error grows with the record under noise (``docs/continuous.md``). The record is
  *clean* when every channel's in-band SNR is at least :data:`CLEAN_SNR_DB` and no
  displacement comes in encoder counts. ``auto`` takes the single window for a clean record
  of at most :data:`SHORT_S`, and for any record too short to give the continuous estimator
  :data:`MIN_WINDOW_RESULTS` window results of at least :data:`SHORTEN_MAX` of the window
  its time scale asks for; otherwise the continuous estimator.
* **Window length** of the continuous estimator. A first estimate of the chain
  (:func:`.motion.equation_error_fit`) with a natural frequency inside the signal band sets
  it to :data:`MODE_PERIODS` periods of the lowest one (a window must see the slowest mode
  swing to tell its spring from its mass; longer windows integrate more noise): one period
  for the weak-form windows, whose long windows (three times as long) join them; half a
  period as the first guess of the algebraic windows, whose length is then the best of its
  multiples :data:`WINDOW_MULTIPLES` by the error the bootstrap measures
  (:func:`.estimate.select_window`). Without a mode in the band, one period of the force's
  median frequency (a chain without springs, such as a positioning axis, has no mode; its
  windows must hold whole moves). Clipped to at least :data:`MIN_WINDOW_SAMPLES` samples and
  at most the record over :data:`MIN_WINDOW_RESULTS` / ``stagger``.
* **Window results** (``method``): the weak-form windows (GLS over every test-function row,
  bias-compensated, joined by their summed normal equations; ``docs/continuous.md``) when
  the record carries measured accelerations, whose sensor noise is white as their weights
  and bias terms assume; the paper's algebraic windows behind the prefilter when the
  accelerations are derived from velocities or displacements, whose noise the
  differentiation colours (``docs/identify.md`` compares the two on a positioning axis), or
  when an equation of the chain must stay out of the others' estimates (a base-excited record
  with a force, :mod:`.base`).
* **Impact records** (:mod:`algid.recording.transient`, decided once from the record): the
  record is already band-passed around the modes the chain holds, and the force's spectrum says
  nothing of the time scale, so the window is :data:`TRANSIENT_PERIODS` periods of the lowest of the
  response's modes in the band (:func:`window_length` given those modes) and the estimator the
  continuous one (the band-pass took the noise floor the clean test reads); the weak form is
  given the raw record's white-noise levels (the band-passed signals' fourth differences are
  signal; none for accelerations derived from velocities or displacements) and is the window
  method whatever the motion (the paper's algebraic windows need the force inside each window,
  and a decay has none); the prefilter as below, from the band's top.
* **Prefilter** (the same low-pass on forces and accelerations, which leaves eq. 1
  unchanged): :data:`PREFILTER_MARGIN` times the top of the signal band or of the natural
  frequencies, whichever is higher; off when that is above :data:`PREFILTER_MAX` of the
  sampling rate.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from ..model.chain import stiffness_matrix
from ..recording.noise import NoiseModel
from .motion import equation_error_fit
from .screen import Signals

#: In-band SNR [dB] of every channel above which a record counts as noise-free.
CLEAN_SNR_DB = 90.0
#: Longest clean record [s] that ``auto`` gives to the single growing window.
SHORT_S = 2.0
#: Fewest window results the continuous estimator must deliver over the record.
MIN_WINDOW_RESULTS = 24
#: Shortest window of the continuous estimator [samples].
MIN_WINDOW_SAMPLES = 48
#: A window shortened below this fraction of its guess to give enough window results
#: means the record is too short for the continuous estimator.
SHORTEN_MAX = 0.5
#: Window length in periods of the lowest natural frequency, per window method.
MODE_PERIODS = {"weak_form": 1.0, "algebraic": 0.5}
#: Window length of an impact record in periods of its lowest mode in the band: a lightly damped
#: decay shows its damping only over many periods.
TRANSIENT_PERIODS = 8.0
#: Multiples of the first guess of the algebraic windows' length that are tried.
WINDOW_MULTIPLES = (0.5, 0.7, 1.0, 1.4, 2.0)
#: A force whose median frequency is above this share of the Nyquist rate is broadband (white
#: up to the sampling rate): its period says nothing of the chain's time scale.
BROADBAND = 0.3
#: A signal band reaching this share of the Nyquist rate: the weak form takes its noise levels
#: from the noise model (the signals' fourth differences would count signal as noise).
BROADBAND_BAND = 0.8
#: Windows in flight (staggered) of the continuous estimator.
STAGGER = 4
#: Prefilter cut-off over the top of the band.
PREFILTER_MARGIN = 1.25
#: Highest prefilter cut-off as a fraction of the sampling rate (above it: no prefilter).
PREFILTER_MAX = 0.2

ESTIMATORS = ("auto", "window", "continuous")


@dataclass(frozen=True)
class Plan:
    """Which estimator runs and with which settings, and why."""

    estimator: str  #: "window" or "continuous"
    reason: str  #: one line: why this estimator
    window_s: float  #: continuous window length [s] (nan for the single window)
    prefilter_hz: float  #: continuous prefilter cut-off [Hz] (0 = off; nan for the single window)
    stagger: int  #: continuous windows in flight
    window_basis: str  #: what set the window length
    method: str = ""  #: continuous window results: "weak_form" or "algebraic" ("" for the single window)
    #: weak form: white-noise RMS of the accelerations and forces from the noise model, or -1 to let
    #: the estimator read it off the signals' fourth differences
    noise_rms: tuple = (-1.0, -1.0)

    def to_json(self) -> dict:
        d = asdict(self)
        for key in ("window_s", "prefilter_hz"):
            if not np.isfinite(d[key]):
                d[key] = None
        return d


def clean(nm: NoiseModel) -> bool:
    """Noise-free to the eye of the estimator (see the module docstring)."""
    if nm.quantised:
        return False
    snr = [c.snr_db for c in nm.forces + nm.motions if np.isfinite(c.snr_db)]
    return bool(snr) and min(snr) >= CLEAN_SNR_DB


def natural_frequencies_hz(theta: np.ndarray, n: int, boundary: str) -> np.ndarray:
    """Undamped natural frequencies [Hz] of packed estimates ``m1..mn, c1..cn, k1..k{n+1}``;
    empty when the estimates are not a physical chain (a mass not positive, a spring
    negative or not finite)."""
    m, k = theta[:n], theta[2 * n :].copy()
    if n == 1 and boundary == "fixed":
        k = np.array([k[0], 0.0])
    if boundary == "free":
        k[-1] = 0.0
    if not (np.all(np.isfinite(m)) and np.all(m > 0) and np.all(np.isfinite(k)) and np.all(k >= 0)):
        return np.array([])
    K = stiffness_matrix(k)
    lam = np.linalg.eigvals(K / m[:, None]).real
    return np.sort(np.sqrt(np.clip(lam, 0.0, None))) / (2 * np.pi)


def window_limits(nm: NoiseModel, duration_s: float) -> tuple[float, float]:
    """Shortest and longest continuous window [s] (module docstring)."""
    lo = MIN_WINDOW_SAMPLES * nm.dt
    return lo, max(lo, duration_s * STAGGER / MIN_WINDOW_RESULTS)


def window_method(nm: NoiseModel, joint: bool = True) -> str:
    """The continuous estimator's window results (module docstring); ``joint=False``: the
    algebraic windows, whatever the motion."""
    return "weak_form" if nm.motion == "acceleration" and joint else "algebraic"


def window_length(
    nm: NoiseModel, duration_s: float, f_natural: np.ndarray, joint: bool = True, periods: float | None = None
) -> tuple[float, str]:
    """First guess of the continuous window length [s] and what set it (module docstring);
    ``periods`` of the lowest natural frequency (default :data:`MODE_PERIODS`)."""
    fn = np.asarray(f_natural, dtype=float)
    fn = fn[np.isfinite(fn) & (fn > 2.0 / duration_s) & (fn <= nm.f_hi)]
    if fn.size:
        periods = MODE_PERIODS[window_method(nm, joint)] if periods is None else periods
        what = "one period" if periods == 1.0 else ("half a period" if periods == 0.5 else f"{periods:g} periods")
        f_ref, basis = float(fn.min()) / periods, f"{what} of the lowest natural frequency ({fn.min():.3g} Hz)"
    elif np.isfinite(nm.f_mid) and 0 < nm.f_mid < BROADBAND * nm.nyquist:
        f_ref, basis = nm.f_mid, f"one period of the force's median frequency ({nm.f_mid:.3g} Hz)"
    elif np.isfinite(nm.f_mid):
        f_ref, basis = 10.0 / duration_s, f"a tenth of the record (broadband force, median frequency {nm.f_mid:.3g} Hz)"
    else:
        f_ref, basis = 10.0 / duration_s, "a tenth of the record (no force stands out of its noise)"
    lo, hi = window_limits(nm, duration_s)
    L = float(np.clip(1.0 / f_ref, lo, hi))
    if L == lo and 1.0 / f_ref < lo:
        basis += f", raised to {MIN_WINDOW_SAMPLES} samples"
    elif L < SHORTEN_MAX * (1.0 / f_ref) - 1e-12:
        basis += f", shortened to give {MIN_WINDOW_RESULTS} window results"
    return L, basis


def prefilter_hz(nm: NoiseModel, f_natural: np.ndarray) -> float:
    """Prefilter cut-off [Hz] (0 = off), see the module docstring."""
    fn = np.asarray(f_natural, dtype=float)
    top = max([nm.f_hi] + [float(f) for f in fn if np.isfinite(f)])
    fc = PREFILTER_MARGIN * top
    return 0.0 if fc > PREFILTER_MAX / nm.dt else float(fc)


def make_plan(
    nm: NoiseModel,
    duration_s: float,
    requested: str = "auto",
    f_natural: np.ndarray | None = None,
    joint: bool = True,
    transient=None,
) -> Plan:
    """The plan for a record of ``duration_s`` [s] with noise model ``nm``.

    ``f_natural``: natural frequencies [Hz] of a first estimate (empty if none yet), or of the
    response's modes in the band for an impact record (``transient``, a
    :class:`algid.recording.transient.Transient`).
    ``joint=False``: an equation of the chain must not be pooled with the others (the support's
    of a base-excited record with a force, :mod:`.base`): the algebraic windows, which solve
    every DOF alone, rather than the weak form's joint solve.
    """
    f_natural = np.array([]) if f_natural is None else f_natural
    if requested not in ESTIMATORS:
        raise ValueError(f"estimator must be one of {ESTIMATORS}, got {requested!r}")
    L, basis = window_length(nm, duration_s, f_natural, joint, None if transient is None else TRANSIENT_PERIODS)
    fits = "shortened" not in basis and duration_s >= L * MIN_WINDOW_RESULTS / STAGGER - 1e-12
    is_clean = clean(nm)
    if requested != "auto":
        estimator, reason = requested, "requested (--estimator)"
    elif transient is not None:
        # band-passed: its noise floor outside the band is gone, so "clean" says nothing
        estimator = "continuous"
        reason = "impact record: windows of the response's modes over the whole record, aggregated"
    elif not fits:
        estimator = "window"
        reason = f"record of {duration_s:.3g} s too short for {MIN_WINDOW_RESULTS} continuous windows of {L:.3g} s"
    elif is_clean and duration_s <= SHORT_S:
        estimator = "window"
        reason = (
            f"clean record (in-band SNR >= {CLEAN_SNR_DB:g} dB) of at most {SHORT_S:g} s: "
            "the paper's single window is exact"
        )
    else:
        estimator = "continuous"
        why = "noisy" if not is_clean else f"longer than {SHORT_S:g} s"
        if nm.quantised:
            why = "displacement in encoder counts"
        reason = f"{why} record: reseeded windows of the recording's time scale, aggregated"
    if estimator == "window":
        return Plan("window", reason, float("nan"), float("nan"), 1, "the whole record")
    method = "weak_form" if transient is not None else window_method(nm, joint)
    plan = Plan("continuous", reason, L, prefilter_hz(nm, f_natural), STAGGER, basis, method)
    if method == "weak_form" and transient is not None:
        # derived accelerations: their noise is the motion's, coloured, not a white level to give
        rms = transient.noise_rms if nm.motion == "acceleration" else (0.0, transient.noise_rms[1])
        plan = replace(plan, noise_rms=tuple(float(s) for s in rms))
    elif method == "weak_form" and nm.f_hi >= BROADBAND_BAND * nm.nyquist:
        # signal up to the Nyquist rate: fourth differences are signal, not noise
        rms = [float(np.sqrt(np.mean([c.sigma**2 for c in chans]))) for chans in (nm.motions, nm.forces)]
        plan = replace(plan, noise_rms=tuple(rms))
    return plan


def plan_record(sig: Signals, nm: NoiseModel, boundary: str, requested: str = "auto", joint: bool = True) -> Plan:
    """Identify's plan stage: :func:`make_plan` for the record ``sig`` with noise model ``nm``,
    given the natural frequencies [Hz] of a first estimate of the chain
    (:func:`.motion.equation_error_fit`: eq. 1 on the DFT bins the forces excite), or of the
    response's modes in the band for an impact record."""
    if sig.transient is None:
        first = natural_frequencies_hz(equation_error_fit(sig.rec.u, sig.motion, nm, boundary), sig.rec.n, boundary)
    else:
        first = np.array(sig.transient.in_band_hz)
    return make_plan(nm, sig.duration_s, requested, first, joint, sig.transient)


def window_candidates(plan: Plan, nm: NoiseModel, duration_s: float) -> list[Plan]:
    """The plan with its window scaled by :data:`WINDOW_MULTIPLES`, and the same around the
    force-based guess when the plan's guess came from a natural frequency (a first estimate
    of a chain the record does not fit can put its modes anywhere); within the limits,
    lengths closer than 10 % to one already tried dropped. The plan itself for the single
    window."""
    if plan.estimator != "continuous":
        return [plan]
    lo, hi = window_limits(nm, duration_s)
    guesses = [(plan.window_s, plan.window_basis)]
    force_L, force_basis = window_length(nm, duration_s, np.array([]))
    if force_basis != plan.window_basis:
        guesses.append((force_L, force_basis))
    out: list[Plan] = []
    for L0, basis in guesses:
        for f in WINDOW_MULTIPLES:
            L = float(np.clip(L0 * f, lo, hi))
            if any(abs(L / p.window_s - 1.0) < 0.1 for p in out):
                continue
            out.append(replace(plan, window_s=L, window_basis=basis if f == 1.0 else f"{f:g} x ({basis})"))
    return out
