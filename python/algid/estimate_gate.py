"""The estimate-acceptance gate of the tracking controller: which of the on-line
estimates the control law takes (the rules ``settled``, ``valid`` and ``sigma`` of
:mod:`algid.controller`), and the parameters accepted so far."""

from __future__ import annotations

import numpy as np

from .control_law import LawParameters

__all__ = ["ACCEPT_RULES", "EstimateGate"]

#: The acceptance rules.
ACCEPT_RULES = ("settled", "valid", "sigma")


class EstimateGate:
    """Takes the estimates of every DOF that passes the acceptance ``rule``.

    Parameters
    ----------
    n, boundary : the chain (the right spring is absent with a free end or n = 1).
    dt : sample interval [s].
    rule : one of :data:`ACCEPT_RULES`.
    settle_window_s, settle_tol : window [s] and largest relative change [-] of ``settled``.
    hold : keep the first accepted estimates.
    nominal_mass_kg : mass [kg] in use until a DOF's estimates are accepted (dampings and
        stiffnesses 0).
    """

    def __init__(
        self,
        n: int,
        boundary: str,
        dt: float,
        rule: str,
        settle_window_s: float,
        settle_tol: float,
        hold: bool,
        nominal_mass_kg: float,
    ) -> None:
        self.n, self.rule, self.hold, self.tol = n, rule, hold, settle_tol
        self.good_m = np.full(n, nominal_mass_kg)
        self.good_c = np.zeros(n)
        self.good_k = np.zeros(n + 1)
        #: DOFs whose estimates were taken at least once
        self.accepted = np.zeros(n, bool)
        #: sample of the first substitution (None before)
        self.first_accept: int | None = None
        self.window = max(2, int(round(settle_window_s / dt)))
        self._hist_m = np.zeros((self.window, n))
        self._hist_c = np.zeros((self.window, n))
        self._hist_k = np.zeros((self.window, n + 1))
        self._hist_n = 0
        self.k_right_absent = np.zeros(n, bool)
        self.k_right_absent[-1] = (boundary == "free") or n == 1
        self._packed: LawParameters | None = None

    def parameters(self) -> LawParameters:
        """The accepted parameters (packed once per change)."""
        if self._packed is None:
            self._packed = LawParameters.pack(self.good_m, self.good_c, self.good_k)
        return self._packed

    def offer(self, k: int, m: np.ndarray, c: np.ndarray, kk: np.ndarray, valid: np.ndarray) -> None:
        """Sample ``k``'s estimates (masses (n,), dampings (n,), springs (n+1,), valid
        flags (n,)): take those of every DOF that passes."""
        slot = k % self.window
        self._hist_m[slot], self._hist_c[slot], self._hist_k[slot] = m, c, kk
        self._hist_n = min(self._hist_n + 1, self.window)
        ok = self._passing(m, c, kk, valid)
        if self.rule != "valid" and self.first_accept is None and not np.all(ok):
            # the first substitution takes all DOFs together: a spring between an
            # accepted and a rejected DOF would otherwise get a half-garbage value
            return
        if self.hold and self.first_accept is not None:
            return
        if not np.any(ok):
            return
        self._take(k, ok, m, c, kk)

    def _passing(self, m: np.ndarray, c: np.ndarray, kk: np.ndarray, valid: np.ndarray) -> np.ndarray:
        """(n,) which DOFs pass the rule."""
        n = self.n
        k_left, k_right = kk[:n], kk[1:]
        # the structurally unidentifiable right spring (n = 1 with walls, free end) is NaN
        kr = np.where(np.isnan(k_right) & self.k_right_absent, 0.0, k_right)
        ok = valid & np.isfinite(m) & np.isfinite(c) & np.isfinite(k_left) & np.isfinite(kr) & (m > 0)
        if self.rule == "valid":
            return ok
        ok &= (c >= 0) & (k_left >= 0) & (kr >= 0)
        if self.rule == "sigma":
            return ok  # the estimator's valid flag carries the uncertainty test
        if self._hist_n < self.window:
            return np.zeros(n, bool)
        return ok & self._settled(m, c, kk, k_left + kr)

    def _settled(self, m: np.ndarray, c: np.ndarray, kk: np.ndarray, k_sum: np.ndarray) -> np.ndarray:
        """(n,) which DOFs changed by at most ``settle_tol`` over the window (dampings
        against at least 1 % of the critical damping)."""
        n, tol = self.n, self.tol
        c_floor = 0.01 * 2.0 * np.sqrt(np.abs(k_sum * m))  # 1 % of critical
        with np.errstate(invalid="ignore"):
            dm = np.max(np.abs(self._hist_m - m), axis=0) <= tol * np.abs(m)
            dc = np.max(np.abs(self._hist_c - c), axis=0) <= tol * np.maximum(np.abs(c), c_floor)
            dk = np.max(np.abs(self._hist_k - kk), axis=0)
            dk_ok = (dk <= tol * np.abs(kk)) | (np.isnan(kk) & np.append(np.zeros(n, bool), self.k_right_absent[-1]))
        return dm & dc & dk_ok[:n] & dk_ok[1:]

    def _take(self, k: int, ok: np.ndarray, m: np.ndarray, c: np.ndarray, kk: np.ndarray) -> None:
        self.good_m[ok] = m[ok]
        self.good_c[ok] = c[ok]
        self.accepted |= ok
        # a spring is estimated by the DOFs at its ends: take it from an accepted neighbour
        near = np.zeros(self.n + 1, bool)
        near[: self.n] |= ok
        near[1:] |= ok
        near &= np.isfinite(kk)
        self.good_k[near] = kk[near]
        self._packed = None
        if self.first_accept is None:
            self.first_accept = k
