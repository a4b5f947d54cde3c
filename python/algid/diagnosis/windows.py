"""The record cut into windows (:class:`Prepared`): window length, per-window detrending
against ``{1, t - t_w}``, the projection onto the signal band's DFT bins, and per-window lines."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..model.network import topology
from .equations import target
from .integrals import integrals

__all__ = [
    "FORMS",
    "N_FOLDS",
    "N_SUB",
    "Prepared",
    "band_filter",
    "detrend",
    "parseval_weights",
    "prepare",
    "window_length",
    "window_lines",
]

#: Which signal the forced DOFs' equations are solved for (:func:`target`).
FORMS = ("acceleration", "force")
#: Number of interleaved cross-validation folds (fewer if there are fewer windows).
N_FOLDS = 8
#: Sub-blocks per window on which withheld errors are also reported (the unit of the
#: paired significance test; the fits and the detrending stay per window).
N_SUB = 4


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
    boundary : "fixed" or "free" (the chain), or a :class:`~algid.model.network.Network`.
    network : the topology (:func:`~algid.model.network.topology`); ``chain`` whether it is
        the chain of eq. 1, whose packed vector holds ``n_springs = n + 1`` springs (a free
        end's 0), a network's its ``S`` springs in order.
    columns : per equation e (0-based), ``(spring s (1-based), other DOF (0-based, -1 ground))``
        of its spring columns ``x_e - x_other`` (:meth:`~algid.model.network.Network.columns`).
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
    boundary: object  # "fixed", "free" or a Network
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
        self.network = topology(self.n, self.boundary)
        self.chain = isinstance(self.boundary, str)
        self.n_springs = self.n + 1 if self.chain else self.network.size
        self.columns = [[(s, o - 1) for s, o in self.network.columns(e + 1)] for e in range(self.n)]
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

    def sides(self, s: int) -> list[tuple[int, float]]:
        """``(equation (0-based), sign)`` where spring ``s`` (1-based) pushes (ground left out)."""
        return [(i - 1, sign) for i, sign in self.network.sides(s)]

    def deformation(self, x: np.ndarray, s: int) -> np.ndarray:
        """Deformation (N,) [m] of spring ``s`` (1-based) from positions ``x`` (N, n)."""
        return self.network.deformation(x, s)

    def windows(self, x: np.ndarray) -> np.ndarray:
        """Reshape a (N, ...) array to (nw, L, ...)."""
        return x.reshape(self.nw, self.L, *x.shape[1:])


def parseval_weights(L: int) -> np.ndarray:
    """Weights of the one-sided DFT bins of a real window of L samples in Parseval's sum
    (``sum x^2 = sum_k w_k |X_k|^2 / L``): 1 for DC (and Nyquist for even L), 2 else."""
    w = np.full(L // 2 + 1, 2.0)
    w[0] = 1.0
    if L % 2 == 0:
        w[-1] = 1.0
    return w


def prepare(
    a: np.ndarray,
    u: np.ndarray,
    dt: float,
    L: int,
    boundary="fixed",
    skip: int = 0,
    nfolds: int = N_FOLDS,
    A: tuple[np.ndarray, np.ndarray] | None = None,
    band_hz: float | None = None,
    form: str = "acceleration",
    fit_band: bool = False,
) -> Prepared:
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
    return Prepared(
        a_full=a,
        u_full=u,
        A1_full=A1,
        A2_full=A2,
        skip=skip,
        dt=dt,
        L=L,
        nw=nw,
        boundary=boundary,
        folds=folds,
        band_hz=band_hz,
        form=form,
        fit_band=fit_band,
    )


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
