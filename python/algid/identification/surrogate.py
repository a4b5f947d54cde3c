"""Uncertainty by parametric bootstrap on surrogates of the recording.

A surrogate is a recording of the *identified* chain with the recording's own motion and
sensor noise, so that the estimator's error on it is known:

1. **Motion.** The recorded motion, band-limited to ``[0, f_cut]`` in the frequency domain,
   and its exact derivatives or integrals there: ``x_s``, ``v_s = x_s'``, ``a_s = x_s''``,
   consistent with each other to rounding. From displacements: the line through the first
   and last sample is taken out before the FFT (so that the periodic extension has no
   jump) and added back (it has no acceleration); from velocities likewise, the line and
   the rest's mean integrated exactly. From accelerations: the displacement is
   the double integral ``-A / w^2`` on the bins above ``2 / duration`` (below, the
   integral of noise would wander off).
2. **Forces** of the identified chain along that motion, eq. 1 read from left to right:
   ``u_s = M a_s + C v_s + K x_s``. The motion is prescribed, so no simulation runs and an
   unstable or inadmissible estimate gives a surrogate all the same.
3. **Sensors**, drawn afresh for every replicate from the recording's noise model
   (:mod:`algid.noise`): white noise of each channel's floor on forces and measured
   accelerations; white noise on velocities, then differentiated like the recording's;
   displacements quantised to the recording's encoder resolution (with a random offset of
   the count grid) plus whatever white floor lies above the quantisation noise, then
   differentiated like the recording's.

The same plan is run on ``B`` replicates and once on the noise-free surrogate. The
replicates' spread is the estimate's standard deviation; their mean minus the noise-free
surrogate's estimate is the bias the noise causes (measured against the noise-free run,
not against the chain itself, so that what the band-limited surrogate costs the
estimator's quadrature, at the record's ends for instance, is not mistaken for it). The
noise-free surrogate's estimate minus the chain it was made from is the method's own error
on signals of the record's spectrum (``method_bias``: the quadrature of content close to
the sampling rate, for instance; +0.2 % on the masses and springs of Table 1 under a force
band-limited to fs/5, 0.000 % at fs/20); it is not taken off (it may be the surrogate's)
but counted in the uncertainty. The noise the surrogates
cannot reproduce (coloured or correlated with the input through a controller) and the
model error (effects outside eq. 1) are not in it; :func:`algid.diagnose` looks for those.
"""

from __future__ import annotations

import os
import warnings
from concurrent.futures import ThreadPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..chain import stiffness_matrix
from ..noise import NoiseModel
from ..recording import derivative, second_derivative
from .plan import Plan
from .runner import run_plan

#: Replicates of the bootstrap.
REPLICATES = 8


#: Threads of :func:`parallel_map`; None: one per core (see :func:`threads`).
_threads: int | None = None


@contextmanager
def threads(count: int | None):
    """Run :func:`parallel_map` on at most ``count`` threads inside the block (None: one per
    core). ``algid.fleet`` runs each recording on one, as its workers take a core each."""
    global _threads
    saved, _threads = _threads, count
    try:
        yield
    finally:
        _threads = saved


def parallel_map(fn: Callable, items: list, progress: Callable[[int], None] | None = None) -> list:
    """``[fn(x) for x in items]`` on a thread per core (the estimators release the GIL while
    they run; at most :func:`threads` ones), results in order; ``progress(done)`` after each."""
    workers = min(len(items), _threads or os.cpu_count() or 1)
    if workers <= 1:
        out = []
        for x in items:
            out.append(fn(x))
            if progress is not None:
                progress(len(out))
        return out
    with ThreadPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(fn, x) for x in items]
        for done, _ in enumerate(as_completed(futures), start=1):
            if progress is not None:
                progress(done)
        return [f.result() for f in futures]


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
    """Consistent ``x, v, a`` from the recorded motion ``y`` (T, n) (module docstring, 1)."""
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


def chain_forces(theta: np.ndarray, n: int, boundary: str, mo: Motion) -> np.ndarray:
    """``M a + C v + K x`` (T, n) [N] of packed parameters (NaN counts as 0)."""
    th = np.nan_to_num(np.asarray(theta, dtype=float))
    m, c, k = th[:n], th[n : 2 * n], th[2 * n :].copy()
    if n == 1 and boundary == "fixed":
        k = np.array([k[0], 0.0])
    if boundary == "free":
        k[-1] = 0.0
    K = stiffness_matrix(k)
    return mo.a * m + mo.v * c + mo.x @ K.T


def replicate_signals(
    mo: Motion, u_s: np.ndarray, nm: NoiseModel, rng: np.random.Generator, diff_points: int
) -> tuple[np.ndarray, np.ndarray]:
    """One noisy replicate ``(a, u)`` of the surrogate (module docstring, 3)."""
    T, n = u_s.shape
    su = np.array([c.sigma for c in nm.forces])
    u = u_s + su * rng.standard_normal((T, n))
    if nm.motion == "acceleration":
        sa = np.array([c.sigma for c in nm.motions])
        return mo.a + sa * rng.standard_normal((T, n)), u
    if nm.motion == "velocity":
        sv = np.array([c.sigma for c in nm.motions])
        return derivative(mo.v + sv * rng.standard_normal((T, n)), nm.dt, 1, diff_points), u
    x = mo.x.copy()
    for i, ch in enumerate(nm.motions):
        q = ch.quantum
        white = np.sqrt(max(ch.sigma**2 - q * q / 12.0, 0.0))
        x[:, i] += white * rng.standard_normal(T)
        if q > 0:
            off = rng.uniform(0.0, q)
            x[:, i] = q * np.round((x[:, i] + off) / q) - off
    return second_derivative(x, nm.dt, diff_points), u


@dataclass
class Bootstrap:
    """Spread and bias of a plan's estimates on surrogates of the recording.

    sigma, bias : (3n+1,) standard deviation and noise-induced mean error [parameter units];
    method_bias : (3n+1,) the noise-free surrogate's estimate minus the chain it was made from;
    spread : (3n+1,) median over the replicates of their window results' scatter;
    history_sigma : (R, 3n+1) standard deviation of the history rows; replicates : (B, 3n+1);
    motion : the surrogate motion (also the in-band regressors of the verdicts).
    """

    sigma: np.ndarray
    bias: np.ndarray
    method_bias: np.ndarray
    spread: np.ndarray
    history_sigma: np.ndarray
    replicates: np.ndarray
    motion: Motion


def bootstrap(
    theta: np.ndarray,
    motion_rec: np.ndarray,
    nm: NoiseModel,
    plan: Plan,
    boundary: str,
    f_cut: float,
    forced: np.ndarray,
    replicates: int = REPLICATES,
    seed: int = 0,
    diff_points: int = 5,
    progress: Callable[[float], None] | None = None,
    history: bool = True,
    missing: np.ndarray | None = None,
) -> Bootstrap:
    """Run ``plan`` on ``replicates`` surrogates of the chain ``theta`` (module docstring).

    ``motion_rec``: the recorded motion (T, n) of kind ``nm.motion``; ``f_cut``: band edge of
    the surrogate motion [Hz]; ``forced``: (n,) DOF that carry a force (the others keep a
    zero force, as recorded); ``history``: also the spread of the estimate histories;
    ``missing``: (T,) instants every run sees as not a number, as the recording's did.
    """
    n = motion_rec.shape[1]
    mo = band_limited_motion(motion_rec, nm.motion, nm.dt, f_cut)
    u_s = chain_forces(theta, n, boundary, mo) * forced
    a0 = {
        "acceleration": lambda: mo.a,
        "velocity": lambda: derivative(mo.v, nm.dt, 1, diff_points),
        "displacement": lambda: second_derivative(mo.x, nm.dt, diff_points),
    }[nm.motion]()
    seeds = np.random.SeedSequence(seed).spawn(replicates)  # one stream per replicate: any order

    def one(b: int):
        if b < 0:
            return run_plan(a0, u_s, nm.dt, boundary, plan, history=False, missing=missing)
        a_b, u_b = replicate_signals(mo, u_s, nm, np.random.default_rng(seeds[b]), diff_points)
        return run_plan(a_b, u_b, nm.dt, boundary, plan, history, missing)

    runs = parallel_map(
        one, list(range(-1, replicates)), None if progress is None else (lambda k: progress(k / (replicates + 1)))
    )
    theta0 = runs[0].theta
    thetas, hists = [r.theta for r in runs[1:]], [r.history for r in runs[1:]]
    R = np.array(thetas)
    rows = min(h.shape[0] for h in hists)
    H = np.array([h[-rows:] for h in hists])
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns: parameters not estimated
        sigma = np.nanstd(R, axis=0, ddof=1) if replicates > 1 else np.full(R.shape[1], np.nan)
        bias = np.nanmean(R, axis=0) - theta0
        spread = np.nanmedian(np.array([r.spread for r in runs[1:]]), axis=0)
        hsig = np.nanstd(H, axis=0, ddof=1) if replicates > 1 else np.full(H.shape[1:], np.nan)
    return Bootstrap(
        sigma=sigma, bias=bias, method_bias=theta0 - theta, spread=spread, history_sigma=hsig, replicates=R, motion=mo
    )
