"""A spring network's parameters refined by output error: the joint equation-error fit
(:mod:`algid.diagnosis.joint`) as the start of a Gauss-Newton fit of the network's simulated
accelerations to the recorded ones.

Why: the equation error of DOF e is the accelerometer noise ``n`` passed through the network's
own dynamic stiffness, ``M^-1 Z(w) n / w^2`` with ``Z(w) = K - w^2 M + i w C``: small near
every resonance, large below it. An unweighted least squares on it spends its weight where
the noise is largest and gives the resonances, where a lightly damped network tells most about
itself, little; whitening that noise is the output error (bench/network_identify.py measures
both against the Cramer-Rao bound).

The model: ``M a + C v + K x = u`` simulated exactly from sample to sample with the force the
degree-5 polynomial through the six samples around each interval (:func:`_discrete`), in the
network's modal coordinates (one first-order recursion per mode, :func:`_simulate`). The
residual ``r = a_measured - a_model(theta, s0)`` over the record, ``s0`` the unknown positions
and velocities at its start; each DOF's residual weighted by the inverse of its variance. The
Jacobian: the sensitivities of the simulated accelerations, each the network's response to a
pseudo-force (``-a_e`` at DOF e for ``m_e``, ``-v_e`` for ``c_e``, ``-D_s' d_s`` for ``k_s``),
and the free responses for ``s0``. Standard deviations: ``sqrt(diag((J' W J)^-1))`` at the
optimum (the bound's own form, the noise taken white).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import lfilter

from ..model.network import Network
from ..simulator.state_space import phi

#: Samples through which the force is interpolated on each interval, and how many of them
#: lie before the interval's start.
POINTS, LEAD = 6, 2
#: Gauss-Newton iterations at most, and the relative step below which it stops.
ITERATIONS, STEP_TOL = 8, 1e-9
#: Jacobian columns simulated at once (memory: T x 2n complex numbers each).
BATCH = 8


def _state_space(net: Network, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``A, B, Ca`` of ``s = [x; v]``: ``s' = A s + B f``, ``a = Ca s + M^-1 f``."""
    n = net.n
    m, c, k = theta[:n], theta[n : 2 * n], np.nan_to_num(theta[2 * n :])
    K = net.stiffness_matrix(k)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -K / m[:, None]
    A[n:, n:] = -np.diag(c / m)
    B = np.vstack([np.zeros((n, n)), np.diag(1.0 / m)])
    return A, B, A[n:]


def _discrete(A: np.ndarray, B: np.ndarray, dt: float) -> list[np.ndarray]:
    """``W_i`` (2n, n) with ``s_{t+1} = expm(A dt) s_t + sum_i W_i f_{t-LEAD+i}``: the force on
    each interval the polynomial through samples ``t-LEAD .. t-LEAD+POINTS-1``, integrated
    exactly (the simulator's phi functions, :func:`algid.simulator.state_space.phi`)."""
    ph = phi(A * dt, POINTS)
    # Gamma_j = int_0^dt expm(A (dt - s)) B (s / dt)^j ds = j! dt phi_{j+1}(A dt) B
    gamma = [math.factorial(j) * dt * ph[j + 1] @ B for j in range(POINTS)]
    coef = np.linalg.inv(np.vander(np.arange(POINTS) - LEAD, increasing=True))  # (power j, sample i)
    return [sum(coef[j, i] * gamma[j] for j in range(POINTS)) for i in range(POINTS)]


class _Model:
    """The network ``theta`` discretised in modal coordinates on a record of ``T`` samples."""

    def __init__(self, net: Network, theta: np.ndarray, dt: float, T: int) -> None:
        A, B, self.Ca = _state_space(net, theta)
        lam, self.V = np.linalg.eig(A)
        self.Vinv = np.linalg.inv(self.V)
        self.mu = np.exp(lam * dt)
        Wz = np.concatenate([(self.Vinv @ W).T for W in _discrete(A, B, dt)])  # (POINTS n, 2n modes)
        self.Wz = np.hstack([Wz.real, Wz.imag])
        self.minv = 1.0 / theta[: net.n]
        self.Ns = T - POINTS + 1 + 1  # samples LEAD .. T - POINTS + LEAD + 1
        self.CaV = self.Ca @ self.V

    def forced(self, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Accelerations (Ns, n, c) and states (Ns, 2n, c) from rest at the first analysed
        sample under forces ``f`` (T, n, c) [N]."""
        Ns = self.Ns
        fc = f.transpose(0, 2, 1)  # (T, c, n): the products below are matrix products
        stacked = np.concatenate([fc[i : i + Ns - 1] for i in range(POINTS)], axis=2)
        g = np.dot(stacked.reshape(-1, stacked.shape[2]), self.Wz).reshape(stacked.shape[:2] + (-1,))
        g = g[..., : self.mu.size] + 1j * g[..., self.mu.size :]  # (Ns-1, c, 2n modes)
        z = np.zeros((Ns,) + g.shape[1:], dtype=complex)
        for r, mu in enumerate(self.mu):
            z[1:, :, r] = lfilter([1.0], [1.0, -mu], g[:, :, r], axis=0)
        s = _real_product(z, self.V.T)
        a = _real_product(z, self.CaV.T) + self.minv[None, None, :] * fc[LEAD : LEAD + Ns]
        return a.transpose(0, 2, 1), s.transpose(0, 2, 1)

    def free(self) -> tuple[np.ndarray, np.ndarray]:
        """Accelerations (Ns, n, 2n) and states (Ns, 2n, 2n) of the free responses from each unit initial state."""
        powers = self.mu[None, :] ** np.arange(self.Ns)[:, None]  # (Ns, 2n modes)
        z = powers[:, :, None] * self.Vinv[None]  # (Ns, r, i)
        zt = z.transpose(0, 2, 1)  # (Ns, i, r)
        return _real_product(zt, self.CaV.T).transpose(0, 2, 1), _real_product(zt, self.V.T).transpose(0, 2, 1)


def _real_product(z: np.ndarray, R: np.ndarray) -> np.ndarray:
    """``Re(z @ R)`` over the last axis of ``z`` by two real 2-D matrix products."""
    shape = z.shape[:-1] + (R.shape[1],)
    z2 = z.reshape(-1, z.shape[-1])
    re, im = np.ascontiguousarray(z2.real), np.ascontiguousarray(z2.imag)
    return (np.dot(re, R.real) - np.dot(im, R.imag)).reshape(shape)


def _pseudo_forces(net: Network, j: list[int], a: np.ndarray, s: np.ndarray, T: int) -> np.ndarray:
    """(T, n, len(j)) pseudo-forces of packed parameters ``j`` (module docstring) on the
    analysed samples (zero outside them)."""
    n = net.n
    D = net.deformation_matrix()
    f = np.zeros((T, n, len(j)))
    rows = slice(LEAD, LEAD + a.shape[0])
    for col, p in enumerate(j):
        if p < n:
            f[rows, p, col] = -a[:, p]
        elif p < 2 * n:
            f[rows, p - n, col] = -s[:, p]  # v_e is state n + e = p
        else:
            f[rows, :, col] = -np.outer(s[:, :n] @ D[p - 2 * n], D[p - 2 * n])
    return f


def _jacobian(model: _Model, net: Network, free: np.ndarray, a: np.ndarray, s: np.ndarray, T: int) -> np.ndarray:
    """(Ns, n, len(free)) derivatives of the simulated accelerations in the free parameters."""
    cols = []
    for start in range(0, free.size, BATCH):
        cols.append(model.forced(_pseudo_forces(net, list(free[start : start + BATCH]), a, s, T))[0])
    return np.concatenate(cols, axis=2)


def refine(
    net: Network, theta: np.ndarray, a: np.ndarray, u: np.ndarray, dt: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The output-error fit (module docstring) of accelerations ``a`` (T, n) [m/s^2] under
    forces ``u`` (T, n) [N] from the packed ``theta`` (NaN where no estimate: left as it is)
    -> the refined ``theta``, its standard deviations (NaN where not fitted) and the RMS
    residual of every DOF's acceleration (n,) [m/s^2] at the last step; all NaN when a step
    leaves a mass at or below zero or a damper below zero (no stable network to simulate)."""
    T, n = a.shape
    free = np.nonzero(np.isfinite(theta))[0]
    theta = theta.copy()
    meas = a[LEAD : LEAD + T - POINTS + 2]
    s0 = np.zeros(2 * n)
    for _ in range(ITERATIONS):
        if np.any(theta[:n] <= 0) or np.any(theta[n : 2 * n] < 0):  # no stable network to simulate
            return np.full_like(theta, np.nan), np.full_like(theta, np.nan), np.full(n, np.nan)
        model = _Model(net, theta, dt, T)
        a_f, s_f = model.forced(u[:, :, None])
        a_0, s_0 = model.free()
        a_hat = a_f[..., 0] + a_0 @ s0
        s_hat = s_f[..., 0] + s_0 @ s0
        r = meas - a_hat
        w = 1.0 / np.maximum(np.mean(r**2, axis=0), 1e-300)
        J = np.concatenate([_jacobian(model, net, free, a_hat, s_hat, T), a_0], axis=2)  # d a_model
        step, cov = _weighted_step(J, r, w)
        theta[free] += step[: free.size]
        s0 = s0 + step[free.size :]
        if np.all(np.abs(step[: free.size]) <= STEP_TOL * np.abs(theta[free])):
            break
    sigma = np.full_like(theta, np.nan)
    sigma[free] = np.sqrt(np.diag(cov)[: free.size])
    return theta, sigma, 1.0 / np.sqrt(w)


def _weighted_step(J: np.ndarray, r: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Newton step of ``sum_e w_e |r_e - J_e step|^2`` and the covariance ``(J' W J)^-1``."""
    root = np.sqrt(w)
    Jw = (J * root[None, :, None]).reshape(-1, J.shape[2])
    H = np.dot(Jw.T, Jw)  # np.dot: BLAS on the transposed view (matmul was 20x slower here)
    g = np.dot(Jw.T, (r * root[None, :]).reshape(-1))
    d = np.sqrt(np.diag(H))
    Hs_inv = np.linalg.inv(H / d[:, None] / d[None, :])
    return (Hs_inv @ (g / d)) / d, Hs_inv / d[:, None] / d[None, :]
