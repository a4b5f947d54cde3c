"""Accelerations from measured velocities or displacements: exact derivatives of the
interpolating polynomial of uniformly sampled signals."""

from __future__ import annotations

import math

import numpy as np

from .core import Recording, RecordingError

#: Points of the interpolating polynomial :func:`accelerations` differentiates.
DEFAULT_DIFF_POINTS = 5


def derivative_weights(points: int, order: int, at: int) -> np.ndarray:
    """Weights ``w`` with ``f^(order)(s_at) ~= h^-order * sum_m w[m] f(s_m)``.

    Exact derivative of the degree ``points-1`` polynomial interpolating ``f`` at the
    unit-spaced nodes ``s_m = m`` (m = 0..points-1), evaluated at node ``at``.
    """
    if not 0 <= at < points or order >= points:
        raise ValueError("need 0 <= at < points and order < points")
    s = np.arange(points, dtype=float) - at
    # Row q of V: s^q / q!; the weights solve V w = e_order (moment conditions).
    V = np.array([s**q / math.factorial(q) for q in range(points)])
    rhs = np.zeros(points)
    rhs[order] = 1.0
    return np.linalg.solve(V, rhs)


def derivative(x: np.ndarray, dt: float, order: int = 2, points: int = DEFAULT_DIFF_POINTS) -> np.ndarray:
    """Time derivative of order ``order`` of uniformly sampled columns by polynomial
    interpolation.

    At every sample, the degree ``points-1`` polynomial through ``points`` consecutive
    samples (centred on the sample; shifted inwards at both ends) is differentiated
    exactly. For odd ``points`` the interior stencil is the symmetric central
    difference, of accuracy ``O(dt^(points-1))`` for the second derivative and
    ``O(dt^(points-1))`` for the first; the ``(points-1)/2`` samples at each end use
    one-sided stencils, one order less accurate.

    Parameters
    ----------
    x : (T,) or (T, n) samples.
    dt : sampling interval [s].
    order : 1 or 2 (or higher, below ``points``).
    points : stencil width (> order, >= 3).
    """
    x = np.asarray(x, dtype=float)
    one = x.ndim == 1
    X = x[:, None] if one else x
    T = X.shape[0]
    if points < 3 or points <= order:
        raise ValueError("points must be >= 3 and > order")
    if T < points:
        raise RecordingError(f"too short to differentiate: {T} samples, need {points}")
    half = points // 2
    out = np.empty_like(X)
    w = derivative_weights(points, order, half)
    interior = slice(half, T - (points - 1 - half))
    acc = np.zeros((T - points + 1, X.shape[1]))
    for m in range(points):
        acc += w[m] * X[m : T - points + 1 + m]
    out[interior] = acc
    for k in range(half):  # left end: nodes 0..points-1, evaluated at k
        out[k] = derivative_weights(points, order, k) @ X[:points]
    for k in range(points - 1 - half):  # right end
        at = points - 1 - k
        out[T - 1 - k] = derivative_weights(points, order, at) @ X[T - points :]
    out /= dt**order
    return out[:, 0] if one else out


def second_derivative(x: np.ndarray, dt: float, points: int = DEFAULT_DIFF_POINTS) -> np.ndarray:
    """:func:`derivative` of order 2 (accelerations from displacements)."""
    return derivative(x, dt, 2, points)


def accelerations(rec: Recording, points: int = DEFAULT_DIFF_POINTS) -> np.ndarray:
    """Accelerations (T, n) [m/s^2] the estimator needs.

    The measured ``a`` when the recording has it; otherwise the exact first derivative of
    the ``points``-point interpolating polynomial of the velocities ``v``, or its second
    derivative of the displacements ``x`` (see :func:`derivative`): with the default 5
    points, ``(v[k-2] - 8 v[k-1] + 8 v[k+1] - v[k+2]) / (12 dt)`` and
    ``(-x[k-2] + 16 x[k-1] - 30 x[k] + 16 x[k+1] - x[k+2]) / (12 dt^2)``, error ``dt^4 x^(6) / 90``
    for the second (relative error 1.1e-4 for a sine at 1/20 of the sampling rate, 1.7e-3
    at 1/10).
    Differentiation amplifies measurement noise: white displacement noise of standard
    deviation s becomes acceleration noise of ``3.1 s / dt^2`` (5 points), white velocity
    noise ``0.95 s / dt`` — at 1 kHz a 1 um displacement noise gives 3.1 m/s^2. The
    identification and the diagnosis take that noise into account (:mod:`algid.recording.noise`).
    """
    if rec.a is not None:
        return rec.a
    if rec.v is not None:
        return derivative(rec.v, rec.dt, 1, points)
    return second_derivative(rec.x, rec.dt, points)


def base_acceleration(rec: Recording, points: int = DEFAULT_DIFF_POINTS) -> np.ndarray:
    """The support's acceleration (T,) [m/s^2] of a base-excited record: ``a0`` as measured,
    or derived from ``v0`` or ``x0`` as :func:`accelerations` derives the DOFs'."""
    if rec.base is None:
        raise RecordingError("not a base-excited record: no support motion a0, v0 or x0")
    order = {"a": 0, "v": 1, "x": 2}[rec.base_kind]
    return rec.base if order == 0 else derivative(rec.base, rec.dt, order, points)


#: The :class:`Recording` field of each kind of motion :func:`motion` returns.
MOTION_FIELDS = {"acceleration": "a", "velocity": "v", "displacement": "x"}


def motion(rec: Recording) -> tuple[str, np.ndarray]:
    """The measured motion the estimator's accelerations come from: ``("acceleration", a)``,
    ``("velocity", v)`` or ``("displacement", x)``, in that order of preference."""
    if rec.a is not None:
        return "acceleration", rec.a
    if rec.v is not None:
        return "velocity", rec.v
    return "displacement", rec.x
