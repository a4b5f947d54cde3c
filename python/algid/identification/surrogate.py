"""Uncertainty by parametric bootstrap on surrogates of the recording.

A surrogate is a recording of the *identified* chain with the recording's own motion and
sensor noise, so that the estimator's error on it is known:

1. **Motion.** The recorded motion, band-limited to ``[0, f_cut]``, and its exact derivatives
   or integrals there (:func:`.motion.band_limited_motion`).
2. **Forces** of the identified chain along that motion, eq. 1 read from left to right:
   ``u_s = M a_s + C v_s + K x_s``. The motion is prescribed, so no simulation runs and an
   unstable or inadmissible estimate gives a surrogate all the same. A DOF without force
   keeps none: its motion is the one the chain gives it with zero force, driven by its
   neighbours through the springs (:func:`.motion.unforced_consistent`).
3. **Sensors**, drawn afresh for every replicate from the recording's noise model
   (:mod:`algid.recording.noise`): white noise of each channel's floor on forces and measured
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
the sampling rate, for instance: it grows as the force's band nears the sampling rate); it
is not taken off (it may be the surrogate's)
but counted in the uncertainty. The noise the surrogates
cannot reproduce (coloured or correlated with the input through a controller) and the
model error (effects outside eq. 1) are not in it; :func:`algid.diagnose` looks for those.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..parallel import parallel_map
from ..recording import derivative, second_derivative
from ..recording.noise import NoiseModel
from .motion import Motion, band_limited_motion, chain_forces, unforced_consistent
from .plan import Plan, natural_frequencies_hz
from .runner import run_plan

#: Replicates of the bootstrap.
REPLICATES = 8


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
    """Run ``plan`` on ``replicates`` surrogates of the chain ``theta`` (module docstring);
    with none, on the noise-free surrogate alone (``method_bias``; the rest NaN).

    ``motion_rec``: the recorded motion (T, n) of kind ``nm.motion``; ``f_cut``: band edge of
    the surrogate motion [Hz]; ``forced``: (n,) DOF that carry a force (the others keep a
    zero force, as recorded); ``history``: also the spread of the estimate histories;
    ``missing``: (T,) instants every run sees as not a number, as the recording's did.
    """
    n = motion_rec.shape[1]
    mo = unforced_consistent(
        band_limited_motion(motion_rec, nm.motion, nm.dt, f_cut), theta, n, boundary, forced, nm.dt
    )
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
    if replicates == 0:  # the noise-free surrogate alone: the method's own error
        nan = np.full(theta0.shape, np.nan)
        return Bootstrap(nan, nan, theta0 - theta, nan, nan[None, :], np.zeros((0, theta0.size)), mo)
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


def surrogate_band(nm: NoiseModel, theta: np.ndarray, n: int, boundary: str) -> float:
    """Band edge [Hz] of the surrogate motion: the signal band, widened to hold every natural
    frequency of the estimate with a margin."""
    return max([nm.f_hi] + [1.25 * float(f) for f in natural_frequencies_hz(theta, n, boundary)])
