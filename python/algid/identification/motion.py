"""The recorded motion in the signal band, and a first chain fitted to it.

* :func:`band_limited_motion`: the recorded motion, band-limited to ``[0, f_cut]`` in the
  frequency domain, and its exact derivatives or integrals there: ``x``, ``v = x'``,
  ``a = x''``, consistent with each other to rounding. From displacements: the line through
  the first and last sample is taken out before the FFT (so that the periodic extension has
  no jump) and added back (it has no acceleration); from velocities likewise, the line and
  the rest's mean integrated exactly. From accelerations: the displacement is the double
  integral ``-A / w^2`` on the bins above ``2 / duration`` (below, the integral of noise
  would wander off). The verdicts measure every parameter against its regressor in this
  motion, and the surrogates of :mod:`.surrogate` move along it.
* :func:`chain_forces`: eq. 1 read from left to right, ``M a + C v + K x``;
  :func:`unforced_consistent`: the motion of the DOFs without force made to hold eq. 1
  with zero force.
* :func:`equation_error_fit`: eq. 1 fitted by least squares on the DFT bins of the signal
  band, every DOF's equation at once (its springs shared with its neighbours). Noise in the
  motion biases it (errors in variables) and leakage blurs the lowest bins, so it is only the
  planner's first look at the chain's time scales (:mod:`.plan`), never a reported estimate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.chain import spring_columns, stiffness_matrix
from ..recording.noise import DETECT, NoiseModel

#: Derivative order of each kind of recorded motion.
ORDER = {"displacement": 0, "velocity": 1, "acceleration": 2}

#: Passes of :func:`equation_error_fit`: unweighted, then weighted by the previous pass's noise.
FIT_PASSES = 3


@dataclass
class Motion:
    """Band-limited motion (T, n) each: displacement [m], velocity [m/s], acceleration [m/s^2]."""

    x: np.ndarray
    v: np.ndarray
    a: np.ndarray


def _lowpass_gain(f: np.ndarray, f_cut: float) -> np.ndarray:
    """1 up to ``f_cut``, a raised-cosine roll-off to 0 at ``1.25 f_cut`` (no ringing)."""
    g = np.ones_like(f)
    if f_cut >= f[-1]:
        return g
    s = np.clip((f - f_cut) / (0.25 * f_cut), 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * s))


def band_limited_motion(y: np.ndarray, kind: str, dt: float, f_cut: float) -> Motion:
    """Consistent ``x, v, a`` from the recorded motion ``y`` (T, n) (module docstring)."""
    y = np.asarray(y, dtype=float)
    T = y.shape[0]
    t = np.arange(T) * dt
    f = np.fft.rfftfreq(T, dt)
    w = 2 * np.pi * f
    g = _lowpass_gain(f, f_cut)[:, None]
    if kind == "displacement":
        slope = (y[-1] - y[0]) / (t[-1] - t[0])
        line = y[0] + t[:, None] * slope
        Y = np.fft.rfft(y - line, axis=0) * g
        x = line + np.fft.irfft(Y, T, axis=0)
        v = slope + np.fft.irfft(1j * w[:, None] * Y, T, axis=0)
        a = np.fft.irfft(-(w**2)[:, None] * Y, T, axis=0)
        return Motion(x, v, a)
    if kind == "velocity":  # the line through the ends and the periodic rest's mean, integrated exactly
        slope = (y[-1] - y[0]) / (t[-1] - t[0])
        Y = np.fft.rfft(y - y[0] - t[:, None] * slope, axis=0) * g
        v0 = y[0] + Y[0].real / T
        Y[0] = 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            X = np.where(w[:, None] > 0, Y / (1j * w)[:, None], 0.0)
        v = v0 + t[:, None] * slope + np.fft.irfft(Y, T, axis=0)
        x = t[:, None] * v0 + 0.5 * t[:, None] ** 2 * slope + np.fft.irfft(X, T, axis=0)
        a = slope + np.fft.irfft(1j * w[:, None] * Y, T, axis=0)
        return Motion(x, v, a)
    A = np.fft.rfft(y - y.mean(axis=0), axis=0) * g
    keep = (f >= 2.0 / (T * dt))[:, None]
    A = np.where(keep, A, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        X = np.where(keep, -A / (w**2)[:, None], 0.0)
        V = np.where(keep, A / (1j * w)[:, None], 0.0)
    return Motion(np.fft.irfft(X, T, axis=0), np.fft.irfft(V, T, axis=0), np.fft.irfft(A, T, axis=0))


def packed_springs(theta: np.ndarray, n: int, boundary: str) -> np.ndarray:
    """The springs ``k_1 .. k_{n+1}`` of packed parameters as eq. 1 uses them (NaN counts as
    0; one DOF between walls: ``k_1`` holds both; free end: ``k_{n+1} = 0``)."""
    k = np.nan_to_num(np.asarray(theta, dtype=float)[2 * n :]).copy()
    if n == 1 and boundary == "fixed":
        k = np.array([k[0], 0.0])
    if boundary == "free":
        k[-1] = 0.0
    return k


def chain_forces(theta: np.ndarray, n: int, boundary: str, mo: Motion) -> np.ndarray:
    """``M a + C v + K x`` (T, n) [N] of packed parameters (NaN counts as 0)."""
    th = np.nan_to_num(np.asarray(theta, dtype=float))
    K = stiffness_matrix(packed_springs(th, n, boundary))
    return mo.a * th[:n] + mo.v * th[n : 2 * n] + mo.x @ K.T


def unforced_consistent(mo: Motion, theta: np.ndarray, n: int, boundary: str, forced: np.ndarray, dt: float) -> Motion:
    """``mo`` with the motion of the DOFs without force replaced by the one eq. 1 gives them
    with zero force, driven by the forced DOFs' motion through the springs (a surrogate of a
    one-shaker record must hold ``M a + C v + K x = 0`` on those DOFs, or their ratio
    systems see a force that is not there). The residual force ``r`` of the unforced DOFs
    is cancelled by a correction ``d`` of their motion, ``M_uu d'' + C_uu d' + K_uu d = -r``:
    the line through ``r``'s ends by a polynomial ``d``, the rest bin by bin in the frequency
    domain. Unchanged when some parameter of those DOFs is not finite."""
    th = np.asarray(theta, dtype=float)
    u = ~np.asarray(forced, dtype=bool)
    K = stiffness_matrix(packed_springs(th, n, boundary))
    m, c = th[:n], th[n : 2 * n]
    if not u.any() or not (np.all(np.isfinite(m[u])) and np.all(np.isfinite(c[u]))):
        return mo
    Mu, Cu, Ku = np.diag(m[u]), np.diag(c[u]), K[np.ix_(u, u)]
    r = chain_forces(th, n, boundary, mo)[:, u]
    T = r.shape[0]
    t = np.arange(T) * dt
    r1 = (r[-1] - r[0]) / (t[-1] - t[0])
    p1 = -np.linalg.solve(Ku, r1)  # d = p0 + p1 t cancels r0 + r1 t
    p0 = np.linalg.solve(Ku, -r[0] - Cu @ p1)
    w = 2 * np.pi * np.fft.rfftfreq(T, dt)
    R = np.fft.rfft(r - r[0] - t[:, None] * r1, axis=0)
    Z = -(w**2)[:, None, None] * Mu + 1j * w[:, None, None] * Cu + Ku
    D = -np.linalg.solve(Z, R[:, :, None])[:, :, 0]
    x, v, a = mo.x.copy(), mo.v.copy(), mo.a.copy()
    x[:, u] += p0 + t[:, None] * p1 + np.fft.irfft(D, T, axis=0)
    v[:, u] += p1 + np.fft.irfft(1j * w[:, None] * D, T, axis=0)
    a[:, u] += np.fft.irfft(-(w**2)[:, None] * D, T, axis=0)
    return Motion(x, v, a)


def _stands_out(Z: np.ndarray, channels, dt: float, T: int) -> np.ndarray:
    """Bins where the summed one-sided PSD of the DFTs ``Z`` (bins, n) stands :data:`DETECT`
    times above the channels' summed noise floor."""
    floor = sum(c.floor_psd for c in channels)
    return np.sum(np.abs(Z) ** 2, axis=1) * 2 * dt / T > DETECT * floor


def _residual_sd(theta: np.ndarray, jw: np.ndarray, nm: NoiseModel, boundary: str) -> np.ndarray:
    """Standard deviation (n, bins) of each equation's residual on the DFT bins ``jw`` that the
    sensor noise causes, for packed parameters ``theta``: the force's floor plus the motion's
    floors through the dynamic stiffness ``((jw)^2 M + jw C + K) / (jw)^r`` of its row."""
    n, r = len(nm.forces), ORDER[nm.motion]
    th = np.nan_to_num(theta)
    K = stiffness_matrix(packed_springs(th, n, boundary))
    Z = (jw**2)[:, None, None] * np.diag(th[:n]) + jw[:, None, None] * np.diag(th[n : 2 * n]) + K
    Z /= (jw**r)[:, None, None]
    var = np.abs(Z) ** 2 @ np.array([c.floor_psd for c in nm.motions])
    return np.sqrt(var.T + np.array([c.floor_psd for c in nm.forces])[:, None])


def equation_error_fit(u: np.ndarray, y: np.ndarray, nm: NoiseModel, boundary: str) -> np.ndarray:
    """Packed ``m, c, k`` of eq. 1 fitted to forces ``u`` (T, n) [N] and the recorded motion
    ``y`` (T, n) of the kind ``nm.motion`` (module docstring); NaN where the record does not
    determine them (no force at all, too few bins).

    The bins are those of ``[2 / duration, f_hi]`` where the forces stand :data:`DETECT` times
    above their noise floor (all of the band when fewer than the unknowns do: a force that is
    its own floor). On DFT bins a derivative is ``j w`` times the signal plus the jump of the
    signal's periodic extension, a constant over the bins: integrating the recorded motion to
    the others (or differentiating it) leaves two such constants per DOF, which eq. 1 carries
    as two unknown terms per equation, ``(j w)^(1 - r)`` and ``(j w)^(-r)`` for a motion of
    derivative order ``r`` (the initial conditions, fitted alongside and dropped). Each
    equation on each bin is weighted by the inverse of the residual that the sensor noise
    causes there (:func:`_residual_sd`, from the previous pass's parameters, :data:`FIT_PASSES`
    passes): integrating measured accelerations amplifies their noise like ``1 / w^2``, and
    unweighted, the many bins below the first mode that a broadband force excites would bias
    the springs towards zero."""
    T, n = u.shape
    dt = nm.dt
    f = np.fft.rfftfreq(T, dt)
    U = np.fft.rfft(u, axis=0)
    P, Q = 3 * n + 1, 5 * n + 1  # parameters, and with two initial-condition terms per DOF
    band = (f >= 2.0 / (T * dt)) & (f <= nm.f_hi)
    excited = band & _stands_out(U, nm.forces, dt, T)
    bins = excited if 2 * n * excited.sum() >= 2 * Q else band
    if not np.any(u != 0.0) or 2 * n * bins.sum() < 2 * Q:
        return np.full(P, np.nan)
    jw = 2j * np.pi * f[bins]
    r = ORDER[nm.motion]
    X = np.fft.rfft(y, axis=0)[bins] / (jw**r)[:, None]
    D = np.zeros((n, jw.size, Q), dtype=complex)
    for e, cols in enumerate(spring_columns(n, boundary)):
        D[e, :, e] = jw**2 * X[:, e]
        D[e, :, n + e] = jw * X[:, e]
        for j, other in cols:
            D[e, :, 2 * n + j - 1] = X[:, e] - (X[:, other] if other >= 0 else 0.0)
        D[e, :, P + 2 * e] = jw ** (1 - r)
        D[e, :, P + 2 * e + 1] = jw ** (-r)
    b = U[bins].T
    theta = np.full(Q, np.nan)
    weight = np.ones(b.shape)
    for _ in range(FIT_PASSES):
        step = _weighted_lstsq(D * weight[..., None], b * weight)
        if not np.any(np.isfinite(step[:P])):  # NaN marks the columns that are zero (a free end's spring)
            break
        theta = step
        weight = 1.0 / _residual_sd(theta[:P], jw, nm, boundary)
    return theta[:P]


def _weighted_lstsq(D: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Real least squares of the complex equations ``D theta = b`` (n, bins, Q) and (n, bins),
    columns scaled to unit norm; NaN for columns that are zero."""
    Q = D.shape[-1]
    D, b = D.reshape(-1, Q), b.reshape(-1)
    D, b = np.concatenate([D.real, D.imag]), np.concatenate([b.real, b.imag])
    scale = np.linalg.norm(D, axis=0)
    used = scale > 0
    theta = np.full(Q, np.nan)
    theta[used] = np.linalg.lstsq(D[:, used] / scale[used], b, rcond=None)[0] / scale[used]
    return theta
