"""Weights of the estimator's interpolatory quadrature (the library's one implementation in
numpy; the C++ core computes the same rule in ``cpp/include/algid/quadrature.hpp``).

On every sample interval the signal is replaced by the degree ``points-1`` polynomial through
``points`` consecutive samples, and the iterated integrals are advanced exactly for it. Used by
the diagnosis's integrals (:mod:`algid.diagnosis.integrals`) and by the tests' numpy oracle
(:mod:`algid.estimator.reference`).
"""

from __future__ import annotations

from functools import cache
from math import factorial

import numpy as np

__all__ = ["MAX_ORDER", "quadrature_weights"]

#: Highest iterated-integral order eqs. 4-6 need of a ``Delta^p``-weighted signal (row 4 of
#: a_13: I^3 of I^2); through the identity that is order ``MAX_ORDER + 2`` of the signal.
MAX_ORDER = 5


@cache
def quadrature_weights(points: int, max_order: int = MAX_ORDER) -> np.ndarray:
    """Weights ``W[off, r-1, m]`` (shape ``(points-1, max_order, points)``).

    ``int_{j}^{j+1} (j+1-s)^(r-1)/(r-1)! p(s) ds = h^r sum_m W[off, r-1, m] f_{j-off+m}``
    for the interpolant ``p`` through nodes ``j-off .. j-off+points-1`` (unit spacing).
    """
    if points < 2 or points % 2:
        raise ValueError("points must be even and >= 2")
    nodes = np.arange(points, dtype=float)
    W = np.zeros((points - 1, max_order, points))
    for off in range(points - 1):
        for m in range(points):
            # Lagrange basis L_m(s) as a polynomial in local x = s - off in [0, 1].
            others = np.delete(nodes, m) - off
            L = np.poly1d(np.poly(others)) / np.prod(nodes[m] - np.delete(nodes, m))
            for r in range(1, max_order + 1):
                kernel = np.poly1d([-1.0, 1.0]) ** (r - 1) / factorial(r - 1)  # (1-x)^(r-1)/(r-1)!
                P = np.polyint(L * kernel)
                W[off, r - 1, m] = P(1.0) - P(0.0)
    W.setflags(write=False)  # cached: shared by every call
    return W
