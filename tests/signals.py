"""Test oracles: an independent high-accuracy simulation of eq. 1 (scipy DOP853, tight
tolerances) sampled at fs, used to feed the estimators in the tests."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from algid.chain import Chain


def simulate_chain(chain: Chain, force, duration_s: float, fs_hz: float = 1000.0):
    """Accelerations and forces (T, n) of ``chain`` from rest under a smooth ``force(t)``."""
    M, C, K = chain.matrices()
    n = chain.n
    Minv = np.linalg.inv(M)

    def rhs(t, s):
        x, v = s[:n], s[n:]
        return np.concatenate([v, Minv @ (force(t) - C @ v - K @ x)])

    t = np.arange(int(round(duration_s * fs_hz)) + 1) / fs_hz
    sol = solve_ivp(rhs, (0.0, t[-1]), np.zeros(2 * n), t_eval=t, method="DOP853", rtol=1e-12, atol=1e-15)
    x, v = sol.y[:n].T, sol.y[n:].T
    u = np.array([force(tt) for tt in t])
    a = (Minv @ (u.T - C @ v.T - K @ x.T)).T
    return t, a, u, x


def multisine(n: int, seed: int = 0, offset_n: float = 5.0, amplitude_n: float = 4.0):
    """Open-loop multisine-plus-offset force per DOF [N] (7 tones, 1.3-31 Hz, random phases)."""
    rng = np.random.default_rng(seed)
    f = np.array([1.3, 3.7, 7.1, 11.3, 17.9, 23.5, 31.0])
    ph = rng.uniform(0, 2 * np.pi, (n, f.size))

    def force(t):
        return offset_n + amplitude_n * np.sin(2 * np.pi * f[None, :] * t + ph).sum(axis=1)

    return force


def relative_errors(chain: Chain, mass, damping, stiffness) -> np.ndarray:
    """|estimate / truth - 1| for the 3n+1 identifiable parameters (free end: 3n)."""
    truth = chain.identifiable()
    est = np.concatenate([np.atleast_1d(mass), np.atleast_1d(damping), np.atleast_1d(stiffness)])
    keep = np.isfinite(truth) & (truth != 0)
    return np.abs(est[keep] / truth[keep] - 1)
