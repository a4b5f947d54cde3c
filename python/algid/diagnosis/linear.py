"""The linear chain on windows: cross-validated fit, state reconstruction, per-window fits."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .equations import force_form, linear_design, target, to_physical
from .gram import CVResult, EqSpec, cross_validate, solve_gram, window_stats
from .windows import Prepared, detrend, window_lines


@dataclass
class LinearFit:
    """Linear chain fitted by windowed equation error.

    Attributes
    ----------
    theta_a : list of (p_e,) parameters of each equation as fitted (acceleration form
        ``[1/m, c/m, k_j/m ...]``, or ``[m, c, k_j ...]`` for a force-form equation).
    theta : list of physical ``[m, c, k_j ...]`` per DOF equation (per unit mass,
        ``m = 1``, for an unforced DOF).
    names : parameter names per equation (``m, c, k<j>``).
    forced : (n,) which DOFs carry a force.
    cv : cross-validated stacked fit (all equations, acceleration units).
    x, v : (N, n) reconstructed displacements [m] and velocities [m/s].
    resid : (N, n) in-sample detrended equation errors in the units of each equation's
        target (:func:`.equations.target`: m/s^2, or N for a force-form equation).
    resid_force : the same in force units [N] (per unit mass for an unforced DOF).
    """

    theta_a: list[np.ndarray]
    theta: list[np.ndarray]
    names: list[list[str]]
    forced: np.ndarray
    cv: CVResult
    x: np.ndarray
    v: np.ndarray
    resid: np.ndarray
    resid_force: np.ndarray = None
    n_springs: int | None = None  # springs in the packed vector (n + 1 for the chain)
    chain: bool = True

    @property
    def mass(self) -> np.ndarray:
        """(n,) masses [kg] (1 for an unforced DOF: its parameters are per unit mass)."""
        return np.array([th[0] for th in self.theta])

    def damping(self) -> np.ndarray:
        """(n,) dampings [N s/m]."""
        return np.array([th[1] for th in self.theta])

    def stiffness(self) -> np.ndarray:
        """(n+1,) spring stiffnesses [N/m] (a network's (S,), in its spring order); springs
        in two equations fused (their mean); n = 1: the identified sum in k1, NaN in k2; free
        end: k_{n+1} = 0; the second of springs in parallel NaN."""
        n = len(self.theta)
        vals: dict[int, list[float]] = {}
        for th, nm in zip(self.theta, self.names):
            for value, name in zip(th[2:], nm[2:]):
                vals.setdefault(int(name[1:]), []).append(float(value))
        out = np.full(self.n_springs or n + 1, np.nan)
        for j, vs in vals.items():
            out[j - 1] = float(np.mean(vs))
        if self.chain and n > 1 and (n + 1) not in vals:
            out[n] = 0.0
        return out


def linear_specs(P: Prepared) -> list[EqSpec]:
    """One :class:`EqSpec` per DOF: the acceleration equation on the raw integrals."""
    return [EqSpec(e=e, X=linear_design(P, e), y=target(P, e), E=None, key=("base", e)) for e in range(P.n)]


def stiffness_rows(P: Prepared, theta_a: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Row-wise ``K`` and ``C`` in each equation's own units (``M^-1 K``, ``M^-1 C`` for an
    acceleration-form equation, ``K``, ``C`` for a force-form one), each row from its own
    equation: the parameters after the first (1/m or m) of a forced equation."""
    n = P.n
    K = np.zeros((n, n))
    C = np.zeros((n, n))
    for e, th in enumerate(theta_a):
        off = 1 if P.forced[e] else 0
        C[e, e] = th[off]
        for (_j, other), k in zip(P.columns[e], th[off + 1 :]):
            K[e, e] += k
            if other >= 0:
                K[e, other] -= k
    return K, C


def reconstruct_states(
    P: Prepared,
    theta_a: list[np.ndarray],
    raw_resid: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Velocities and displacements from the integrals and the per-window lines of the
    raw equation errors (in each equation's target units, like the rows of
    :func:`stiffness_rows`).

    On window w, ``v = A1 + p`` and ``x = A2 + q + p tau``; substituted in eq. 1 the
    unknown constants leave ``-(C p + K q + K p tau)`` (row-scaled by ``M^-1``) in the raw
    acceleration errors, so the line ``alpha + beta tau`` fitted to them gives
    ``p = -K^-1 beta`` and ``q = -K^-1 (alpha + C p)``.
    """
    K, C = stiffness_rows(P, theta_a)
    # a force-form error is u - (m a + c v + k x): the constants enter with the other sign
    sign = np.array([1.0 if force_form(P, e) else -1.0 for e in range(P.n)])
    alpha, beta = window_lines(P, -sign[None, :] * raw_resid)  # (nw, n)
    try:
        p = -np.linalg.solve(K, beta.T).T
        q = -np.linalg.solve(K, (alpha + p @ C.T).T).T
    except np.linalg.LinAlgError:
        p = np.zeros_like(beta)
        q = np.zeros_like(alpha)
    v = P.windows(P.A1) + p[:, None, :]
    x = P.windows(P.A2) + q[:, None, :] + p[:, None, :] * P.tau[None, :, None]
    N = P.nw * P.L
    return x.reshape(N, P.n), v.reshape(N, P.n)


def fit_linear(P: Prepared) -> LinearFit:
    """Cross-validated linear fit of every DOF equation and the reconstructed states."""
    specs = linear_specs(P)
    cv = cross_validate(P, window_stats(P, specs))
    theta_a = [cv.theta[s] for s in cv.stats.slices]
    raw = np.stack([s.y - s.X @ th for s, th in zip(specs, theta_a)], axis=1)
    x, v = reconstruct_states(P, theta_a, raw)
    theta = [to_physical(P, e, th) for e, th in enumerate(theta_a)]
    resid = detrend(P, raw).reshape(raw.shape)
    names = [["m", "c"] + [f"k{s}" for s, _ in P.columns[e]] for e in range(P.n)]
    return LinearFit(
        theta_a=theta_a,
        theta=theta,
        names=names,
        forced=P.forced.copy(),
        cv=cv,
        x=x,
        v=v,
        resid=resid,
        resid_force=resid * force_scale(P, theta)[None, :],
        n_springs=P.n_springs,
        chain=P.chain,
    )


def force_scale(P: Prepared, theta: list[np.ndarray]) -> np.ndarray:
    """(n,) factor from each equation's target units to force units: its mass for an
    acceleration-form forced equation, 1 for a force-form one (and for an unforced DOF,
    whose equation is per unit mass)."""
    return np.array([th[0] if P.forced[e] and P.form != "force" else 1.0 for e, th in enumerate(theta)])


def per_window_fits(P: Prepared, fit: LinearFit) -> list[np.ndarray]:
    """Physical linear parameters fitted on every window alone: list over DOF of (nw, p_e)."""
    st = fit.cv.stats
    out = []
    for k, sl in enumerate(st.slices):
        G = st.eq_gram(k)  # (nw, m, m) over the equation's parameters, the shared ones and the target
        idx = np.r_[np.arange(sl.stop - sl.start), G.shape[-1] - 1]
        th = solve_gram(G[:, idx[:, None], idx[None, :]])
        out.append(np.array([to_physical(P, k, t) for t in th]))
    return out
