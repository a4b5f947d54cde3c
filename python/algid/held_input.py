"""The estimator's samples on a rig whose actuator holds the command and lags behind it.

A DAC holds the command ``u_k`` on ``[t_k, t_{k+1})`` and a first-order actuator
``tau w' = u - w`` turns it into the force ``w`` the force sensors read. Between samples::

    w(t_k + s) = u_k + (w_k - u_k) exp(-s / tau),       0 <= s < h                    (H1)

so ``w`` has a kink at every sample, and so has the acceleration: by eq. 1,
``m_i a_i = w_i - c_i v_i - k_i (x_i - x_{i-1}) - k_{i+1} (x_i - x_{i+1})``, whose velocity
and position terms are smooth, carries the kink of ``w_i`` divided by ``m_i``. The
estimator's quadrature interpolates samples by smooth polynomials and so misses the ripple
between them; with the loop's slowly varying commands the ripple does not average out
(the damping columns see the force half a ripple out of step), and the estimates come out
biased by a few percent at 2 ms of lag (Table 1 in the demo's loop).

:class:`HeldLaggedInput` gives the estimator the samples of the smooth signals instead.
The force's mean over interval ``k`` is exact by (H1)::

    wbar_k = u_k + (w_k - u_k) g,      g = (tau / h) (1 - exp(-h / tau))              (H2)

and the smooth force at ``t_k`` is the value there of the cubic whose means over the four
intervals around ``t_k`` are those (H2) gives (exact for any cubic; the box of the two
intervals next to ``t_k`` alone is exact for a straight line only and leaves the
estimates 0.3-1.5 % off in the demo's rig loop between 0.1 and 0.3 s)::

    w~_k = (-wbar_{k-2} + 7 wbar_{k-1} + 7 wbar_k - wbar_{k+1}) / 12                  (H3)

so sample ``k`` leaves the smoothing when sample ``k + 1`` arrives, one sample late (the
second sample, without ``wbar_{-1}``, gets the two-interval box ``(wbar_0 + wbar_1) / 2``,
the first passes unchanged). Without lag ``wbar_k = u_k`` and (H3) takes the staircase's
smooth equivalent to fourth order instead of the mean of the two one-sided limits, the
simulator's sampling convention. The ripple ``w_k - w~_k`` reaches the acceleration
divided by the mass, so the smooth acceleration is::

    a~_k = a_k - (w_k - w~_k) / m_i                                                  (H4)

with a mass ``m_i`` the caller gives (a DOF without a finite positive mass is passed
unchanged, force and acceleration alike). The controller gives the masses its law has
accepted and, once it has, smooths the samples before again with them
(:meth:`algid.controller.TrackingController.observe`).

**The lag from the rig's own records.** (H1) at ``s = h`` ties consecutive force samples
to the command held between them::

    w_{k+1} - u_k = a (w_k - u_k),      a = exp(-h / tau)                                (H5)

so the least-squares ``a = sum (w_{k+1} - u_k)(w_k - u_k) / sum (w_k - u_k)^2`` over all
samples and DOF, and ``tau = -h / ln a``, come from the recorded commands and the measured
forces alone (:class:`LagEstimator`). Without lag the force jumps at the samples and a
sample reads the mean of the one-sided limits, ``w_k = (u_{k-1} + u_k) / 2``, which (H5)
would take for a lag of about ``h / ln 2``; the estimator therefore reports no lag when
that model leaves the smaller residual. The smooth samples need ``tau`` well: Table 1's loop
behind 5 ms of lag, told 4 or 6 ms, gets estimates 12-18 % off (the demo's rig loop, whose
position feedback still tracks within 1.2 % of the stroke).
"""

from __future__ import annotations

import numpy as np

__all__ = ["HeldLaggedInput", "LagEstimator"]


class HeldLaggedInput:
    """Smooth-equivalent samples (H3, H4) of a held command behind a first-order lag.

    Parameters
    ----------
    n : number of DOF.
    dt : sample interval h [s] (the hold time of the DAC).
    actuator_lag_s : time constant tau [s] of the actuator (0: the command acts at once).
    """

    def __init__(self, n: int, dt: float, actuator_lag_s: float) -> None:
        if not dt > 0:
            raise ValueError("dt must be > 0")
        if not actuator_lag_s >= 0:
            raise ValueError("actuator_lag_s must be >= 0")
        self.n, self.dt = int(n), float(dt)
        self.set_lag(actuator_lag_s)
        self._wbar = np.zeros((4, self.n))  # wbar_{k-3} .. wbar_k [N]
        self._prev = np.zeros((2, self.n))  # acceleration [m/s^2] and force [N] at t_{k-1}
        self._k = 0  # samples in so far

    def set_lag(self, actuator_lag_s: float) -> None:
        """Use the time constant ``actuator_lag_s`` [s] from the next sample on."""
        self.tau = float(actuator_lag_s)
        #: g of (H2): the weight of the start value w_k in the interval mean [-]
        self.g = 0.0 if self.tau == 0 else self.tau / self.dt * -np.expm1(-self.dt / self.tau)

    def interval_mean(self, command: np.ndarray, force: np.ndarray) -> np.ndarray:
        """(H2): mean force [N] over ``[t_k, t_{k+1})`` from the command held there and the
        force measured at ``t_k`` [N] (n,)."""
        return command + (force - command) * self.g

    def smooth(
        self, command: np.ndarray, accel: np.ndarray, force: np.ndarray, mass: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """Sample ``k`` in: the command held from ``t_k`` [N], the measured acceleration
        [m/s^2] and force [N] at ``t_k``; the smooth acceleration (H4) and force (H3) of
        sample ``k - 1`` out, with the masses ``mass`` [kg] (n,); None for the first sample."""
        self._wbar[:-1] = self._wbar[1:]
        self._wbar[-1] = self.interval_mean(np.asarray(command, float), np.asarray(force, float))
        (a, w), k = self._prev.copy(), self._k
        self._prev[0], self._prev[1] = accel, force
        self._k += 1
        if k <= 1:
            return None if k == 0 else (a, w)
        wb = self._wbar  # wbar_{j-2}, wbar_{j-1}, wbar_j, wbar_{j+1} of the sample j = k - 1 out
        w_s = 0.5 * (wb[1] + wb[2]) if k == 2 else (-wb[0] + 7.0 * (wb[1] + wb[2]) - wb[3]) / 12.0
        m = np.asarray(mass, float)
        known = np.isfinite(m) & (m > 0)
        ripple = np.where(known, (w - w_s) / np.where(known, m, 1.0), 0.0)
        # a DOF without a mass keeps both raw samples: its force and acceleration ripples
        # then cancel in the mass column of eq. 5 at least
        return a - ripple, np.where(known, w_s, w)


class LagEstimator:
    """The actuator's time constant from the held commands and the measured forces (H5).

    Parameters
    ----------
    dt : sample interval h [s].

    Feed every sample with :meth:`update`; :attr:`tau` [s] is the running least-squares
    estimate (0 until the commands have moved the force, when ``a <= 0``, and when the
    no-lag model fits the samples better).
    """

    def __init__(self, dt: float) -> None:
        if not dt > 0:
            raise ValueError("dt must be > 0")
        self.dt = float(dt)
        self.sxy = 0.0  # sum (w_{k+1} - u_k)(w_k - u_k) [N^2]
        self.sxx = 0.0  # sum (w_k - u_k)^2 [N^2]
        self.syy = 0.0  # sum (w_{k+1} - u_k)^2 [N^2]
        self.r0 = 0.0  # residual of the no-lag model, sum (w_{k+1} - (u_k + u_{k+1}) / 2)^2 [N^2]
        self._prev: tuple[np.ndarray, np.ndarray] | None = None  # (u_k, w_k)

    def update(self, command: np.ndarray, force: np.ndarray) -> float:
        """Sample ``k``: the command held from ``t_k`` and the force measured at ``t_k``
        [N] (n,); returns :attr:`tau` [s]."""
        u, w = np.asarray(command, float), np.asarray(force, float)
        if self._prev is not None:
            u0, w0 = self._prev
            self.sxy += float(np.dot(w - u0, w0 - u0))
            self.sxx += float(np.dot(w0 - u0, w0 - u0))
            self.syy += float(np.dot(w - u0, w - u0))
            self.r0 += float(np.sum((w - 0.5 * (u0 + u)) ** 2))
        self._prev = (u.copy(), w.copy())
        return self.tau

    @property
    def pole(self) -> float:
        """``a = exp(-h / tau)`` of (H5) [-] (NaN before any information)."""
        return self.sxy / self.sxx if self.sxx > 0 else float("nan")

    @property
    def tau(self) -> float:
        """Estimated time constant [s] (0 without information or lag)."""
        a = self.pole
        if not np.isfinite(a) or a <= 0 or self.r0 <= self.syy - a * self.sxy:
            return 0.0
        return -self.dt / np.log(min(a, 1.0 - 1e-12))
