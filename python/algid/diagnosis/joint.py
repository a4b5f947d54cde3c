"""A spring network's linear parameters in one joint fit of all its DOF equations.

The diagnosis fits every DOF's windowed equation alone (:func:`.linear.fit_linear`). In a
network each spring enters the equations of both DOFs it joins, and a DOF without force gives
its equation per unit mass only; here every mass ``m_e``, damper ``c_e`` and spring ``k_s`` is
one unknown shared by all equations it enters, ``theta = (m, c, k)`` packed as
:meth:`~algid.model.network.Network.parameter_names`. Equation e's fitted parameters are
functions of them (:func:`.equations.to_physical` read backwards):

* acceleration form, forced DOF: ``phi_e = [1/m_e, c_e/m_e, k_s/m_e ...]``;
* acceleration form, unforced DOF: ``phi_e = [c_e/m_e, k_s/m_e ...]``;
* force form (forced DOF): ``phi_e = [m_e, c_e, k_s ...]``.

The fit minimises ``sum_e w_e |y_e - X_e phi_e(theta)|^2`` over the windows (each equation's
error as the diagnosis scores it, weighted by ``w_e = 1 / sigma_e^2``, its error variance per
sample under its own fit: a generalised least squares across equations of different noise),
by Gauss-Newton on the per-window Gram matrices the diagnosis has already built. It starts
from the same sum with every error in force units, ``m_e (y_e - X_e phi_e)``, which is linear
in ``theta``. A spring estimated in a forced DOF's equation and in an unforced one's fixes the
unforced DOF's mass, and so on along every path of springs, all in the one solve: one force
scales a whole connected network. A part of the network with no force and no spring path to
one has no scale: its first mass is held at 1 and its parameters are reported NaN (the reason
is :meth:`~algid.model.network.Network.identifiability`'s). Standard deviations: the
delete-a-group jackknife over the folds' refits (each fold's windows withheld).
"""

from __future__ import annotations

import numpy as np

from .equations import force_form
from .gram import jackknife_std, scaled_solve
from .windows import Prepared

#: Gauss-Newton stops when no free parameter moves by more than this fraction of itself.
STEP_TOL = 1e-12


def _equation_grams(P: Prepared, st) -> list[np.ndarray]:
    """Per equation, the per-window Gram (nw, p+1, p+1) over its columns and its target,
    the ones the diagnosis fitted (in band when it fits in band)."""
    blocks = st.blocks_band if P.fit_band and not P.full_band else st.blocks
    return [b.sum(axis=1) for b in blocks]


def _places(P: Prepared) -> list[np.ndarray]:
    """Per equation, the packed indices of ``m_e, c_e, k_s ...`` (its spring columns)."""
    n = P.n
    return [np.array([e, n + e] + [2 * n + s - 1 for s, _ in P.columns[e]]) for e in range(n)]


def _phi(P: Prepared, e: int, idx: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Equation ``e``'s fitted parameters ``phi_e(theta)`` (module docstring) and their
    Jacobian (p_e, size) in ``theta``."""
    v = theta[idx]
    if force_form(P, e):
        J = np.zeros((idx.size, theta.size))
        J[np.arange(idx.size), idx] = 1.0
        return v.copy(), J
    m, rest = v[0], v[1:]
    lead = 1 if P.forced[e] else 0  # the 1/m of the force column
    J = np.zeros((lead + rest.size, theta.size))
    J[lead:, idx[0]] = -rest / m**2
    J[np.arange(lead, lead + rest.size), idx[1:]] = 1.0 / m
    if lead:
        J[0, idx[0]] = -1.0 / m**2
        return np.r_[1.0 / m, rest / m], J
    return rest / m, J


def _force_units(P: Prepared, e: int, idx: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """``T, t`` with ``T theta + t = m_e [phi_e, -1]``: equation ``e``'s extended parameters in
    force units, affine in ``theta`` (``[1, c, k.., -m]``, ``[c, k.., -m]``, ``[m, c, k.., -1]``)."""
    if force_form(P, e):
        T = np.zeros((idx.size + 1, size))
        T[np.arange(idx.size), idx] = 1.0
        return T, np.r_[np.zeros(idx.size), -1.0]
    lead = 1 if P.forced[e] else 0
    T = np.zeros((lead + idx.size, size))
    T[np.arange(lead, lead + idx.size - 1), idx[1:]] = 1.0
    T[-1, idx[0]] = -1.0
    return T, np.r_[np.ones(lead), np.zeros(idx.size)]


def _start(P: Prepared, G: list, places: list, w: np.ndarray, theta: np.ndarray, free: np.ndarray) -> np.ndarray:
    """The force-unit least squares (module docstring): ``theta`` with its ``free`` entries
    solved, equation e weighted ``w_e`` (its error variance in force units)."""
    H = np.zeros((theta.size, theta.size))
    g = np.zeros(theta.size)
    for e, (Ge, idx) in enumerate(zip(G, places)):
        T, t = _force_units(P, e, idx, theta.size)
        H += w[e] * T.T @ Ge @ T
        g += w[e] * T.T @ Ge @ t
    out = theta.copy()
    out[free] = scaled_solve(H[np.ix_(free, free)], -g[free] - H[np.ix_(free, ~free)] @ theta[~free])
    return out


def _gauss_newton(P: Prepared, G: list, places: list, w: np.ndarray, theta: np.ndarray, free: np.ndarray, iters: int):
    """Gauss-Newton on ``sum_e w_e phi_e' G_e phi_e`` (extended by -1) from ``theta``."""
    for _ in range(iters):
        H = np.zeros((theta.size, theta.size))
        g = np.zeros(theta.size)
        for e, (Ge, idx) in enumerate(zip(G, places)):
            phi, J = _phi(P, e, idx, theta)
            A, b = Ge[:-1, :-1], Ge[:-1, -1]
            H += w[e] * J.T @ A @ J
            g += w[e] * J.T @ (A @ phi - b)
        step = -scaled_solve(H[np.ix_(free, free)], g[free])
        theta = theta.copy()
        theta[free] += step
        if np.all(np.abs(step) <= STEP_TOL * np.abs(theta[free])):
            break
    return theta


def _unscaled(P: Prepared) -> list[set[int]]:
    """The parts of the network (0-based DOFs) with no force nor a spring path to one."""
    forced = {int(i) for i in np.nonzero(P.forced)[0]}
    parts = P.network.components()
    return [{i - 1 for i in part} for part in parts if not {i - 1 for i in part} & forced]


def _error_variances(G: list, N: int) -> np.ndarray:
    """(n,) each equation's error variance per sample [target units^2] under its own least squares."""
    out = []
    for Ge in G:
        A, b = Ge[:-1, :-1], Ge[:-1, -1]
        out.append(max(float(Ge[-1, -1] - b @ scaled_solve(A, b)), 0.0) / N)
    return np.array(out)


def joint_fit(P: Prepared, cv) -> tuple[np.ndarray, np.ndarray]:
    """The packed ``theta = (m, c, k)`` of the joint fit (module docstring) of the linear fit
    ``cv`` (:class:`~.gram.CVResult` of :func:`.linear.fit_linear`) and its jackknife
    standard deviations; NaN where no equation holds a parameter (the second of springs in
    parallel) or the record gives it no scale."""
    n, size = P.n, 2 * P.n + P.n_springs
    places = _places(P)
    Gw = _equation_grams(P, cv.stats)
    G = [g.sum(axis=0) for g in Gw]
    var = _error_variances(G, P.nw * P.L)
    # an exact record's variances are rounding: held within 1e-12 of the largest
    w = 1.0 / np.maximum(var, 1e-12 * float(var.max())) if var.max() > 0 else np.ones(n)
    used = np.zeros(size, dtype=bool)
    used[np.concatenate(places)] = True
    free, theta = used.copy(), np.zeros(size)
    unscaled = _unscaled(P)
    for part in unscaled:
        free[min(part)], theta[min(part)] = False, 1.0
    own_mass = [
        1.0 / cv.theta[sl][0] if P.forced[e] and not force_form(P, e) else 1.0 for e, sl in enumerate(cv.stats.slices)
    ]
    theta = _start(P, G, places, w / np.square(own_mass), theta, free)
    theta = _gauss_newton(P, G, places, w, theta, free, 20)
    folds = np.array(
        [
            _gauss_newton(P, [Ge - g[P.folds == k].sum(axis=0) for Ge, g in zip(G, Gw)], places, w, theta, free, 5)
            for k in range(P.nfolds)
        ]
    )
    sigma = jackknife_std(folds)
    blind = ~used
    for part in unscaled:
        for e in part:
            blind[places[e]] = True
    theta[blind] = sigma[blind] = np.nan
    return theta, sigma
