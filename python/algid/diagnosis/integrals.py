"""The single and double integrals ``A1 = int a`` and ``A2 = int int a`` of the measured
accelerations from the first sample (the estimator's interpolatory quadrature)."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..estimator.quadrature import quadrature_weights

__all__ = ["QUAD_POINTS", "integrals"]

#: Quadrature points of the integrals A1, A2 (as the estimator's default).
QUAD_POINTS = 6


@lru_cache(maxsize=4)
def _weights(points: int) -> np.ndarray:
    return quadrature_weights(points, 2)


def integrals(a: np.ndarray, dt: float, points: int = QUAD_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """``(int a, int int a)`` from the first sample for every column of ``a`` (T, c).

    The estimator's quadrature (:mod:`algid.estimator.quadrature`: on every interval the
    degree ``points-1`` interpolant through the nearest samples, integrated exactly),
    vectorised over columns.
    """
    a = np.asarray(a, dtype=float)
    T = a.shape[0]
    if T < points:
        raise ValueError(f"need at least {points} samples")
    W = _weights(points)
    half = points // 2
    j = np.arange(T - 1)
    start = np.clip(j - (half - 1), 0, T - points)
    off = j - start
    stencil = a[start[:, None] + np.arange(points)[None, :]]  # (T-1, points, c)
    inc1 = dt * np.einsum("jm,jmc->jc", W[off, 0], stencil)
    inc2 = dt**2 * np.einsum("jm,jmc->jc", W[off, 1], stencil)
    A1 = np.zeros_like(a)
    A2 = np.zeros_like(a)
    A1[1:] = np.cumsum(inc1, axis=0)
    A2[1:] = np.cumsum(inc2 + dt * A1[:-1], axis=0)
    return A1, A2
