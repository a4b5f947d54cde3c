"""Plain numpy reference of the algebraic estimator (eqs. 3-7), whole-signal.

Written independently of the C++ core (vectorised over the whole record instead of
sample by sample) and used as the oracle in the tests and as the baseline in bench/; the
library never imports it (its quadrature weights are :mod:`algid.estimator.quadrature`).
It implements the same discretisation, so both agree to rounding:

* Quadrature ("interpolatory iterated integration"): on every sample interval
  ``[t_j, t_{j+1}]`` the signal is replaced by the degree ``P-1`` polynomial through
  ``P`` consecutive samples (centred on the interval, shifted right near ``t0``), and
  the iterated integrals ``I^r f`` are advanced *exactly* for that polynomial:

      I^r(t_{j+1}) = sum_{q=1..r} h^(r-q)/(r-q)! I^q(t_j) + int_{t_j}^{t_{j+1}} (t_{j+1}-s)^(r-1)/(r-1)! p_j(s) ds

  ``P = 2`` is piecewise-linear (the trapezoidal baseline).
* The integrals of ``Delta^p f`` (``Delta = t - t0``) that eq. 4 needs are not integrated
  separately: integration by parts gives exactly
  ``I^r(Delta f) = Delta I^r f - r I^(r+1) f`` and
  ``I^r(Delta^2 f) = Delta^2 I^r f - 2 r Delta I^(r+1) f + r (r+1) I^(r+2) f``,
  so one chain of ``f`` up to order 7 serves every power (:func:`moments`; the direct
  quadrature of ``Delta^p f``, :func:`moments_direct`, agrees to the rule's truncation error).
* Eq. 4, rows 2-4 of eq. 5 by eq. 6, Cramer on a time-scaled copy of the 4x4 system,
  eq. 7 as the weighted mean of the Cramer solutions with weight ``|det A|`` (identical to
  the paper's ratio of double integrals of determinants).
"""

from __future__ import annotations

from math import factorial

import numpy as np

from .quadrature import MAX_ORDER, quadrature_weights


def iterated_integrals(f: np.ndarray, h: float, points: int, max_order: int = MAX_ORDER) -> np.ndarray:
    """``I[r, j] = (I^r f)(t_j)`` for r = 0..max_order (r = 0 is f itself), I^r(t_0) = 0."""
    f = np.asarray(f, dtype=float)
    T = f.size
    if T < points:
        raise ValueError(f"need at least {points} samples")
    W = quadrature_weights(points, max_order)
    half = points // 2
    j = np.arange(T - 1)
    start = np.clip(j - (half - 1), 0, T - points)
    off = j - start
    idx = start[:, None] + np.arange(points)[None, :]
    stencil = f[idx]  # (T-1, points)
    out = np.zeros((max_order + 1, T))
    out[0] = f
    for r in range(1, max_order + 1):
        inc = h**r * np.einsum("jm,jm->j", W[off, r - 1], stencil)
        for q in range(1, r):
            inc = inc + h ** (r - q) / factorial(r - q) * out[q, :-1]
        out[r, 1:] = np.cumsum(inc)
    return out


def moments(f: np.ndarray, delta: np.ndarray, h: float, points: int, max_order: int = MAX_ORDER) -> np.ndarray:
    """``G[p, r, j] = I^r(Delta^p f)(t_j)`` for p = 0, 1, 2, r = 0..max_order, from the chain
    of ``f`` alone and the integration-by-parts identity (what the C++ core does)."""
    top = max_order
    I = iterated_integrals(f, h, points, top + 2)
    r = np.arange(top + 1)[:, None]
    G = np.empty((3, top + 1, f.size))
    G[0] = I[: top + 1]
    G[1] = delta * I[: top + 1] - r * I[1 : top + 2]
    G[2] = delta**2 * I[: top + 1] - 2 * r * delta * I[1 : top + 2] + r * (r + 1) * I[2 : top + 3]
    return G


def moments_direct(f: np.ndarray, delta: np.ndarray, h: float, points: int) -> np.ndarray:
    """The same ``G`` by integrating each ``Delta^p f`` with the rule (exact for ``f`` of
    degree ``points - 1 - p`` only): the cross-check of :func:`moments`."""
    return np.stack([iterated_integrals(delta**p * f, h, points) for p in range(3)])


def _row1_operator(G: np.ndarray, q: int) -> np.ndarray:
    """``I^q`` of ``Delta^2 f - 4 I(Delta f) + 2 I^2 f`` (the a_11 / b_1 operator of eq. 4)."""
    return G[2, q] - 4.0 * G[1, q + 1] + 2.0 * G[0, q + 2]


def system(y: np.ndarray, u: np.ndarray, dt: float, boundary: str = "fixed", points: int = 8):
    """The time-scaled systems of eq. 5 for every DOF and sample.

    Returns ``S (T, n, 4, 4)``, ``b (T, n, 4)`` and ``tau (T,)``; ``S = R A C`` with
    ``R = diag(1, tau^-1, tau^-2, tau^-3)``, ``C = diag(tau^-2, tau^-3, tau^-4, tau^-4)``
    and ``b = tau^-2 R B``, so that ``S phi = b`` with
    ``theta = [phi_1, phi_2/tau, phi_3/tau^2, phi_4/tau^2]``.
    """
    y = np.atleast_2d(np.asarray(y, dtype=float))
    u = np.atleast_2d(np.asarray(u, dtype=float))
    if y.shape != u.shape:
        raise ValueError("accel and force must have the same shape")
    T, n = y.shape
    tau = dt * np.arange(T)
    Gy = [moments(y[:, i], tau, dt, points) for i in range(n)]
    Gu = [moments(u[:, i], tau, dt, points) for i in range(n)]
    zero = np.zeros_like(Gy[0])
    A = np.zeros((T, n, 4, 4))
    B = np.zeros((T, n, 4))
    for i in range(n):
        left = Gy[i - 1] if i > 0 else zero
        right = Gy[i + 1] if i + 1 < n else zero
        g = Gy[i]
        for q in range(4):
            A[:, i, q, 0] = _row1_operator(g, q)
            A[:, i, q, 1] = g[2, q + 1] - 2.0 * g[1, q + 2]
            A[:, i, q, 2] = g[2, q + 2] - left[2, q + 2]
            A[:, i, q, 3] = g[2, q + 2] - right[2, q + 2]
            B[:, i, q] = _row1_operator(Gu[i], q)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(tau > 0, 1.0 / tau, 0.0)
    R = np.stack([np.ones(T), inv, inv**2, inv**3], axis=1)  # (T, 4)
    C = np.stack([inv**2, inv**3, inv**4, inv**4], axis=1)
    S = A * R[:, None, :, None] * C[:, None, None, :]
    b = B * R[:, None, :] * (inv**2)[:, None, None]
    return S, b, tau


def equilibrated_hadamard(S: np.ndarray) -> np.ndarray:
    """Hadamard ratio ``|det| / prod(row norms)`` after scaling every column to unit norm."""
    col = np.linalg.norm(S, axis=-2, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        Sc = S / col
        h = np.abs(np.linalg.det(Sc)) / np.prod(np.linalg.norm(Sc, axis=-1), axis=-1)
    return np.where(np.isfinite(h), h, 0.0)


def estimate(
    y, u, dt: float, boundary: str = "fixed", points: int = 8, min_samples: int = 16, min_hadamard: float = 1e-9
):
    """Instantaneous (eq. 5) and ratio (eq. 7) estimates for every sample.

    Returns a dict with ``theta_inst`` and ``theta_ratio`` of shape ``(T, n, 4)``
    (``[m_i, c_i, k_i, k_{i+1}]``; reduced DOFs — n = 1 with walls or the last DOF of
    a free chain — solve the 3x3 system and put NaN in the 4th entry; for n = 1 with
    walls entry 3 is k_1 + k_2), ``hadamard (T, n)`` and ``tau (T,)``.

    A sample enters eq. 7 when it is *trusted*: ``index + points - 1 >= min_samples``
    (the samples the causal C++ chain has consumed when it reaches that instant), a finite
    non-zero determinant, and an equilibrated Hadamard ratio ``>= min_hadamard``.
    """
    S, b, tau = system(y, u, dt, boundary, points)
    T, n = S.shape[:2]
    reduced = np.zeros(n, dtype=bool)
    if n == 1 or boundary == "free":
        reduced[-1] = True
    theta = np.full((T, n, 4), np.nan)
    weight = np.zeros((T, n))
    had = np.zeros((T, n))
    for i in range(n):
        m = 3 if reduced[i] else 4
        Si, bi = S[:, i, :m, :m], b[:, i, :m]
        det = np.linalg.det(Si)
        had[:, i] = equilibrated_hadamard(Si)
        ok = (tau > 0) & np.isfinite(det) & (det != 0)
        phi = np.full((T, m), np.nan)
        phi[ok] = np.linalg.solve(Si[ok], bi[ok][..., None])[..., 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.stack([np.ones(T), 1 / tau, 1 / tau**2, 1 / tau**2], axis=1)[:, :m]
        theta[:, i, :m] = phi * scale
        # |det A| = |det S| tau^q, q = 19 (4x4) or 12 (3x3); only well-conditioned samples count.
        q = 19 if m == 4 else 12
        good = ok & (had[:, i] >= min_hadamard) & (np.arange(T) + points - 1 >= min_samples)
        with np.errstate(over="ignore"):
            weight[:, i] = np.where(good, np.abs(det) * tau**q, 0.0)
    theta_ratio = np.full_like(theta, np.nan)
    for i in range(n):
        w = weight[:, i]
        den = _cumtrapz2(w, dt)
        for j in range(4):
            num = _cumtrapz2(np.where(w > 0, w * np.nan_to_num(theta[:, i, j]), 0.0), dt)
            with np.errstate(divide="ignore", invalid="ignore"):
                theta_ratio[:, i, j] = np.where(den > 0, num / den, np.nan)
        if reduced[i]:
            theta_ratio[:, i, 3] = np.nan
    return {"theta_inst": theta, "theta_ratio": theta_ratio, "hadamard": had, "tau": tau}


def _cumtrapz2(w: np.ndarray, h: float) -> np.ndarray:
    """Double cumulative trapezoidal integral from t0 (zero initial conditions)."""
    z1 = np.concatenate([[0.0], np.cumsum(0.5 * h * (w[1:] + w[:-1]))])
    return np.concatenate([[0.0], np.cumsum(0.5 * h * (z1[1:] + z1[:-1]))])
