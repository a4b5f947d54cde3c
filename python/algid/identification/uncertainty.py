"""How far each estimate may be off: a standard deviation per parameter, the bias taken off,
the method's own error, and how much more the record's window results scatter than its noise
explains.

* **Weak-form windows** (measured accelerations) carry their own uncertainty: the
  generalised least squares covariance of every window and of their summed normal equations
  (:mod:`algid.estimator.continuous`; their per-window sigmas match the scatter of window results on
  records whose noise is known). Their bias compensation takes off the noise bias of the
  iterated integrals, so no bootstrap runs. ``excess`` is the scatter of the window results
  about the estimate in units of each window's own sigma (:class:`.runner.Run`): about 1 when
  eq. 1 and the recording's white noise explain them. The quadrature's own error grows with the
  content close to the sampling rate: when the signal band reaches past :data:`METHOD_BAND` of
  the sampling rate, one noise-free surrogate of the identified chain measures it
  (``method_bias``, :func:`.surrogate.bootstrap` without noise); below, it is zero.
* **Algebraic windows** (accelerations derived from velocities or encoder counts, whose noise
  the differentiation colours) have no such covariance: a parametric bootstrap on surrogates
  of the recording gives the spread, the noise bias and the method's error
  (:func:`.surrogate.bootstrap`); ``excess`` compares the window results' scatter with the
  surrogates'.

Either way the estimate's uncertainty then counts the method's error (not taken off: it may
be the surrogate's) and is scaled up by ``excess`` where that exceeds 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..recording import DEFAULT_DIFF_POINTS
from ..recording.noise import NoiseModel
from .estimate import Estimate
from .motion import Motion, band_limited_motion
from .screen import Signals
from .surrogate import bootstrap, surrogate_band

#: A bootstrap bias is taken off the estimate when it exceeds this many of its standard
#: errors (3: a correction by chance on 0.3 % of the parameters).
BIAS_Z = 3.0
#: Signal band, as a share of the sampling rate, above which the weak form's quadrature error
#: is measured on a noise-free surrogate.
METHOD_BAND = 0.1


@dataclass
class Uncertainty:
    """theta (3n+1,) the estimate with any bias taken off, ``sigma`` its standard deviation,
    ``bias`` the correction taken off, ``method_bias`` the method's own error counted in
    ``sigma``, ``excess`` the window-result scatter over what noise explains (1 where not
    measured), ``history_sigma`` (R, 3n+1), ``motion`` the in-band motion of the record and
    ``replicates`` the bootstrap's (0 without one)."""

    theta: np.ndarray
    sigma: np.ndarray
    bias: np.ndarray
    method_bias: np.ndarray
    excess: np.ndarray
    history_sigma: np.ndarray
    motion: Motion
    replicates: int


def _combine(theta, sigma, bias, bias_stderr, method_bias, excess):
    """The estimate with a significant bias taken off, and its uncertainty (module docstring)."""
    correct = np.isfinite(bias) & (np.abs(bias) > BIAS_Z * bias_stderr)
    theta = np.where(correct, theta - np.nan_to_num(bias), theta)
    sigma = np.where(correct, np.sqrt(sigma**2 + bias_stderr**2), sigma)
    method_bias = np.where(np.isfinite(method_bias), method_bias, 0.0)
    sigma = np.sqrt(sigma**2 + method_bias**2) * np.maximum(excess, 1.0)
    return theta, sigma, np.where(correct, bias, 0.0), method_bias


def estimate_uncertainty(
    est: Estimate,
    sig: Signals,
    nm: NoiseModel,
    boundary: str,
    replicates: int,
    seed: int,
    progress: Callable[[float], None] | None = None,
) -> Uncertainty:
    """Identify's uncertainty stage: the uncertainty of the estimate ``est`` of the record
    ``sig`` (module docstring), with ``replicates`` bootstrap replicates of ``seed``."""
    run, plan, motion_rec, forced, missing = est.run, est.plan, sig.motion, sig.forced, sig.missing
    replicates = int(replicates)
    n = motion_rec.shape[1]
    f_cut = surrogate_band(nm, run.theta, n, boundary)
    weak = plan.method == "weak_form"
    if weak and nm.f_hi <= METHOD_BAND / nm.dt:
        mo = band_limited_motion(motion_rec, nm.motion, nm.dt, f_cut)
        zero = np.zeros_like(run.theta)
        excess = np.where(np.isfinite(run.scatter), run.scatter, 1.0)
        theta, sigma, bias, method_bias = _combine(run.theta, run.sigma, zero, zero, zero, excess)
        return Uncertainty(theta, sigma, bias, method_bias, excess, run.history_sigma, mo, 0)
    boot = bootstrap(
        run.theta,
        motion_rec,
        nm,
        plan,
        boundary,
        f_cut,
        forced,
        0 if weak else replicates,
        seed,
        DEFAULT_DIFF_POINTS,
        progress=progress,
        history=not weak,
        missing=missing,
    )
    if weak:
        excess = np.where(np.isfinite(run.scatter), run.scatter, 1.0)
        zero = np.zeros_like(run.theta)
        theta, sigma, bias, method_bias = _combine(run.theta, run.sigma, zero, zero, boot.method_bias, excess)
        return Uncertainty(theta, sigma, bias, method_bias, excess, run.history_sigma, boot.motion, 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        excess = np.where(np.isfinite(run.spread / boot.spread), run.spread / boot.spread, 1.0)
    theta, sigma, bias, method_bias = _combine(
        run.theta, boot.sigma, boot.bias, boot.sigma / np.sqrt(replicates), boot.method_bias, excess
    )
    return Uncertainty(theta, sigma, bias, method_bias, excess, boot.history_sigma, boot.motion, replicates)
