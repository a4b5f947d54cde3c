"""The two baselines a user would otherwise pick, for bench/continuous.py.

A module, not a script: it measures nothing by itself; ``bench/continuous.py`` runs and scores
both beside the continuous estimator (docs/continuous.md, "Baselines").

RLS (``rls``): recursive least squares with exponential forgetting on the same integrated
regressors as the algebraic estimator: row 1 of eqs. 3-4 for every DOF,

    a_11,i m_i + a_12,i c_i + a_13,i k_i + a_14,i k_{i+1} = b_1,i        (divided by Delta^2),

built on reseeded windows of ``window_s`` (the iterated integrals by the estimator's 8-point
interpolatory rule, weights from ``algid.estimator.reference``; the first ``skip`` samples of each window, where the
row is nearly zero, are left out), one row per DOF and sample, all DOFs in one joint
least-squares problem over the 3n+1 parameters (interior springs shared). RLS with
forgetting factor lambda and an uninformative start is exactly the exponentially weighted
least-squares solution theta_t = R_t^-1 r_t with R_t = lambda R_{t-1} + sum_rows phi phi^T and
r_t = lambda r_{t-1} + sum_rows phi y, which is what is computed (the running sums by a
first-order recursive filter along time, vectorised; the solve only where an estimate is
read). ``memory_s`` = h / (1 - lambda) is the forgetting time constant.

UKF (``ukf``): filterpy's UnscentedKalmanFilter estimating positions, velocities and the log
parameters jointly from the accelerations, the measured force taken as a known input (held
linear between samples, one RK4 step per sample). Parameters follow a random walk of
intensity ``q_param`` [1/sqrt(s)] in log space (the tuning knob: 0 cannot track, large is
noisy). Run at 1/``decimate`` of the sample rate on low-passed signals (see ``ukf``). The measurement noise is set to the true noise level (plus the force noise seen
through 1/m), the process noise of the velocities to the force noise. The initial parameter
guess is the truth times exp(N(0, 0.3^2)) per parameter with that prior spread: the UKF is
told more than the algebraic estimator, which needs no guess. Sigma points are propagated in
one vectorised call (the only change to filterpy: ``compute_process_sigmas``); the
measurement function is filterpy's per-point loop.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from algid.estimator import reference  # noqa: E402

# ---------------------------------------------------------------------------------------------
# RLS on the integrated regressors


def _window_integrals(F: np.ndarray, h: float, W: np.ndarray, orders: int = 2) -> list[np.ndarray]:
    """``[F, I F, I^2 F]`` for every row of F (windows x M) with the estimator's interpolatory
    rule (weights ``W`` of ``reference.quadrature_weights``; stencil centred, shifted at t0),
    vectorised over windows (same arithmetic as ``reference.iterated_integrals``)."""
    nw, M = F.shape
    P = W.shape[2]
    j = np.arange(M - 1)
    start = np.clip(j - (P // 2 - 1), 0, M - P)
    off = j - start
    stencil = F[:, start[:, None] + np.arange(P)[None, :]]  # (nw, M-1, P)
    out = [F]
    for r in range(1, orders + 1):
        inc = h**r * np.einsum("jm,wjm->wj", W[off, r - 1], stencil)
        for q in range(1, r):
            inc = inc + h ** (r - q) / np.prod(np.arange(1, r - q + 1)) * out[q][:, :-1]
        out.append(np.concatenate([np.zeros((nw, 1)), np.cumsum(inc, axis=1)], axis=1))
    return out


def rls_rows(
    a: np.ndarray, u: np.ndarray, dt: float, window_s: float, skip: int = 16, boundary: str = "fixed"
) -> tuple[np.ndarray, np.ndarray]:
    """Regressor rows Phi (T, n, 3n+1) and targets Y (T, n) of row 1 of eqs. 3-4 divided by
    Delta^2 on reseeded windows (zero rows in the first ``skip`` samples of each window and in a
    partial last one). Iterated integrals by the estimator's 8-point interpolatory rule."""
    T, n = a.shape
    p = 3 * n + 1
    M = int(round(window_s / dt))
    nw = T // M
    W = reference.quadrature_weights(8)
    delta = np.arange(M) * dt
    d2 = np.where(delta > 0, delta, np.inf) ** -2.0
    Phi = np.zeros((T, n, p))
    Y = np.zeros((T, n))
    used = slice(0, nw * M)

    def blocks(x):
        return x[: nw * M].reshape(nw, M)

    def row1(f):  # Delta^2 f - 4 I(Delta f) + 2 I^2 f, and I(Delta^2 f) - 2 I^2(Delta f)
        g0 = _window_integrals(f, dt, W)
        g1 = _window_integrals(delta * f, dt, W)
        g2 = _window_integrals(delta**2 * f, dt, W)
        return g2[0] - 4 * g1[1] + 2 * g0[2], g2[1] - 2 * g1[2], g2[2]

    Ya = [row1(blocks(a[:, i])) for i in range(n)]
    ok = (np.arange(M) >= skip)[None, :]
    for i in range(n):
        a_m, a_c, i2_self = Ya[i]
        i2_left = Ya[i - 1][2] if i > 0 else 0.0
        i2_right = Ya[i + 1][2] if i + 1 < n else 0.0
        b, _, _ = row1(blocks(u[:, i]))
        cols = [i, n + i, 2 * n + i]
        rows = [a_m, a_c, i2_self - i2_left]
        if not ((n == 1 or boundary == "free") and i == n - 1):
            cols.append(2 * n + i + 1)
            rows.append(i2_self - i2_right)
        for c, r in zip(cols, rows):
            Phi[used, i, c] = np.where(ok, r * d2, 0.0).reshape(-1)
        Y[used, i] = np.where(ok, b * d2, 0.0).reshape(-1)
    return Phi, Y


def rls(
    a: np.ndarray,
    u: np.ndarray,
    dt: float,
    read: np.ndarray,
    *,
    window_s: float = 0.3,
    memory_s=np.inf,
    boundary: str = "fixed",
) -> np.ndarray | list[np.ndarray]:
    """RLS-with-forgetting estimates (len(read), 3n+1) at the sample indices ``read``; a list
    of them when ``memory_s`` is a sequence (the regressors are shared).

    The regressor rows of a window use samples up to its end, so they enter the sums at the
    window's last sample with their own ages (causal, like the algebraic window results)."""
    T, n = a.shape
    p = 3 * n + 1
    Phi, Y = rls_rows(a, u, dt, window_s, boundary=boundary)
    known = np.ones(p, dtype=bool)
    if boundary == "free" or n == 1:
        known[-1] = False
    idx = np.nonzero(known)[0]
    R_t = np.einsum("tia,tib->tab", Phi, Phi).reshape(T, p * p)
    r_t = np.einsum("tia,ti->ta", Phi, Y)
    M = int(round(window_s / dt))
    results = []
    for mem in np.atleast_1d(memory_s):
        out = np.full((len(read), p), np.nan)
        done = (np.asarray(read) + 1) // M * M - 1  # last sample of the last complete window
        have = np.nonzero(done >= 0)[0]
        if not np.isfinite(mem):
            Rc, rc = np.cumsum(R_t, axis=0), np.cumsum(r_t, axis=0)
        else:  # filter along contiguous rows (time last), then back
            lam = float(np.exp(-dt / mem))
            Rc = lfilter([1.0], [1.0, -lam], np.ascontiguousarray(R_t.T), axis=-1).T
            rc = lfilter([1.0], [1.0, -lam], np.ascontiguousarray(r_t.T), axis=-1).T
        R = Rc[done[have]].reshape(-1, p, p)[:, idx][:, :, idx]
        r = rc[done[have]][:, idx]
        sol = np.full((have.size, idx.size), np.nan)
        try:  # batch solve; if a start-up system is singular, one by one (that one stays NaN)
            sol = np.linalg.solve(R, r[..., None])[..., 0]  # the common decay cancels
        except np.linalg.LinAlgError:
            for q in range(have.size):
                try:
                    sol[q] = np.linalg.solve(R[q], r[q])
                except np.linalg.LinAlgError:
                    pass
        out[np.ix_(have, idx)] = sol
        if boundary == "free":
            out[:, -1] = 0.0
        results.append(out)
    return results if np.ndim(memory_s) else results[0]


# ---------------------------------------------------------------------------------------------
# UKF (filterpy)


def _ukf_class():
    from filterpy.kalman import UnscentedKalmanFilter

    class VectorisedUKF(UnscentedKalmanFilter):
        """filterpy's UKF whose process model takes all sigma points at once."""

        def compute_process_sigmas(self, dt, fx=None, **fx_args):
            fx = self.fx if fx is None else fx
            sigmas = self.points_fn.sigma_points(self.x, self.P)
            self.sigmas_f = fx(sigmas, dt, **fx_args)

    return VectorisedUKF


def _accel(X: np.ndarray, V: np.ndarray, th: np.ndarray, u: np.ndarray, n: int) -> np.ndarray:
    """Accelerations of eq. 1 for a batch: X, V (B, n), th (B, 3n+1) physical, u (n,)."""
    m, c, k = th[:, :n], th[:, n : 2 * n], th[:, 2 * n :]
    Xp = np.concatenate([np.zeros((X.shape[0], 1)), X, np.zeros((X.shape[0], 1))], axis=1)
    spring = k[:, :n] * (X - Xp[:, :-2]) + k[:, 1:] * (X - Xp[:, 2:])
    return (u[None, :] - c * V - spring) / m


def ukf(
    a: np.ndarray,
    u: np.ndarray,
    dt: float,
    read: np.ndarray,
    *,
    truth0: np.ndarray,
    sigma_a: np.ndarray,
    sigma_u: np.ndarray,
    q_param: float = 1e-3,
    prior: float = 0.3,
    seed: int = 0,
    boundary: str = "fixed",
    alpha: float = 0.3,
    decimate: int = 4,
) -> tuple[np.ndarray, bool]:
    """UKF estimates (len(read), 3n+1) at the sample indices ``read`` (the latest UKF update
    at or before each; NaN after a divergence); returns (estimates, diverged).

    ``decimate`` D > 1: the accelerations and forces are low-passed (zero-phase FIR, cut-off
    0.4 of the decimated Nyquist rate, 100 Hz for D = 4 at 1 kHz: the 0-20 Hz signal band is
    untouched) and the UKF updates every D-th sample, with D RK4 sub-steps per update on the
    full-rate filtered force (mid-points by 4-point interpolation). The measurement noise is
    the filtered noise's. This keeps nearly all the information of the band-limited signals
    at 1/D of the cost (filterpy at 1 kHz costs ~1.5 ms per sample); the filtering looks
    ahead by ~30 ms, irrelevant at the 1, 10, 60 s marks.
    """
    from filterpy.kalman import MerweScaledSigmaPoints
    from scipy.signal import filtfilt, firwin

    T, n = a.shape
    p = 3 * n + 1
    D = max(1, int(decimate))
    if D > 1:
        taps = firwin(61, 0.4 / D)
        a = filtfilt(taps, [1.0], a, axis=0)
        u = filtfilt(taps, [1.0], u, axis=0)
        impulse = np.zeros(401)
        impulse[200] = 1.0
        gain = float(np.sqrt(np.sum(filtfilt(taps, [1.0], impulse) ** 2)))
    else:
        gain = 1.0
    sigma_a = np.asarray(sigma_a, dtype=float) * gain
    sigma_u = np.asarray(sigma_u, dtype=float) * gain
    up = np.concatenate([u[:1], u, u[-1:], u[-1:]])  # up[k+1] = u[k], padded for the stencil
    known = np.ones(p, dtype=bool)
    if boundary == "free":
        known[-1] = False
    idx = np.nonzero(known)[0]
    q = idx.size
    L = 2 * n + q
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x0CF]))
    guess = truth0[idx] * np.exp(prior * rng.standard_normal(q))
    base = truth0.copy()

    def physical(phi_batch):
        th = np.tile(base, (phi_batch.shape[0], 1))
        th[:, idx] = np.exp(phi_batch)
        if boundary == "free":
            th[:, -1] = 0.0
        return th

    def fx(S, h, k0):
        """Propagate the sigma points from sample k0 to k0 + D (D RK4 steps of dt)."""
        X, V, th = S[:, :n].copy(), S[:, n : 2 * n].copy(), physical(S[:, 2 * n :])
        for k in range(k0, k0 + D):
            u0, u1 = up[k + 1], up[k + 2]
            um = (-up[k] + 9 * u0 + 9 * u1 - up[k + 3]) / 16
            k1x, k1v = V, _accel(X, V, th, u0, n)
            k2x, k2v = V + 0.5 * dt * k1v, _accel(X + 0.5 * dt * k1x, V + 0.5 * dt * k1v, th, um, n)
            k3x, k3v = V + 0.5 * dt * k2v, _accel(X + 0.5 * dt * k2x, V + 0.5 * dt * k2v, th, um, n)
            k4x, k4v = V + dt * k3v, _accel(X + dt * k3x, V + dt * k3v, th, u1, n)
            X = X + dt / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
            V = V + dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        out = S.copy()
        out[:, :n], out[:, n : 2 * n] = X, V
        return out

    def hx(s, uk):
        return _accel(s[None, :n], s[None, n : 2 * n], physical(s[None, 2 * n :]), uk, n)[0]

    points = MerweScaledSigmaPoints(L, alpha=alpha, beta=2.0, kappa=0.0)
    filt = _ukf_class()(dim_x=L, dim_z=n, dt=dt * D, fx=fx, hx=hx, points=points)
    x_scale = np.maximum(np.sqrt(np.mean(a**2, axis=0)) / (2 * np.pi * 3.0) ** 2, 1e-9)  # ~ displacement RMS
    v_scale = x_scale * 2 * np.pi * 3.0
    filt.x = np.concatenate([np.zeros(n), np.zeros(n), np.log(guess)])
    filt.P = np.diag(np.concatenate([(3 * x_scale) ** 2, (3 * v_scale) ** 2, np.full(q, prior**2)]))
    m_guess = physical(np.log(guess)[None])[0, :n]
    floor = 1e-6 * np.sqrt(np.mean(a**2, axis=0))
    filt.R = np.diag(sigma_a**2 + (sigma_u / m_guess) ** 2 + floor**2)
    qv = D * (dt * sigma_u / m_guess) ** 2 + (1e-9 * v_scale) ** 2
    qx = (1e-9 * x_scale) ** 2
    filt.Q = np.diag(np.concatenate([qx, qv, np.full(q, q_param**2 * dt * D)]))
    out = np.full((len(read), p), np.nan)
    read = np.asarray(read)
    diverged = False
    latest = None
    r = 0
    for k in range(0, T, D):
        try:
            if k > 0:
                filt.predict(k0=k - D)
            filt.update(a[k], uk=u[k])
        except (np.linalg.LinAlgError, ValueError, FloatingPointError):
            diverged = True
            break
        if not np.all(np.isfinite(filt.x)):
            diverged = True
            break
        latest = physical(filt.x[None, 2 * n :])[0]
        while r < len(read) and read[r] < k + D:
            out[r] = latest
            r += 1
        if r == len(read):
            break
    return out, diverged
