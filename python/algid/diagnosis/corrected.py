"""The chain with the diagnosed effect in it: the model a user takes away from a diagnosis.

The reported candidate was fitted as eq. 1 plus the effect's columns on the equations it enters
(:mod:`.candidates`), cross-validated over the folds; its chain parameters are the corrected
ones for those equations, the linear fit's for the others (the effect does not enter them).
Physical units per equation (:func:`.equations.to_physical`); an interior spring estimated in
two forced equations is their inverse-variance weighted mean (an effect on one of them leaves
that equation's estimate the less certain). A DOF without force has no scale
here (its parameters are per unit mass): its mass and damping are ``None`` and its springs
come from a forced neighbour's equation only. Standard deviations: the delete-a-group
jackknife over the folds' fits, the spread the effect's parameters are given.

A spring network's linear model (:func:`network_model`) is the joint fit of all its DOF
equations instead (:mod:`.joint`): each spring one unknown of both equations it enters, which
also scales a DOF without force along its springs.
"""

from __future__ import annotations

import numpy as np

from .equations import to_physical
from .gram import jackknife_std
from .joint import joint_fit


def _physical(P, eqs: list[int], cv) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Equation -> (physical parameters (p,), per-fold physical parameters (K, p))."""
    return {
        e: (to_physical(P, e, cv.theta[sl]), np.array([to_physical(P, e, f[sl]) for f in cv.theta_folds]))
        for e, sl in zip(eqs, cv.stats.slices)
    }


def _packed(P, names: list[list[str]], thetas: dict[int, np.ndarray], var: dict[int, np.ndarray]) -> np.ndarray:
    """``m1..mn, c1..cn, k1..k{n+1}`` from per-equation physical parameters, an interior
    spring the mean of its equations' estimates weighted by ``1 / var`` (NaN where no forced
    equation holds the parameter; free end ``k{n+1} = 0``)."""
    n = P.n
    out = np.full(2 * n + P.n_springs, np.nan)
    springs: dict[int, list[tuple[float, float]]] = {}
    for e, th in thetas.items():
        if not P.forced[e]:
            continue
        out[e], out[n + e] = th[0], th[1]
        for name, value, v in zip(names[e][2:], th[2:], var[e][2:]):
            springs.setdefault(int(name[1:]), []).append((float(value), 1.0 / max(float(v), 1e-300)))
    for j, pairs in springs.items():
        values, weights = np.array(pairs).T
        out[2 * n + j - 1] = float(np.sum(values * weights) / np.sum(weights))
    if P.chain and P.boundary == "free" and n > 1:
        out[3 * n] = 0.0
    return out


def _listed(x: np.ndarray) -> list:
    return [float(v) if np.isfinite(v) else None for v in x]


def _as_dict(P, theta: np.ndarray, sigma: np.ndarray) -> dict:
    """Packed parameters and standard deviations as :meth:`algid.Chain.from_json` reads them
    (``springs`` in place of ``boundary`` for a network; ``None`` where NaN)."""
    n = P.n
    return {
        "n": n,
        **({"boundary": P.boundary} if P.chain else {"springs": [list(p) for p in P.network.springs]}),
        "mass": _listed(theta[:n]),
        "damping": _listed(theta[n : 2 * n]),
        "stiffness": _listed(theta[2 * n :]),
        "sigma_mass": _listed(sigma[:n]),
        "sigma_damping": _listed(sigma[n : 2 * n]),
        "sigma_stiffness": _listed(sigma[2 * n :]),
    }


def effect_parts(effect: str, location: dict, params: dict, params_std: dict) -> list[dict]:
    """A reported effect as a list of ``{effect, location, params, params_std}``, one per part
    of a combination (``a+b``, whose location holds ``parts`` and params one dict per effect)."""
    if "+" not in effect:
        return [{"effect": effect, "location": location, "params": params, "params_std": params_std}]
    return [
        {"effect": e, "location": loc, "params": params[e], "params_std": params_std[e]}
        for e, loc in zip(effect.split("+"), location["parts"])
    ]


def chain_model(d, fit=None) -> dict:
    """The chain of the diagnosis's linear fit, with ``fit``'s equations (a candidate's,
    cross-validated) in place of the linear ones it refits, as a dict that
    :meth:`algid.Chain.from_json` reads (a network's: :meth:`algid.NetworkModel.from_json`, with
    ``springs`` in place of ``boundary``): ``n, boundary, mass, damping, stiffness`` (``None``
    where the record gives no scale) and their ``sigma_*`` (module docstring)."""
    P, lin = d.P, d.lin
    per_eq = _physical(P, list(range(P.n)), lin.cv)
    if fit is not None:
        per_eq.update(_physical(P, fit.eqs, fit.cv))
    var = {e: jackknife_std(v[1]) ** 2 for e, v in per_eq.items()}
    theta = _packed(P, lin.names, {e: v[0] for e, v in per_eq.items()}, var)
    K = len(next(iter(per_eq.values()))[1])
    folds = np.array([_packed(P, lin.names, {e: v[1][k] for e, v in per_eq.items()}, var) for k in range(K)])
    return _as_dict(P, theta, jackknife_std(folds))


def network_model(d) -> dict:
    """The keys of :func:`chain_model` for a spring network (``springs`` in place of
    ``boundary``) from the joint fit of its equations (:func:`.joint.joint_fit`): every spring
    one unknown of both DOFs it joins, a DOF without force scaled along its springs."""
    return _as_dict(d.P, *joint_fit(d.P, d.lin.cv))


def linear_model(d) -> dict:
    """The one linear model of a record, whichever command prints it: the diagnosis's linear
    fit (:func:`chain_model` for the chain, :func:`network_model` for a network), its
    withheld gap ``gap``."""
    model = chain_model(d) if d.P.chain else network_model(d)
    return {**model, "effects": [], "gap": d.gap_before}


def corrected_model(d) -> dict | None:
    """The chain refitted with the effect :func:`~.engine.diagnose` reports (module
    docstring): :func:`chain_model` with the reported candidate's equations, the ``effects``
    (``effect, location, params, params_std``) and the withheld gap ``gap_after`` with them;
    ``None`` when no effect is reported."""
    if d.best is None:
        return None
    return {
        **chain_model(d, d.best.fit),
        "effects": effect_parts(d.effect, d.location, d.params, d.params_std),
        "gap_after": d.gap_after,
        "refitted_dofs": sorted(e + 1 for e in d.best.fit.eqs),
    }
