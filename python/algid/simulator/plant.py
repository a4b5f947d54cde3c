"""The plant of eq. 1: its linear part (masses, dampers, springs) and the forces of the
switched-on mechanical effects, in the integrator's scalar form and vectorised over a record."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..model.chain import Chain
from ..model.network import NetworkModel
from .effects import COULOMB_V_EPS, Effect, as_effect

__all__ = ["Plant", "effect_forces"]


class Plant:
    """Linear part of eq. 1 and the effect forces."""

    def _effect_force_1(self, t: float, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """:meth:`effect_force` for one state, in scalar arithmetic."""
        return self.state_force(t, np.concatenate((x, v)))

    def state_force(self, t: float, state: np.ndarray) -> np.ndarray:
        """Effect forces [N] from a state vector starting ``[x, v, ..]`` (the integrator's
        hot path: plain float arithmetic, faster than numpy on a few entries)."""
        n = self.n
        vals = state.tolist()
        xs = vals[:n]
        vs = vals[n : 2 * n]
        f = [0.0] * n
        for kind, i, a, fs, vs_, eps in self.dof_terms:
            vi = vs[i]
            if kind == "fo":
                f[i] += a
            elif kind == "cf":
                level = a if fs == a else a + (fs - a) * math.exp(-((vi / vs_) ** 2))
                f[i] -= level * math.tanh(vi / eps)
            else:
                f[i] -= a * vi * abs(vi)
        for kind, j, a, b in self.spring_terms:  # spring j (0-based) joins DOF lo and DOF hi
            lo, hi = self.ends[j]
            d = (xs[hi] if hi >= 0 else 0.0) - (xs[lo] if lo >= 0 else 0.0)
            if kind == "cs":
                s = a * d * d * d
            elif kind == "cl":
                ad = abs(d) - a
                s = b * ad * (1.0 if d > 0 else -1.0) if ad > 0 else 0.0
            elif kind == "ad":
                dd = (vs[hi] if hi >= 0 else 0.0) - (vs[lo] if lo >= 0 else 0.0)
                s = a * abs(d) * dd
            else:
                s = a * t * d
            if hi >= 0:
                f[hi] -= s
            if lo >= 0:
                f[lo] += s
        return np.array(f)

    def __init__(
        self, chain: Chain | NetworkModel, effects: Sequence[Effect], duration_s: float, v_eps: dict[int, float]
    ) -> None:
        _, _, K = chain.matrices()
        self.n = chain.n
        self.minv = 1.0 / chain.mass
        self.c = chain.damping.copy()
        self.K = K
        D = chain.deformation_matrix()  # d = D x, d_s = x_hi - x_lo (ground 0)
        self.D = D
        #: (lo, hi) 0-based DOFs of every spring, -1 for ground
        self.ends = spring_ends(D)
        # (kind, dof, level, static level, Stribeck velocity, regularisation velocity)
        self.dof_terms: list[tuple[str, int, float, float, float, float]] = []
        for q, e in enumerate(effects):
            p = e.params
            if e.name == "coulomb_friction":
                self.dof_terms.append(("cf", e.dof, p["force"], p["force"], 1.0, v_eps[q]))
            elif e.name == "stribeck_friction":
                self.dof_terms.append(("cf", e.dof, p["force"], p["static"], p["v_stribeck"], v_eps[q]))
            elif e.name == "quadratic_damping":
                self.dof_terms.append(("qd", e.dof, p["c_quadratic"], 0.0, 0.0, 0.0))
            elif e.name == "force_offset":
                self.dof_terms.append(("fo", e.dof, p["offset"], 0.0, 0.0, 0.0))

        def rows(kind: str) -> tuple[np.ndarray | None, list[Effect]]:
            sel = [e for e in effects if e.name == kind]
            return (D[[e.spring - 1 for e in sel]] if sel else None), sel

        self.cs_D, cs = rows("cubic_stiffness")
        self.cs_k3 = np.array([e.params["k_cubic"] for e in cs])
        self.cl_D, cl = rows("clearance")
        self.cl_gap = np.array([e.params["gap"] for e in cl])
        self.cl_k = np.array([e.params["k_contact"] for e in cl])
        self.dr_D, dr = rows("parameter_drift")
        self.dr_rate = np.array([chain.stiffness[e.spring - 1] * e.params["rel_change"] / duration_s for e in dr])
        self.ad_D, ad = rows("amplitude_damping")
        self.ad_c = np.array([e.params["c_amp"] for e in ad])
        self.spring_terms: list[tuple[str, int, float, float]] = (
            [("cs", e.spring - 1, e.params["k_cubic"], 0.0) for e in cs]
            + [("cl", e.spring - 1, e.params["gap"], e.params["k_contact"]) for e in cl]
            + [("dr", e.spring - 1, r, 0.0) for e, r in zip(dr, self.dr_rate)]
            + [("ad", e.spring - 1, e.params["c_amp"], 0.0) for e in ad]
        )
        self.nonlinear = bool(self.dof_terms or cs or cl or dr or ad)
        self.has_switches = bool(cl) or any(kind == "cf" for kind, *_ in self.dof_terms)

    def switch_state(self, state: np.ndarray) -> tuple:
        """Which side of its switch every steep effect is on: the sign of each dry-friction
        velocity and whether each clearance contact is engaged (a change within a step
        makes the integrator redo that step with finer sub-steps)."""
        n = self.n
        vals = state.tolist()
        out = [vals[n + i] > 0.0 for kind, i, *_ in self.dof_terms if kind == "cf"]
        for kind, j, gap, _ in self.spring_terms:
            if kind == "cl":
                lo, hi = self.ends[j]
                d = (vals[hi] if hi >= 0 else 0.0) - (vals[lo] if lo >= 0 else 0.0)
                out.append(abs(d) > gap)
        return tuple(out)

    def effect_force(self, t: float | np.ndarray, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Sum of the effect forces [N] on each mass; ``x, v`` (n,) or (T, n) with ``t``
        scalar or (T,)."""
        if np.ndim(x) == 1:
            return self._effect_force_1(t, x, v)
        f = np.zeros(np.shape(x))
        for kind, i, a, fs, vs_, eps in self.dof_terms:
            vi = v[..., i]
            if kind == "fo":
                f[..., i] += a
            elif kind == "cf":
                f[..., i] -= (a + (fs - a) * np.exp(-((vi / vs_) ** 2))) * np.tanh(vi / eps)
            else:
                f[..., i] -= a * vi * np.abs(vi)
        if self.cs_D is not None:
            d = x @ self.cs_D.T
            f -= (self.cs_k3 * d * d * d) @ self.cs_D
        if self.cl_D is not None:
            d = x @ self.cl_D.T
            f -= (self.cl_k * np.maximum(np.abs(d) - self.cl_gap, 0.0) * np.sign(d)) @ self.cl_D
        if self.dr_D is not None:
            d = x @ self.dr_D.T
            tt = np.asarray(t)[..., None] if np.ndim(t) else t
            f -= (self.dr_rate * tt * d) @ self.dr_D
        if self.ad_D is not None:
            d, dd = x @ self.ad_D.T, v @ self.ad_D.T
            f -= (self.ad_c * np.abs(d) * dd) @ self.ad_D
        return f


def spring_ends(D: np.ndarray) -> list[tuple[int, int]]:
    """``(lo, hi)`` per spring from the deformation matrix ``D`` (S, n): ``d_s = x_hi - x_lo``,
    0-based DOFs, -1 for ground."""
    return [(int(np.argmin(r)) if r.min() < 0 else -1, int(np.argmax(r)) if r.max() > 0 else -1) for r in D]


def effect_forces(
    chain: Chain,
    effects: Sequence[Effect | Mapping[str, Any]],
    t: np.ndarray,
    x: np.ndarray,
    v: np.ndarray,
    duration_s: float | None = None,
) -> np.ndarray:
    """The forces [N] (T, n) the effects put on the masses along a prescribed motion
    ``x`` [m], ``v`` [m/s] (T, n) at times ``t`` [s] (T,): what the simulator adds to eq. 1.
    A device driven in displacement needs ``M a + C v + K x - effect_forces(...)`` from its
    actuator. Dry friction uses ``v_eps`` if given, else ``COULOMB_V_EPS``."""
    effs = tuple(as_effect(e) for e in effects)
    for e in effs:
        e.check(chain)
    duration = float(t[-1] - t[0]) if duration_s is None else float(duration_s)
    v_eps = {
        q: e.params.get("v_eps", COULOMB_V_EPS)
        for q, e in enumerate(effs)
        if e.name in ("coulomb_friction", "stribeck_friction")
    }
    return Plant(chain, effs, duration, v_eps).effect_force(
        np.asarray(t, dtype=float), np.asarray(x, dtype=float), np.asarray(v, dtype=float)
    )
