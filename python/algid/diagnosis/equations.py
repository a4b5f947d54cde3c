"""The linear equation of every DOF on the windows: its target (acceleration or force),
its columns and the conversions of its parameters to physical units."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .windows import Prepared

__all__ = [
    "base_design",
    "effect_column",
    "force_form",
    "linear_design",
    "target",
    "to_acceleration_form",
    "to_physical",
]


def force_form(P: Prepared, e: int) -> bool:
    """Is equation ``e`` solved for the force (a forced DOF of a force-form analysis)?"""
    return P.form == "force" and bool(P.forced[e])


def target(P: Prepared, e: int, a: np.ndarray | None = None, u: np.ndarray | None = None) -> np.ndarray:
    """The target of equation ``e``: the force ``u_e`` [N] in the force form, else the
    acceleration ``a_e`` [m/s^2]; ``a``, ``u`` (N,) replace the recorded column."""
    if force_form(P, e):
        return P.u[:, e] if u is None else u
    return P.a[:, e] if a is None else a


def base_design(
    P: Prepared, e: int, v: np.ndarray, x: np.ndarray, u: np.ndarray | None = None, a: np.ndarray | None = None
) -> np.ndarray:
    """Columns of the linear equation of DOF ``e``.

    Acceleration form (target ``a_e``): ``[u_e, -v_e, -(x_e - x_other) ...]`` (the force
    column only for a forced DOF), parameters ``[1/m, c/m, k_j/m ...]``. Force form
    (target ``u_e``, forced DOF): ``[a_e, v_e, x_e - x_other ...]``, parameters
    ``[m, c, k_j ...]``. ``u``, ``a`` (N,) replace the recorded force or acceleration
    column."""
    if force_form(P, e):
        cols = [P.a[:, e] if a is None else a, v[:, e]]
        sign = 1.0
    else:
        cols = [P.u[:, e] if u is None else u] if P.forced[e] else []
        cols.append(-v[:, e])
        sign = -1.0
    for _j, other in P.columns[e]:
        cols.append(sign * (x[:, e] - (x[:, other] if other >= 0 else 0.0)))
    return np.stack(cols, axis=1)


def linear_design(P: Prepared, e: int) -> np.ndarray:
    """:func:`base_design` of equation ``e`` on the recorded states (``P.A1``, ``P.A2``),
    computed once per :class:`Prepared` and shared, read-only, by every model that uses it
    (dozens of candidates would otherwise hold a copy each)."""
    key = ("linear_design", e)
    X = P._cache.get(key)
    if X is None:
        X = base_design(P, e, P.A1, P.A2)
        X.flags.writeable = False
        P._cache[key] = X
    return X


def effect_column(P: Prepared, e: int, g: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """Column of an effect force ``g`` [N per unit parameter] in equation ``e``
    (eq. 1 read as ``m a + c v + k x + g = u``): ``g`` in the force form, ``-g / m_e`` in
    the acceleration form (``m_e`` from the linear fit), so that its coefficient is the
    effect's physical parameter either way."""
    return g if force_form(P, e) else -g / mass[e]


def to_physical(P: Prepared, e: int, th: np.ndarray) -> np.ndarray:
    """``[m, c, k_j ...]`` from the parameters of equation ``e`` (``m = 1``, i.e. per
    unit mass, for an unforced DOF)."""
    th = np.asarray(th, dtype=float)
    if force_form(P, e):
        return th.copy()
    if not P.forced[e]:
        return np.concatenate([[1.0], th])
    m = 1.0 / th[0]
    return np.concatenate([[m], th[1:] * m])


def to_acceleration_form(P: Prepared, e: int, th: np.ndarray) -> np.ndarray:
    """The acceleration-form parameters ``[1/m, c/m, k_j/m ...]`` of equation ``e`` (the
    parameters as they are for an unforced DOF or an acceleration-form analysis)."""
    th = np.asarray(th, dtype=float)
    if not force_form(P, e):
        return th
    return np.concatenate([[1.0 / th[0]], th[1:] / th[0]])
