"""An independent high-accuracy simulation of eq. 1 (scipy's DOP853 at tight tolerances),
sampled at fs, and the multisine force the tests and benchmarks drive it with: the reference
the estimators are checked against, noise-free (``tests/``, ``bench/accuracy.py``,
``bench/identify.py``). :func:`algid.simulator.simulate` is the general simulator (effects,
sensors, closed loop); this one does the linear chain only, to rounding."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from ..model.chain import Chain


def simulate_chain(chain: Chain, force, duration_s: float, fs_hz: float = 1000.0, breaks=()):
    """Accelerations and forces (T, n) of ``chain`` from rest under ``force(t)``, smooth
    between the instants in ``breaks`` [s]. A sample at a break (a jump of the force) takes
    the mean of the one-sided limits of force and acceleration, as a simultaneous sampler
    of the continuous signals sees a jump's midpoint."""
    M, C, K = chain.matrices()
    n = chain.n
    Minv = np.linalg.inv(M)

    def rhs(t, s):
        x, v = s[:n], s[n:]
        return np.concatenate([v, Minv @ (force(t) - C @ v - K @ x)])

    t = np.arange(int(round(duration_s * fs_hz)) + 1) / fs_hz
    edges = [0.0] + sorted(b for b in breaks if 0 < b < t[-1]) + [t[-1]]
    state = np.zeros(2 * n)
    x, v = np.zeros((t.size, n)), np.zeros((t.size, n))
    for lo, hi in zip(edges[:-1], edges[1:]):
        sol = solve_ivp(rhs, (lo, hi), state, method="DOP853", rtol=1e-12, atol=1e-15, dense_output=True)
        inside = (t >= lo - 1e-12) & (t <= hi + 1e-12)
        y = sol.sol(t[inside])
        x[inside], v[inside] = y[:n].T, y[n:].T
        state = sol.y[:, -1]
    u = np.array([force(tt) for tt in t])
    eps = 1e-9
    for b in breaks:
        at = np.isclose(t, b, rtol=0, atol=1e-12)
        if at.any():
            u[at] = 0.5 * (force(b - eps) + force(b + eps))
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
