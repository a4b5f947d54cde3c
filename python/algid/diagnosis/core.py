"""Windowed equation-error machinery shared by the location, candidate and report steps.

The equation of DOF i (eq. 1 plus an optional unmodelled effect g), solved for the
acceleration,

    a_i = (u_i - c_i v_i - k_i (x_i - x_{i-1}) - k_{i+1} (x_i - x_{i+1}) - g_i) / m_i,

is linear in ``[1/m_i, c_i/m_i, k_i/m_i, k_{i+1}/m_i]`` with the (noisy) measured
acceleration alone on the left: sensor noise stays out of the regressors, and the error
is in acceleration units. A DOF without force (``u_i = 0`` throughout, e.g. a response
point of a structure excited elsewhere) has no scale: its parameters are reported per
unit mass (``m_i = 1``). The equation needs velocities and displacements, which are not measured. Integrating the measured
accelerations from the start of the record gives ``A1 = int a`` and ``A2 = int int a``
(the same exact-for-polynomials interpolatory quadrature as the estimator, 6 points);
the true signals are ``v = A1 + p`` and ``x = A2 + q + p (t - t_w)`` on every window
``w``, with unknown constants ``p``, ``q`` (initial conditions plus the random walk that
integrated sensor noise adds). Substituted into eq. 1 they contribute, per equation and
per window, a first-degree polynomial in time ``alpha + beta (t - t_w)``. The algebraic
identification kills initial conditions by integration by parts; here they are killed by
projecting every regressor and the target, window by window, orthogonally to
``{1, t - t_w}`` ("detrending"), which removes exactly those terms and keeps every other
parameter linear. The windows are short enough (see :func:`window_length`) that the
integrated noise does not drift far inside one of them.

All least-squares problems are then reduced to per-window sufficient statistics (Gram
matrices of the detrended columns): a fit on any set of windows is a sum of Grams and a
small solve, and the error of that fit on any other window is a quadratic form. This is
what makes the cross-validation of dozens of candidate effects cheap: windows are dealt
to ``K`` interleaved folds; each fold is withheld once while the model is fitted on the
others.

Metric. The error of every equation is the difference between the measured acceleration
and the acceleration the model predicts from the recorded force and the reconstructed
displacement and velocity. ``gap = sqrt(sum of squared withheld in-band errors over all
DOF) / sqrt(sum of squared measured accelerations)``, i.e. the normalised RMS acceleration
equation error on withheld windows (after the per-window initial-condition terms),
restricted to the signal band ``[0, f_hi]`` of the recording (:func:`signal_band`): on
every window the detrended error is projected onto the DFT bins of the window at or
below ``f_hi`` (:func:`band_filter`; an orthogonal projection, so the in-band squared
error of a window is a quadratic form of the same kind as the full-band one and the
whole fold machinery carries over). The fits themselves stay full-band least squares;
only the scoring of withheld windows is restricted. Outside the band the recording
carries no signal, only the accelerometer's white noise, which no model can explain and
which would otherwise bound the gap shrink by the ratio of the full-band to the in-band
noise. The full-band gap (the same without the projection) is reported alongside.

Band rule (from the recording alone, :func:`signal_band`): Welch PSD (Hann, segments of
about 1 s) of every recorded force and every measured acceleration; per signal a noise
floor = median PSD over the upper third of the spectrum; the bins more than
:data:`BAND_DETECT` times above it carry signal; the signal frequency ``f_exc`` is the
frequency below which :data:`BAND_POWER` of that signal's above-floor power lies
(maximum over the signals: the band is never narrower than where either the forces or
the responses carry signal; accelerations derived from velocities or displacements are
left out, their differentiated noise rising with frequency). ``f_hi = min(f_Nyquist, max(BAND_HARMONICS f_exc,
BAND_MODES f_n,max))`` with ``f_n,max`` the highest natural frequency of the linear chain
fitted first: the band keeps the harmonics up to the third that polynomial nonlinearities
(cubic spring, clearance, Coulomb friction, quadratic damping) create from the
excitation, and every mode. The low edge is 0 (bias and drift live there; the
per-window detrending removes the lines).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from functools import lru_cache

from ..noise import white_floor
from ..reference import quadrature_weights

#: Quadrature points of the integrals A1, A2 (as the estimator's default).
QUAD_POINTS = 6
#: Which signal the forced DOFs' equations are solved for (:func:`target`).
FORMS = ("acceleration", "force")
#: Number of interleaved cross-validation folds (fewer if there are fewer windows).
N_FOLDS = 8
#: Sub-blocks per window on which withheld errors are also reported (the unit of the
#: paired significance test; the fits and the detrending stay per window).
N_SUB = 4
#: Band rule (see the module docstring): a PSD bin carries signal above this multiple of
#: the noise floor; f_exc holds this share of the above-floor power; the band edge is at
#: least this multiple of f_exc and of the highest natural frequency.
BAND_DETECT = 10.0
BAND_POWER = 0.99
BAND_HARMONICS = 3.0
BAND_MODES = 1.25
METRIC = (
    "nrms_accel_equation_error_in_band: RMS over the withheld windows and all DOF of "
    "(measured acceleration - acceleration predicted by each DOF's equation from the "
    "recorded force and reconstructed displacement/velocity, after the per-window "
    "initial-condition terms), projected per window onto the DFT bins in the signal band "
    "[0, f_hi] of the recording (f_hi = min(Nyquist, max(3 f_exc, 1.25 f_n,max)), f_exc: "
    "largest over the recorded forces and accelerations of the frequency below which 99 % "
    "of the PSD power above 10x the signal's noise floor lies, f_n,max: highest natural "
    "frequency of the linear fit), divided by the RMS of the measured accelerations; "
    "*_fullband: the same without the band projection"
)


METRIC_FORCE = (
    "nrms_force_equation_error_in_band: the same withheld in-band equation errors in force units (each "
    "acceleration-form error times its DOF's fitted mass), RMS over the forced DOFs divided by the RMS of their "
    "recorded forces: the error measure of drive and friction studies"
)


def window_length(dt: float, f_low_hz: float, T: int, periods: float = 0.5, max_s: float = 1.0) -> int:
    """Samples per window: ``periods`` (half a) period of the lowest natural frequency,
    clipped to [0.1 s, ``max_s``] and to at most an eighth of the record (at least 8
    windows for cross-validation), never fewer than 32 samples, a multiple of
    :data:`N_SUB`. (A quasi-static record, analysed in the force form, takes one period of
    its lowest forced frequency and no 1 s cap: nothing there integrates noise, and a
    window shorter than the motion's period leaves little once its line is removed.)

    Short windows keep the random walk of the integrated sensor noise small (its
    displacement error grows like the window length to the power 1.5, and on a window
    of half the lowest period it stays below the white noise of the accelerometer in the
    equation error); a mode of period 2 W still bends visibly within a window, so the
    per-window line removes little of the signal."""
    w_s = periods / max(f_low_hz, 1e-6)
    w_s = min(max(w_s, 0.1), max_s)
    L = int(round(w_s / dt))
    L = min(L, T // 8)
    L = max(L, 32)
    return L - L % N_SUB


@dataclass
class Band:
    """Signal band ``[0, f_hi]`` of a recording (:func:`signal_band`).

    f_hi : upper edge [Hz]; f_exc : signal frequency [Hz] (nan if no signal found);
    f_modes : highest natural frequency used [Hz] (nan if none); nyquist [Hz];
    f_derived_noise : where derived accelerations sink into their differentiated noise
    [Hz] (nan for measured accelerations);
    source : the signal that sets f_exc ("force 1", "acceleration 2", ...; "" if none);
    f_signals : f_exc of every signal used (nan: nothing above its floor);
    floors : noise-floor PSD of every signal used [unit^2/Hz].
    """

    f_hi: float
    f_exc: float
    f_modes: float
    nyquist: float
    source: str
    floors: list
    f_signals: dict = field(default_factory=dict)
    f_derived_noise: float = float("nan")

    @property
    def full(self) -> bool:
        return bool(self.f_hi >= self.nyquist)

    def to_json(self) -> dict:
        return {"band_hz": [0.0, self.f_hi], "f_excitation_hz": self.f_exc,
                "f_natural_max_hz": self.f_modes, "nyquist_hz": self.nyquist, "source": self.source,
                "f_derived_noise_hz": self.f_derived_noise,
                "f_signals_hz": self.f_signals, "noise_floor_psd": self.floors,
                "rule": f"f_hi = min(Nyquist, max({BAND_HARMONICS:g} f_exc, {BAND_MODES:g} f_n,max)); f_exc: "
                        f"largest over the forces and accelerations of the frequency below which "
                        f"{BAND_POWER:.0%} of the PSD power in bins above {BAND_DETECT:g}x the median PSD of "
                        "the upper third of the spectrum lies"}


def excitation_frequency(x: np.ndarray, dt: float) -> tuple[float, float]:
    """``(f_exc, floor)`` of one signal: Welch PSD (Hann, ~1 s segments), noise floor =
    median PSD over the upper third of the spectrum, f_exc = frequency below which
    :data:`BAND_POWER` of the power in bins above :data:`BAND_DETECT` x floor lies (above
    the floor); nan when no bin is above."""
    from scipy.signal import welch

    x = np.asarray(x, dtype=float)
    T = x.size
    nper = int(min(T, max(256, min(T // 4, round(1.0 / dt)))))
    f, S = welch(x, fs=1.0 / dt, nperseg=nper)
    floor = float(white_floor(f, S))
    exc = np.where(S > BAND_DETECT * floor, S - floor, 0.0)
    tot = exc.sum()
    if not tot > 0:
        return float("nan"), floor
    c = np.cumsum(exc) / tot
    return float(f[min(int(np.searchsorted(c, BAND_POWER)), f.size - 1)]), floor


def derived_noise_limit(a: np.ndarray, motion: np.ndarray, dt: float, order: int) -> float:
    """Highest frequency [Hz] at which accelerations differentiated ``order`` times from
    ``motion`` stand :data:`BAND_DETECT` times above their own noise: the motion's white
    floor (median PSD of its upper third) times ``(2 pi f)^(2 order)``, the gain of
    differentiation. Above it the derived accelerations are noise whatever the model."""
    from scipy.signal import welch

    nper = int(min(a.shape[0], max(256, min(a.shape[0] // 4, round(1.0 / dt)))))
    f, Sa = welch(a, fs=1.0 / dt, nperseg=nper, axis=0)
    _, Sm = welch(motion, fs=1.0 / dt, nperseg=nper, axis=0)
    floor = white_floor(f, Sm)
    noise = floor[None, :] * (2 * np.pi * f[:, None]) ** (2 * order)
    above = np.any(Sa > BAND_DETECT * noise, axis=1)
    above[0] = False
    return float(f[np.nonzero(above)[0].max()]) if above.any() else float(f[1])


def signal_band(a: np.ndarray, u: np.ndarray, dt: float, natural_hz=(), derived: tuple | None = None) -> Band:
    """The band ``[0, f_hi]`` in which the recording carries signal (module docstring):
    from the forces of the forced DOFs, the accelerations and the natural frequencies of a
    first linear fit. Never uses anything but the recording.

    ``derived = (motion, order)``: the accelerations were differentiated ``order`` times
    from the recorded ``motion`` (velocities or displacements). Their noise then grows
    like ``f^order``: no flat floor tells it from signal, so the forces (and the modes)
    set the band, which is cut where the accelerations sink into their differentiated
    noise (:func:`derived_noise_limit`)."""
    a = np.atleast_2d(np.asarray(a, dtype=float).T).T
    u = np.atleast_2d(np.asarray(u, dtype=float).T).T
    nyq = 0.5 / dt
    forced = np.any(u != 0.0, axis=0)
    cols = {f"force {i + 1}": u[:, i] for i in np.nonzero(forced)[0]}
    if derived is None or not cols:
        cols.update({f"acceleration {i + 1}": a[:, i] for i in range(a.shape[1])})
    res = {name: excitation_frequency(c, dt) for name, c in cols.items()}
    fe = {name: f for name, (f, _) in res.items() if np.isfinite(f)}
    source = max(fe, key=fe.get) if fe else ""
    f_exc = fe[source] if fe else float("nan")
    fn = np.asarray(natural_hz, dtype=float)
    fn = fn[np.isfinite(fn) & (fn > 0)]
    f_modes = float(fn.max()) if fn.size else float("nan")
    if not fe:
        f_hi = nyq
    else:
        f_hi = min(nyq, max(BAND_HARMONICS * f_exc, BAND_MODES * f_modes if fn.size else 0.0))
    f_noise = float("nan")
    if derived is not None:
        f_noise = derived_noise_limit(a, np.atleast_2d(np.asarray(derived[0], dtype=float).T).T, dt, derived[1])
        f_hi = min(f_hi, max(f_noise, f_exc if np.isfinite(f_exc) else 0.0))
    return Band(f_hi=float(f_hi), f_exc=f_exc, f_modes=f_modes, nyquist=nyq, source=source,
                floors=[fl for _, fl in res.values()], f_signals={k: f for k, (f, _) in res.items()},
                f_derived_noise=f_noise)


@dataclass
class Prepared:
    """Signals cut into ``nw`` windows of ``L`` samples after ``skip`` leading samples
    (the tail ``T - skip - nw L`` is dropped).

    Attributes
    ----------
    t : (N,) time since the first recorded sample [s], N = nw L.
    a, u : (N, n) accelerations [m/s^2] and forces [N] on the analysed samples.
    A1, A2 : (N, n) single and double integrals of ``a`` from the first recorded
        sample [m/s], [m].
    a_full, u_full, A1_full, A2_full : the same over the whole record (for filters
        and delays that need the samples before the first window).
    skip : index of the first analysed sample in the full record.
    dt : sampling interval [s]; duration : length of the whole record, T dt [s].
    L, nw : window length [samples] and number of windows.
    boundary : "fixed" or "free".
    folds : (nw,) fold index of every window.
    band_hz : upper edge of the signal band [Hz] (None: the whole band); the withheld
        errors are scored on the DFT bins of every window at or below it
        (``band_mask``, (L//2+1,) bool; ``band_fraction``: share of a window's white
        noise power on those bins; ``full_band``: every bin kept).
    form : "acceleration" or "force": which signal each forced DOF's equation is solved
        for (:func:`target`); ``y`` (N, n) those targets.
    fit_band : fit on the band-projected windows too, not only score on them (accelerations
        differentiated from velocities or displacements carry noise that grows with
        frequency; out of band it would bias every regressor it enters).
    """

    a_full: np.ndarray
    u_full: np.ndarray
    A1_full: np.ndarray
    A2_full: np.ndarray
    skip: int
    dt: float
    L: int
    nw: int
    boundary: str
    folds: np.ndarray
    band_hz: float | None = None
    form: str = "acceleration"
    fit_band: bool = False
    tau: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.tau = self.dt * np.arange(self.L)
        s = np.arange(self.L) - (self.L - 1) / 2.0
        self.basis = np.stack([np.full(self.L, 1.0 / np.sqrt(self.L)), s / np.linalg.norm(s)], axis=1)
        self._cache: dict = {}
        sl = self.sl
        self.a, self.u = self.a_full[sl], self.u_full[sl]
        self.A1, self.A2 = self.A1_full[sl], self.A2_full[sl]
        self.t = self.dt * np.arange(sl.start, sl.stop)
        self.duration = self.dt * self.a_full.shape[0]
        self.forced = np.any(self.u_full != 0.0, axis=0)
        if self.form not in FORMS:
            raise ValueError(f"form must be one of {FORMS}, got {self.form!r}")
        self.y = np.stack([target(self, e) for e in range(self.n)], axis=1)
        fk = np.fft.rfftfreq(self.L, self.dt)
        self.band_mask = np.ones(fk.size, dtype=bool) if self.band_hz is None else fk <= self.band_hz * (1 + 1e-12)
        self.band_mask[0] = True
        self.full_band = bool(self.band_mask.all())
        self.band_fraction = float(np.sum(parseval_weights(self.L) * self.band_mask) / self.L)

    @property
    def sl(self) -> slice:
        """Analysed samples within the full record."""
        return slice(self.skip, self.skip + self.nw * self.L)

    @property
    def n(self) -> int:
        return int(self.a_full.shape[1])

    @property
    def nfolds(self) -> int:
        return int(self.folds.max()) + 1

    def windows(self, x: np.ndarray) -> np.ndarray:
        """Reshape a (N, ...) array to (nw, L, ...)."""
        return x.reshape(self.nw, self.L, *x.shape[1:])


@lru_cache(maxsize=4)
def _weights(points: int) -> np.ndarray:
    return quadrature_weights(points, 2)


def integrals(a: np.ndarray, dt: float, points: int = QUAD_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """``(int a, int int a)`` from the first sample for every column of ``a`` (T, c).

    The quadrature of :func:`algid.reference.iterated_integrals` (on every interval the
    degree ``points-1`` interpolant through the nearest samples, integrated exactly),
    vectorised over columns.
    """
    a = np.asarray(a, dtype=float)
    T = a.shape[0]
    if T < points:
        raise ValueError(f"need at least {points} samples")
    W = _weights(points)
    half = points // 2
    j = np.arange(T - 1)
    start = np.clip(j - (half - 1), 0, T - points)
    off = j - start
    stencil = a[start[:, None] + np.arange(points)[None, :]]  # (T-1, points, c)
    inc1 = dt * np.einsum("jm,jmc->jc", W[off, 0], stencil)
    inc2 = dt**2 * np.einsum("jm,jmc->jc", W[off, 1], stencil)
    A1 = np.zeros_like(a)
    A2 = np.zeros_like(a)
    A1[1:] = np.cumsum(inc1, axis=0)
    A2[1:] = np.cumsum(inc2 + dt * A1[:-1], axis=0)
    return A1, A2


def parseval_weights(L: int) -> np.ndarray:
    """Weights of the one-sided DFT bins of a real window of L samples in Parseval's sum
    (``sum x^2 = sum_k w_k |X_k|^2 / L``): 1 for DC (and Nyquist for even L), 2 else."""
    w = np.full(L // 2 + 1, 2.0)
    w[0] = 1.0
    if L % 2 == 0:
        w[-1] = 1.0
    return w


def prepare(a: np.ndarray, u: np.ndarray, dt: float, L: int, boundary: str = "fixed",
            skip: int = 0, nfolds: int = N_FOLDS, A: tuple[np.ndarray, np.ndarray] | None = None,
            band_hz: float | None = None, form: str = "acceleration", fit_band: bool = False) -> Prepared:
    """Integrate the accelerations (unless ``A = (A1, A2)`` is given) and cut the record
    into windows of ``L`` samples, starting ``skip`` samples in; withheld errors are
    scored on ``[0, band_hz]`` (the whole band if None) and, with ``fit_band``, fitted
    there too; the forced equations are solved for the acceleration or the force (``form``)."""
    a = np.ascontiguousarray(a, dtype=float)
    u = np.ascontiguousarray(u, dtype=float)
    T = a.shape[0]
    nw = (T - skip) // L
    if nw < 3:
        raise ValueError(f"record too short: {T} samples make only {nw} windows of {L} samples")
    A1, A2 = integrals(a, dt) if A is None else A
    K = min(nfolds, nw)
    folds = np.arange(nw) % K
    return Prepared(a_full=a, u_full=u, A1_full=A1, A2_full=A2, skip=skip, dt=dt, L=L, nw=nw,
                    boundary=boundary, folds=folds, band_hz=band_hz, form=form, fit_band=fit_band)


def detrend(P: Prepared, x: np.ndarray) -> np.ndarray:
    """Project (N, c) columns orthogonally to {1, t - t_w} on every window -> (nw, L, c)."""
    X = P.windows(x if x.ndim == 2 else x[:, None])
    B = P.basis  # (L, 2) orthonormal {1, t - t_w}
    C = np.matmul(B.T[None], X)  # (nw, 2, c)
    return X - np.matmul(B[None], C)


def band_filter(P: Prepared, Z: np.ndarray) -> np.ndarray:
    """Orthogonal projection of every window of (nw, L, c) data onto the DFT bins of the
    signal band (``P.band_mask``); the identity when the band is the whole spectrum."""
    if P.full_band:
        return Z
    F = np.fft.rfft(Z, axis=1)
    F[:, ~P.band_mask] = 0.0
    return np.fft.irfft(F, n=P.L, axis=1)


def window_lines(P: Prepared, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares line ``alpha + beta tau`` of (N,) or (N, c) data on every window
    (tau from the window's first sample) -> alpha, beta of shape (nw,) or (nw, c)."""
    R = P.windows(r)
    tau = P.tau
    tm = tau.mean()
    s = tau - tm
    beta = np.einsum("l,wl...->w...", s, R) / np.dot(s, s)
    alpha = R.mean(axis=1) - beta * tm
    return alpha, beta


# --------------------------------------------------------------------------- equations


def spring_columns(n: int, boundary: str) -> list[list[tuple[int, int]]]:
    """For every DOF equation e (0-based): list of (spring j (1-based), other DOF or -1).

    The column of spring j in equation e is ``x_e - x_other`` (x_other = 0 for a wall).
    For n = 1 the two springs act in parallel: one column (x_1) identifies k_1 + k_2 and
    is attributed to spring 1. With a free right end spring n+1 does not exist.
    """
    out = []
    for e in range(n):
        cols = [(e + 1, e - 1 if e >= 1 else -1)]
        if n == 1:
            out.append(cols)
            continue
        if e + 1 < n:
            cols.append((e + 2, e + 1))
        elif boundary == "fixed":
            cols.append((e + 2, -1))
        out.append(cols)
    return out


def springs(n: int, boundary: str) -> list[int]:
    """Springs (1-based) that exist and can be told apart: 1..n+1 (fixed), 1..n (free),
    only 1 for n = 1."""
    if n == 1:
        return [1]
    return list(range(1, n + 1 + (boundary == "fixed")))


def param_names(n: int, boundary: str, e: int) -> list[str]:
    """Names of the linear parameters of equation ``e``: ``m, c, k<j> ...``."""
    return ["m", "c"] + [f"k{j}" for j, _ in spring_columns(n, boundary)[e]]


def force_form(P: Prepared, e: int) -> bool:
    """Is equation ``e`` solved for the force (a forced DOF of a force-form analysis)?"""
    return P.form == "force" and bool(P.forced[e])


def target(P: Prepared, e: int, a: np.ndarray | None = None, u: np.ndarray | None = None) -> np.ndarray:
    """The target of equation ``e``: the force ``u_e`` [N] in the force form, else the
    acceleration ``a_e`` [m/s^2]; ``a``, ``u`` (N,) replace the recorded column."""
    if force_form(P, e):
        return P.u[:, e] if u is None else u
    return P.a[:, e] if a is None else a


def base_design(P: Prepared, e: int, v: np.ndarray, x: np.ndarray, u: np.ndarray | None = None,
                a: np.ndarray | None = None) -> np.ndarray:
    """Columns of the linear equation of DOF ``e``.

    Acceleration form (target ``a_e``): ``[u_e, -v_e, -(x_e - x_other) ...]`` (the force
    column only for a forced DOF), parameters ``[1/m, c/m, k_j/m ...]``. Force form
    (target ``u_e``, forced DOF): ``[a_e, v_e, x_e - x_other ...]``, parameters
    ``[m, c, k_j ...]``. ``u``, ``a`` (N,) replace the recorded force or acceleration
    column."""
    if force_form(P, e):
        cols = [P.a[:, e] if a is None else a, v[:, e]]
        sign = 1.0
    else:
        cols = [P.u[:, e] if u is None else u] if P.forced[e] else []
        cols.append(-v[:, e])
        sign = -1.0
    for j, other in spring_columns(P.n, P.boundary)[e]:
        cols.append(sign * (x[:, e] - (x[:, other] if other >= 0 else 0.0)))
    return np.stack(cols, axis=1)


def effect_column(P: Prepared, e: int, g: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """Column of an effect force ``g`` [N per unit parameter] in equation ``e``
    (eq. 1 read as ``m a + c v + k x + g = u``): ``g`` in the force form, ``-g / m_e`` in
    the acceleration form (``m_e`` from the linear fit), so that its coefficient is the
    effect's physical parameter either way."""
    return g if force_form(P, e) else -g / mass[e]


def to_physical(P: Prepared, e: int, th: np.ndarray) -> np.ndarray:
    """``[m, c, k_j ...]`` from the parameters of equation ``e`` (``m = 1``, i.e. per
    unit mass, for an unforced DOF)."""
    th = np.asarray(th, dtype=float)
    if force_form(P, e):
        return th.copy()
    if not P.forced[e]:
        return np.concatenate([[1.0], th])
    m = 1.0 / th[0]
    return np.concatenate([[m], th[1:] * m])


def to_acceleration_form(P: Prepared, e: int, th: np.ndarray) -> np.ndarray:
    """The acceleration-form parameters ``[1/m, c/m, k_j/m ...]`` of equation ``e`` (the
    parameters as they are for an unforced DOF or an acceleration-form analysis)."""
    th = np.asarray(th, dtype=float)
    if not force_form(P, e):
        return th
    return np.concatenate([[1.0 / th[0]], th[1:] / th[0]])


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
    ``per_sub`` : (nw, S, E, P+1, P+1) contribution of each sub-block and equation;
    ``per_eq`` : (nw, E, P+1, P+1) its sum over sub-blocks; ``per_sub_band`` : the same
    for the band-projected columns (:func:`band_filter`; the scoring Grams; ``per_sub``
    itself when the band is the whole spectrum).
    """

    G: np.ndarray
    slices: list[slice]
    shared: slice
    eqs: list[int]
    per_sub: np.ndarray
    per_sub_band: np.ndarray

    @property
    def per_eq(self) -> np.ndarray:
        return self.per_sub.sum(axis=1)


def window_stats(P: Prepared, specs: list[EqSpec]) -> WindowStats:
    """Detrend and accumulate the per-window Grams of a stacked model."""
    q = 0 if specs[0].E is None else specs[0].E.shape[1]
    sizes = [s.X.shape[1] for s in specs]
    Ptot = sum(sizes) + q
    slices, off = [], 0
    for p in sizes:
        slices.append(slice(off, off + p))
        off += p
    shared = slice(off, off + q)
    S = N_SUB
    band = not P.full_band
    per_sub = np.zeros((P.nw, S, len(specs), Ptot + 1, Ptot + 1))
    per_sub_band = np.zeros_like(per_sub) if band else per_sub

    def sub(Z):  # (nw, L, c) -> (nw, S, L/S, c)
        return Z.reshape(P.nw, S, P.L // S, Z.shape[-1])

    def fill(blk, ix, ir, gxx, gxr, grr):
        blk[:, :, ix[:, None], ix[None, :]] = gxx
        blk[:, :, ix[:, None], ir[None, :]] = gxr
        blk[:, :, ir[:, None], ix[None, :]] = gxr.swapaxes(-1, -2)
        blk[:, :, ir[:, None], ir[None, :]] = grr

    for k, s in enumerate(specs):
        rest = np.concatenate(([s.E] if q else []) + [s.y[:, None]], axis=1) * s.w
        Zr_w = detrend(P, rest)  # (nw, L, q+1)
        Zr = sub(Zr_w)  # (nw, S, L/S, q+1)
        cached = P._cache.get((s.key, s.w)) if s.key is not None else None
        if cached is None:
            Zx_w = detrend(P, s.X * s.w)
            Zx = sub(Zx_w)
            Zxb = sub(band_filter(P, Zx_w)) if band else Zx
            cached = (Zx, np.matmul(Zx.swapaxes(-1, -2), Zx), Zxb,
                      np.matmul(Zxb.swapaxes(-1, -2), Zxb) if band else None)
            if s.key is not None:
                P._cache[(s.key, s.w)] = cached
        Zx, gxx, Zxb, gxxb = cached
        ix = np.arange(slices[k].start, slices[k].stop)
        ir = np.r_[np.arange(shared.start, shared.stop), Ptot]
        fill(per_sub[:, :, k], ix, ir, gxx, np.matmul(Zx.swapaxes(-1, -2), Zr), np.matmul(Zr.swapaxes(-1, -2), Zr))
        if band:
            Zrb = sub(band_filter(P, Zr_w))
            fill(per_sub_band[:, :, k], ix, ir, gxxb, np.matmul(Zxb.swapaxes(-1, -2), Zrb),
                 np.matmul(Zrb.swapaxes(-1, -2), Zrb))
    return WindowStats(G=(per_sub_band if P.fit_band else per_sub).sum(axis=(1, 2)), slices=slices, shared=shared,
                       eqs=[s.e for s in specs], per_sub=per_sub, per_sub_band=per_sub_band)


def solve_gram(G: np.ndarray) -> np.ndarray:
    """Least-squares parameters from Gram(s) (..., P+1, P+1) (target last), column-scaled,
    with a 1e-12 relative ridge against exactly collinear columns -> (..., P)."""
    A = G[..., :-1, :-1]
    b = G[..., :-1, -1]
    d = np.sqrt(np.clip(np.diagonal(A, axis1=-2, axis2=-1), 1e-300, None))
    As = A / d[..., :, None] / d[..., None, :]
    eye = np.eye(A.shape[-1])
    z = np.linalg.solve(As + 1e-12 * eye, (b / d)[..., None])[..., 0]
    return z / d


def sse(G: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Squared error of ``theta`` under Gram(s) ``G`` (..., P+1, P+1) -> (...)."""
    th = np.append(theta, -1.0)
    return np.einsum("...i,i->...", np.einsum("...ij,j->...i", G, th), th)


@dataclass
class CVResult:
    """Cross-validated fit of a stacked model.

    theta : (P,) fit on all windows; theta_folds : (K, P) fits with fold k withheld;
    test_sub : (nw, S, E) in-band squared error (the metric's, see the module docstring)
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
    test = np.zeros(st.per_sub.shape[:3])
    full = np.zeros_like(test)
    for k in range(K):
        mask = P.folds == k
        th = solve_gram(Gsum - st.G[mask].sum(axis=0))
        thetas[k] = th
        full[mask] = sse(st.per_sub[mask], th)
        test[mask] = full[mask] if st.per_sub_band is st.per_sub else sse(st.per_sub_band[mask], th)
    return CVResult(theta=theta, theta_folds=thetas, test_sub=test, fit_sse=sse(st.G, theta), stats=st,
                    test_sub_full=full)


def cross_validate_grid(P: Prepared, stats: list[WindowStats], grid: np.ndarray) -> CVResult:
    """Cross-validation of a model with one nonlinear parameter known on ``grid``.

    For every fold the grid value is chosen by the (full-band) error on the training
    windows, as the fit itself (refined
    by a parabola through the three best neighbours, reported in ``extra["g_folds"]``),
    and the withheld windows are scored at the chosen grid point. The all-window fit is
    reported at the best grid point (``extra["g"]`` refined, ``extra["g_index"]``).
    """
    K = P.nfolds
    G = np.stack([s.G for s in stats])  # (ng, nw, P+1, P+1)
    Gsum = G.sum(axis=1)
    ng = len(grid)
    thetas_all = solve_gram(Gsum)
    fit_all = np.array([sse(Gsum[g], thetas_all[g]) for g in range(ng)])
    best = int(np.argmin(fit_all))
    res = cross_validate(P, stats[best])
    test = np.zeros(stats[best].per_sub.shape[:3])
    full = np.zeros_like(test)
    thetas = np.zeros((K, thetas_all.shape[1]))
    g_folds = np.zeros(K)
    gb_folds = np.zeros(K, dtype=int)
    for k in range(K):
        mask = P.folds == k
        Gtr = Gsum - G[:, mask].sum(axis=1)
        ths = solve_gram(Gtr)
        tr = np.array([sse(Gtr[g], ths[g]) for g in range(ng)])
        gb = int(np.argmin(tr))
        gb_folds[k] = gb
        thetas[k] = ths[gb]
        g_folds[k] = refine_min(grid, tr, gb)
        test[mask] = sse(stats[gb].per_sub_band[mask], ths[gb])
        full[mask] = sse(stats[gb].per_sub[mask], ths[gb])
    res.theta_folds = thetas
    res.test_sub = test
    res.test_sub_full = full
    res.extra = {"g": refine_min(grid, fit_all, best), "g_index": best, "g_folds": g_folds,
                 "g_index_folds": gb_folds, "grid_sse": fit_all}
    return res


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
