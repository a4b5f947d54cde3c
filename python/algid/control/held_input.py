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
intervals next to ``t_k`` alone is exact for a straight line only and biases the estimates
behind a lag; ``docs/demo.md`` gives by how much)::

    w~_k = (-wbar_{k-2} + 7 wbar_{k-1} + 7 wbar_k - wbar_{k+1}) / 12                  (H3)

(the second sample, without ``wbar_{-1}``, gets the two-interval box
``(wbar_0 + wbar_1) / 2``, the first its measured force). Without lag ``wbar_k = u_k`` and
(H3) takes the staircase's smooth equivalent to fourth order instead of the mean of the two
one-sided limits, the simulator's sampling convention. The ripple ``w_k - w~_k`` reaches the acceleration
divided by the mass, so the smooth acceleration is::

    a~_k = a_k - (w_k - w~_k) / m_i                                                  (H4)

**Positions.** The estimator integrates the smooth acceleration twice. The ripple has zero
mean over every interval, so the velocities agree at the samples, but over interval ``k``
it moves the mass by ``nu_k / m_i``, with (``w~`` between samples: the straight line between
``w~_k`` and ``w~_{k+1}`` plus the curvature at ``t_k``)::

    nu_k = int_0^h (h - s) (w(t_k + s) - w~(t_k + s)) ds
         = u_k h^2 / 2 + (w_k - u_k) (h tau - tau^2 (1 - exp(-h / tau)))
           - h^2 (2 w~_k + w~_{k+1}) / 6 + h^2 (w~_{k+1} - 2 w~_k + w~_{k-1}) / 24        (H6)

Without lag these add up to about ``h^2 (w - w_0) / (12 m_i)`` in position, which no initial
condition absorbs, and the estimator reads it as stiffness. The smooth force therefore gets
``(nu_k - nu_{k-1}) / h^2`` added (and, through (H4), the acceleration the same over the
mass): a smooth motion whose positions are the measured ones. It needs ``w~_{k+1}``, so
sample ``k`` leaves the smoothing when sample ``k + 2`` arrives, two samples late (the
first two samples without it).

(H4) takes a mass ``m_i`` the caller gives (a DOF without a finite positive mass is passed
unchanged, force and acceleration alike). The controller gives the masses its law has
accepted and, once it has, smooths the samples before again with them
(:class:`RigInput`).

**The lag from the rig's own records.** (H1) at ``s = h`` ties consecutive force samples
to the command held between them::

    w_{k+1} - u_k = a (w_k - u_k),      a = exp(-h / tau)                                (H5)

so the least-squares ``a = sum (w_{k+1} - u_k)(w_k - u_k) / sum (w_k - u_k)^2`` over all
samples and DOF, and ``tau = -h / ln a``, come from the recorded commands and the measured
forces alone (:class:`LagEstimator`). Without lag the force jumps at the samples and a
sample reads the mean of the one-sided limits, ``w_k = (u_{k-1} + u_k) / 2``, which (H5)
would take for a lag of about ``h / ln 2``; the estimator therefore reports no lag when
that model leaves the smaller residual. The smooth samples need ``tau`` well: a lag told
20 % off biases every estimate (``docs/demo.md``).
"""

from __future__ import annotations

import numpy as np

from ..estimator import Status

__all__ = ["HeldLaggedInput", "LagEstimator", "RigInput"]


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
        self._w_s = np.zeros((3, self.n))  # w~_{k-3} .. w~_{k-1} (H3) [N]
        self._raw = np.zeros((3, 3, self.n))  # command, acceleration, force at t_{k-2} .. t_k
        self._nu = np.zeros(self.n)  # nu_{k-3} (H6) [N s^2]
        self._k = 0  # samples in so far

    def set_lag(self, actuator_lag_s: float) -> None:
        """Use the time constant ``actuator_lag_s`` [s] from the next sample on."""
        self.tau = float(actuator_lag_s)
        h, tau = self.dt, self.tau
        #: g of (H2): the weight of the start value w_k in the interval mean [-]
        self.g = 0.0 if tau == 0 else tau / h * -np.expm1(-h / tau)
        #: the lag's term of (H6), int_0^h (h - s) exp(-s / tau) ds [s^2]
        self.e = 0.0 if tau == 0 else h * tau + tau**2 * np.expm1(-h / tau)

    def interval_mean(self, command: np.ndarray, force: np.ndarray) -> np.ndarray:
        """(H2): mean force [N] over ``[t_k, t_{k+1})`` from the command held there and the
        force measured at ``t_k`` [N] (n,)."""
        return command + (force - command) * self.g

    def smooth(
        self, command: np.ndarray, accel: np.ndarray, force: np.ndarray, mass: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """Sample ``k`` in: the command held from ``t_k`` [N], the measured acceleration
        [m/s^2] and force [N] at ``t_k``; the smooth acceleration (H4) and force (H3, H6)
        of sample ``k - 2`` out, with the masses ``mass`` [kg] (n,); None for the first two."""
        k, h = self._k, self.dt
        self._k += 1
        self._raw[:-1] = self._raw[1:]
        self._raw[-1] = command, accel, force
        self._wbar[:-1] = self._wbar[1:]
        self._wbar[-1] = self.interval_mean(self._raw[-1, 0], self._raw[-1, 2])
        self._w_s[:-1] = self._w_s[1:]
        wb = self._wbar  # wbar_{k-3} .. wbar_k: (H3) of sample k - 1
        if k >= 3:
            self._w_s[-1] = (-wb[0] + 7.0 * (wb[1] + wb[2]) - wb[3]) / 12.0
        elif k == 2:  # no wbar_{-1}: the two-interval box
            self._w_s[-1] = 0.5 * (wb[1] + wb[2])
        elif k == 1:  # the first sample: its measured force
            self._w_s[-1] = self._raw[-2, 2]
        if k < 2:
            return None
        (u, a, w), (s0, s1, s2) = self._raw[0], self._w_s  # sample j = k - 2; w~_{j-1}, w~_j, w~_{j+1}
        nu = u * h * h / 2 + (w - u) * self.e - h * h * (2.0 * s1 + s2) / 6 + h * h * (s2 - 2.0 * s1 + s0) / 24
        w_s = s1 + (nu - self._nu) / (h * h) if k >= 4 else s1
        self._nu = nu
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


class RigInput:
    """The estimator's samples on a rig: the lag from the rig's records (unless given), the
    smooth samples of :class:`HeldLaggedInput`, and a reseed at the controller's switch.

    (H4) takes the masses the law has accepted (a growing window's early masses fed back
    into their own window spoil it), so the samples before that go in raw. If every DOF's
    masses are accepted by the last sample before the switch (``k_switch - 1``), a new
    estimator (``new_estimator()``) gets all samples so far smoothed with them: the estimates
    the law takes at the switch are those of smooth samples.

    Parameters
    ----------
    n, dt : number of DOF and sample interval [s].
    actuator_lag_s : time constant [s] of the actuator, or ``"estimate"`` (:class:`LagEstimator`).
    k_switch : the sample from which the law uses the estimates.
    new_estimator : callable ``() -> estimator`` (the controller's factory).
    """

    def __init__(self, n: int, dt: float, actuator_lag_s, k_switch: int, new_estimator) -> None:
        estimate = actuator_lag_s == "estimate"
        self.model = HeldLaggedInput(n, dt, 0.0 if estimate else actuator_lag_s)
        self.lag = LagEstimator(dt) if estimate else None
        self.k_switch, self.new_estimator = int(k_switch), new_estimator
        self.raw = np.zeros((max(self.k_switch, 0), 3, int(n)))  # command, acceleration, force

    def update(self, k: int, command, accel, force, mass, estimator) -> tuple:
        """Sample ``k`` (the command held from ``t_k``, acceleration, force; the accepted
        masses [kg], NaN where none) into ``estimator``; returns the estimator (a new one
        after the reseed) and its status."""
        if self.lag is not None:
            self.model.set_lag(self.lag.update(command, force))
        if k < self.k_switch:
            self.raw[k] = command, accel, force
        sample = self.model.smooth(command, accel, force, mass)
        status = int(Status.WARMUP) if sample is None else estimator.update(*sample)
        if k == self.k_switch - 1 and np.all(np.isfinite(mass)):
            estimator = self.new_estimator()
            again = HeldLaggedInput(self.model.n, self.model.dt, self.model.tau)
            for raw in self.raw[: k + 1]:
                sample = again.smooth(*raw, mass)
                if sample is not None:
                    status = estimator.update(*sample)
        return estimator, status
