"""The estimate-acceptance gate of the tracking controller: which of the on-line
estimates the control law takes (the rules ``settled``, ``valid``, ``sigma`` and
``better`` of :mod:`algid.control.controller`), and the parameters accepted so far.

``better`` never replaces accepted estimates by worse ones. Each DOF ``i`` keeps the
uncertainty ``s_i`` of its accepted estimates, the largest relative one-sigma uncertainty
of ``m_i, c_i, k_i, k_{i+1}``, and the *rank* of their source (0: a steadiness proxy such
as the growing window's, 1: a statistical uncertainty such as the continuous estimator's
running one). A DOF's new estimates that pass the ``sigma`` rule replace the accepted
ones when they come from a higher rank, or from the same rank with ``s_new <= s_i`` and
consistent with them: ``|theta_new - theta_acc| <= z sqrt(sigma_new^2 + sigma_acc^2)``
for each of the four (``z = consistency_z``, sigmas absolute). A better estimate that
stays inconsistent for ``confirm_s`` is taken too: the accepted one was off by more than
its uncertainty said (or the plant changed).
"""

from __future__ import annotations

import numpy as np

from .control_law import LawParameters

__all__ = ["ACCEPT_RULES", "EstimateGate"]

#: The acceptance rules.
ACCEPT_RULES = ("settled", "valid", "sigma", "better")


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
    consistency_z, confirm_s : the consistency bound [sigmas] and the time [s] after which a
        persistently inconsistent better estimate is taken (rule ``better``).
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
        consistency_z: float = 3.0,
        confirm_s: float = 0.2,
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
        self.z = float(consistency_z)
        self.confirm = max(1, int(round(confirm_s / dt)))
        #: rule ``better``: uncertainty [-] (n,), source rank (n,) and absolute sigmas
        #: (3n+1,) of the accepted estimates
        self.acc_s = np.full(n, np.inf)
        self.acc_rank = np.full(n, -1)
        self.acc_sigma = np.full(3 * n + 1, np.inf)
        self._inconsistent = np.zeros(n, int)  # samples a better estimate stayed inconsistent
        idx = np.arange(n)
        self._dof_params = np.stack([idx, n + idx, 2 * n + idx, 2 * n + idx + 1], axis=1)  # (n, 4)

    def parameters(self) -> LawParameters:
        """The accepted parameters (packed once per change)."""
        if self._packed is None:
            self._packed = LawParameters.pack(self.good_m, self.good_c, self.good_k)
        return self._packed

    def offer(
        self,
        k: int,
        m: np.ndarray,
        c: np.ndarray,
        kk: np.ndarray,
        valid: np.ndarray,
        uncertainty: tuple[np.ndarray, np.ndarray, int] | None = None,
    ) -> None:
        """Sample ``k``'s estimates (masses (n,), dampings (n,), springs (n+1,), valid
        flags (n,)): take those of every DOF that passes. ``uncertainty`` (rule
        ``better``): the estimates' relative and absolute one-sigma uncertainties (3n+1,)
        [-, their units] and the rank of their source."""
        slot = k % self.window
        self._hist_m[slot], self._hist_c[slot], self._hist_k[slot] = m, c, kk
        self._hist_n = min(self._hist_n + 1, self.window)
        ok = self._passing(m, c, kk, valid)
        if self.rule == "better" and uncertainty is not None:
            ok &= self._better(np.concatenate([m, c, kk]), *uncertainty)
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
        if self.rule in ("sigma", "better"):
            return ok  # the estimator's valid flag carries the uncertainty test
        if self._hist_n < self.window:
            return np.zeros(n, bool)
        return ok & self._settled(m, c, kk, k_left + kr)

    def _better(self, theta: np.ndarray, rel: np.ndarray, sigma: np.ndarray, rank: int) -> np.ndarray:
        """(n,) which DOFs' estimates ``theta`` (3n+1,) are no worse than the accepted ones
        (rule ``better``, see the module docstring); remembers their uncertainty for
        :meth:`_take`."""
        P = self._dof_params
        r = np.where(np.isfinite(rel), rel, np.inf)
        s_new = np.max(r[P], axis=1)
        with np.errstate(invalid="ignore"):
            good_theta = np.concatenate([self.good_m, self.good_c, self.good_k])
            bound = self.z * np.hypot(np.nan_to_num(sigma, nan=np.inf), self.acc_sigma)
            d = np.abs(np.nan_to_num(theta - good_theta))
            consistent = np.all(d[P] <= bound[P], axis=1)
        no_worse = (rank > self.acc_rank) | ((rank == self.acc_rank) & (s_new <= self.acc_s))
        self._inconsistent = np.where(no_worse & ~consistent, self._inconsistent + 1, 0)
        ok = no_worse & (consistent | (rank > self.acc_rank) | (self._inconsistent >= self.confirm))
        self._offer_unc = (s_new, rank, np.asarray(sigma, float))
        return ok

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
        if self.rule == "better" and getattr(self, "_offer_unc", None) is not None:
            s_new, rank, sigma = self._offer_unc
            self.acc_s[ok], self.acc_rank[ok] = s_new[ok], rank
            self._inconsistent[ok] = 0
            for j in np.nonzero(ok)[0]:
                self.acc_sigma[self._dof_params[j]] = sigma[self._dof_params[j]]
        self._packed = None
        if self.first_accept is None:
            self.first_accept = k
