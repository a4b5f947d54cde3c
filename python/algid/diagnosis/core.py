"""Windowed equation-error machinery shared by the location, candidate and report steps.

The equation of DOF i (eq. 1 plus an optional unmodelled effect g), solved for the
acceleration,

    a_i = (u_i - c_i v_i - k_i (x_i - x_{i-1}) - k_{i+1} (x_i - x_{i+1}) - g_i) / m_i,

is linear in ``[1/m_i, c_i/m_i, k_i/m_i, k_{i+1}/m_i]`` with the (noisy) measured
acceleration alone on the left: sensor noise stays out of the regressors, and the error
is in acceleration units. A DOF without force (``u_i = 0`` throughout, e.g. a response
point of a structure excited elsewhere) has no scale: its parameters are reported per
unit mass (``m_i = 1``). The equation needs velocities and displacements, which are not
measured. Integrating the measured
accelerations from the start of the record gives ``A1 = int a`` and ``A2 = int int a``
(the same exact-for-polynomials interpolatory quadrature as the estimator, 6 points);
the true signals are ``v = A1 + p`` and ``x = A2 + q + p (t - t_w)`` on every window
``w``, with unknown constants ``p``, ``q`` (initial conditions plus the random walk that
integrated sensor noise adds). Substituted into eq. 1 they contribute, per equation and
per window, a first-degree polynomial in time ``alpha + beta (t - t_w)``. The algebraic
identification kills initial conditions by integration by parts; here they are killed by
projecting every regressor and the target, window by window, orthogonally to
``{1, t - t_w}`` ("detrending"), which removes exactly those terms and keeps every other
parameter linear. The windows are short enough (see :func:`.windows.window_length`) that the
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
restricted to the signal band ``[0, f_hi]`` of the recording (:func:`.band.signal_band`): on
every window the detrended error is projected onto the DFT bins of the window at or
below ``f_hi`` (:func:`.windows.band_filter`; an orthogonal projection, so the in-band squared
error of a window is a quadratic form of the same kind as the full-band one and the
whole fold machinery carries over). The fits themselves stay full-band least squares;
only the scoring of withheld windows is restricted. Outside the band the recording
carries no signal, only the accelerometer's white noise, which no model can explain and
which would otherwise bound the gap shrink by the ratio of the full-band to the in-band
noise. The full-band gap (the same without the projection) is reported alongside.

The band rule is in :mod:`.band`. The machinery itself lives in :mod:`.band` (the signal
band), :mod:`.windows` (windows, detrending, band projection), :mod:`.integrals` (A1, A2),
:mod:`.equations` (the columns of every DOF's equation) and :mod:`.gram` (per-window Grams
and the cross-validation); this module keeps the metric's description (:data:`METRIC`)
and gathers the building blocks under one name.
"""

from __future__ import annotations

from .band import signal_band
from .equations import to_physical
from .gram import EqSpec, cross_validate, window_stats
from .integrals import integrals
from .windows import band_filter, detrend, prepare

__all__ = [
    "METRIC",
    "METRIC_FORCE",
    "EqSpec",
    "band_filter",
    "cross_validate",
    "detrend",
    "integrals",
    "prepare",
    "signal_band",
    "to_physical",
    "window_stats",
]

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
