"""Force pieces: the force over every sample interval as a cubic in the local time
``tau`` (coefficients ``c[..., j, :]`` of ``tau^j``), as recorded (held, interpolated or
sampled from a callable) and as applied to each DOF behind its input delay."""

from __future__ import annotations

import numpy as np

from .inputs import RunInputs

__all__ = ["InputRouting", "peval", "recorded_pieces", "shift"]


def shift(c: np.ndarray, tau0: float | np.ndarray) -> np.ndarray:
    """Re-expand cubic pieces ``c[..., j, :]`` (coefficient of ``tau^j``) about ``tau0``."""
    c0, c1, c2, c3 = c[..., 0, :], c[..., 1, :], c[..., 2, :], c[..., 3, :]
    return np.stack(
        [
            c0 + tau0 * (c1 + tau0 * (c2 + tau0 * c3)),
            c1 + tau0 * (2.0 * c2 + 3.0 * tau0 * c3),
            c2 + 3.0 * tau0 * c3,
            c3,
        ],
        axis=-2,
    )


def peval(c: np.ndarray, tau: float) -> np.ndarray:
    """Value of cubic pieces ``c[..., 4, n]`` at local time ``tau``."""
    return c[..., 0, :] + tau * (c[..., 1, :] + tau * (c[..., 2, :] + tau * c[..., 3, :]))


def recorded_pieces(inp: RunInputs) -> np.ndarray:
    """Recorded force pieces (T, 4, n) of an open loop: ``rec[k, j]`` is the coefficient
    of ``tau^j`` on ``[t_k, t_{k+1})``. Sampled mode holds the samples; continuous mode
    interpolates an array (cubic spline or linear) or fits a cubic through a callable's
    values at the thirds of every interval."""
    T, n = inp.T, inp.n
    rec = np.zeros((T, 4, n))
    U, f_call = inp.force_samples, inp.force_fn
    if inp.mode == "sampled":
        if U is not None:
            rec[:, 0] = U
        elif f_call is not None:
            rec[:, 0] = [np.asarray(f_call(tk), dtype=float).reshape(n) for tk in inp.t]
    elif U is not None:
        _interpolated(rec, inp.t, U, inp.h, inp.force_interp)
    elif f_call is not None:
        rec = _cubic_through_thirds(f_call, T, n, inp.h)
    return rec


def _interpolated(rec: np.ndarray, t: np.ndarray, U: np.ndarray, h: float, force_interp: str) -> None:
    """Fill ``rec`` with the pieces of a C2 not-a-knot cubic spline through the samples
    ``U`` (``force_interp="cubic"``, at least 4 samples) or of the polygon through them;
    the last interval continues the piece before it."""
    T = U.shape[0]
    if force_interp == "cubic" and T >= 4:
        from scipy.interpolate import CubicSpline

        cs = CubicSpline(t, U, axis=0, bc_type="not-a-knot")
        rec[:-1] = np.transpose(cs.c[::-1], (1, 0, 2))
    else:
        rec[:-1, 0] = U[:-1]
        rec[:-1, 1] = (U[1:] - U[:-1]) / h
    rec[-1] = shift(rec[-2], h)


def _cubic_through_thirds(f_call, T: int, n: int, h: float) -> np.ndarray:
    """Pieces (T, 4, n) of the cubics through ``f(t)`` at ``t_k + (0, 1, 2, 3) h / 3``."""
    tn = np.arange(3 * T + 1) * (h / 3.0)
    vals = np.array([np.asarray(f_call(tt), dtype=float).reshape(n) for tt in tn])
    nodes = np.arange(4) * (h / 3.0)
    Vinv = np.linalg.inv(nodes[:, None] ** np.arange(4)[None, :])
    idx = 3 * np.arange(T)[:, None] + np.arange(4)[None, :]
    return np.einsum("jq,kqn->kjn", Vinv, vals[idx])


class InputRouting:
    """What reaches each DOF on each sub-interval of a sample interval: the recorded force
    of an earlier interval when the DOF has an input delay.

    Sub-interval ``q`` of interval ``k`` (starting at the fraction ``bounds[q]`` of it)
    reads DOF ``i``'s recorded piece of interval ``k + offset[q, i]`` from its local time
    ``tau[q, i]`` [s]; before ``t = 0`` the recorded force is zero.
    """

    def __init__(self, bounds: list[float], delays_s: np.ndarray, fs_hz: float, h: float) -> None:
        J, n = len(bounds) - 1, delays_s.size
        self.offset = np.zeros((J, n), dtype=int)
        self.tau = np.zeros((J, n))
        for q in range(J):
            sq = bounds[q] - delays_s * fs_hz
            j0 = np.floor(sq + 1e-7).astype(int)
            self.offset[q] = j0
            self.tau[q] = np.maximum(sq - j0, 0.0) * h

    def applied_pieces(self, recp: np.ndarray) -> np.ndarray:
        """(T, J, 4, n) applied pieces from recorded pieces (T, 4, n)."""
        J, n = self.offset.shape
        out = np.zeros((recp.shape[0], J, 4, n))
        kk = np.arange(recp.shape[0])
        for q in range(J):
            for i in range(n):
                src = kk + self.offset[q, i]
                ok = src >= 0
                out[ok, q, :, i] = shift(recp[src[ok], :, i : i + 1], self.tau[q, i])[..., 0]
        return out

    def held(self, history: np.ndarray, k: int) -> np.ndarray:
        """(J, n) held forces [N] applied on the sub-intervals of interval ``k``, from the
        commands held so far ``history`` (T, n)."""
        J, n = self.offset.shape
        T = history.shape[0]
        app_q = np.empty((J, n))
        for q in range(J):
            src = k + self.offset[q]
            app_q[q] = np.where(src >= 0, history[np.clip(src, 0, T - 1), np.arange(n)], 0.0)
        return app_q
