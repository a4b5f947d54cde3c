"""A closed-loop positioning axis: bang-bang moves tracked by a saturated PID on an encoder.

This is how most slow machine axes are recorded (a DC motor on a ball screw, a linear
stage): the drive follows point-to-point moves, the force is what the drive commands
(motor current times its constant), and the only motion sensor is an incremental encoder.
Driven by :func:`algid.simulator.simulate` in ``mode="sampled"``, it produces the records
that a rig's data logger writes: position in whole encoder counts, a force that jumps at
every sample (a held DAC output) and saturates during the moves, and feedback that makes
the force depend on the measured (quantised) position.

Reference (:class:`BangBangReference`): each DOF moves between ``targets_m`` in turn; a
move of length ``d`` accelerates at ``+a_max`` for half of its duration
``2 sqrt(|d| / a_max)`` and decelerates at ``-a_max`` for the other half (the time-optimal
rest-to-rest move under an acceleration limit), then dwells ``dwell_s``.

Law (:class:`PositioningController`), per DOF, at every sample ``t_k`` from the encoder
reading ``x_k``::

    e_k   = x*_k - x_k                                  position error [m]
    ed_k  = low-pass of (e_k - e_{k-1}) / dt            error rate [m/s], first order at ``rate_filter_hz``
    u_k   = sat( m0 x*''_k + c0 x*'_k + kp e_k + kd ed_k + ki sum e dt,  +-f_max )

held until ``t_{k+1}`` (the integral stops while the force saturates: anti-windup).
``m0``, ``c0`` are the drive's nominal feedforward parameters, deliberately not the
plant's.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["BangBangReference", "PositioningController"]


class BangBangReference:
    """Point-to-point moves with a bang-bang acceleration profile.

    Parameters
    ----------
    targets_m : array (moves, n)
        Positions [m] visited in turn, starting from 0 at ``t = 0``.
    a_max : float
        Acceleration limit of the profile [m/s^2].
    dwell_s : float
        Rest after every move [s].
    start_s : float
        Rest before the first move [s].
    """

    def __init__(
        self, targets_m: Sequence[Sequence[float]], a_max: float, dwell_s: float = 0.5, start_s: float = 0.2
    ) -> None:
        tg = np.asarray(targets_m, dtype=float)
        if tg.ndim == 1:
            tg = tg[:, None]
        if tg.ndim != 2 or tg.shape[0] < 1 or not np.all(np.isfinite(tg)):
            raise ValueError("targets_m must be a finite (moves, n) array with at least one move")
        if not (a_max > 0 and dwell_s >= 0 and start_s >= 0):
            raise ValueError("need a_max > 0, dwell_s >= 0 and start_s >= 0")
        self.targets = tg
        self.a_max = float(a_max)
        starts = np.vstack([np.zeros(tg.shape[1]), tg[:-1]])
        self._from = starts
        dist = tg - starts
        # every DOF of a move takes the time of the longest one (its acceleration is scaled)
        dur = 2.0 * np.sqrt(np.max(np.abs(dist), axis=1) / self.a_max)
        t0 = np.empty(tg.shape[0])
        clock = float(start_s)
        for q, d in enumerate(dur):
            t0[q] = clock
            clock += d + float(dwell_s)
        self._t0, self._dur = t0, dur
        with np.errstate(invalid="ignore", divide="ignore"):
            self._acc = np.where(dur[:, None] > 0, 4.0 * dist / (dur[:, None] ** 2), 0.0)
        self.end_s = clock

    @property
    def n(self) -> int:
        """Number of DOF."""
        return int(self.targets.shape[1])

    def evaluate(self, t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Reference position [m], velocity [m/s] and acceleration [m/s^2] at ``t`` [s]:
        three ``(n,)`` arrays for a scalar ``t``, three ``(T, n)`` for an array."""
        scalar = np.ndim(t) == 0
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        q = np.clip(np.searchsorted(self._t0, tt, side="right") - 1, 0, None)
        started = tt >= self._t0[0]
        s = np.clip(tt - self._t0[q], 0.0, self._dur[q])
        half = 0.5 * self._dur[q]
        acc, x0 = self._acc[q], self._from[q]
        first = (s <= half)[:, None]
        s_, h_ = s[:, None], half[:, None]
        pos = np.where(first, x0 + 0.5 * acc * s_**2, x0 + acc * (h_**2 - 0.5 * (2 * h_ - s_) ** 2))
        vel = np.where(first, acc * s_, acc * (2 * h_ - s_))
        moving = (tt - self._t0[q] < self._dur[q])[:, None] & started[:, None]
        accel = np.where(moving, np.where(first, acc, -acc), 0.0)
        pos = np.where(started[:, None], pos, 0.0)
        vel = np.where(started[:, None], vel, 0.0)
        if scalar:
            return pos[0], vel[0], accel[0]
        return pos, vel, accel


class PositioningController:
    """Saturated PID with feedforward on encoder readings (sampled mode only).

    Parameters
    ----------
    reference : BangBangReference
        Moves to follow.
    f_max : float
        Force limit of the drive [N].
    kp, kd, ki : float
        Gains [N/m], [N s/m], [N/(m s)].
    m0, c0 : float
        Nominal mass [kg] and viscous friction [N s/m] of the feedforward.
    rate_filter_hz : float
        Cut-off of the first-order low-pass on the differentiated error [Hz].

    Notes
    -----
    A :class:`algid.simulator.Controller`: the simulator calls :meth:`start`, then per
    sample :meth:`params_for_sample`, :meth:`sampled_force` and :meth:`observe`, and
    :meth:`log` at the end (:meth:`reference_motion` for the noise level of a noisy loop).
    """

    def __init__(
        self,
        reference: BangBangReference,
        f_max: float,
        kp: float,
        kd: float,
        ki: float = 0.0,
        m0: float = 0.0,
        c0: float = 0.0,
        rate_filter_hz: float = 100.0,
    ) -> None:
        if not (f_max > 0 and kp >= 0 and kd >= 0 and ki >= 0 and rate_filter_hz > 0):
            raise ValueError("need f_max > 0, kp, kd, ki >= 0 and rate_filter_hz > 0")
        self.reference = reference
        self.f_max, self.kp, self.kd, self.ki = float(f_max), float(kp), float(kd), float(ki)
        self.m0, self.c0 = float(m0), float(c0)
        self.rate_filter_hz = float(rate_filter_hz)
        self.n_states = 0

    def start(self, chain_n: int, dt: float, boundary: str = "fixed", samples: int = 0, mode: str = "sampled") -> None:
        """Prepare a run of ``samples`` samples every ``dt`` [s]."""
        if mode != "sampled":
            raise ValueError("PositioningController runs once per sample: use mode='sampled'")
        if self.reference.n != int(chain_n):
            raise ValueError(f"reference has {self.reference.n} DOF, the chain {chain_n}")
        n = int(chain_n)
        self.dt = float(dt)
        self._alpha = 1.0 - np.exp(-2 * np.pi * self.rate_filter_hz * self.dt)
        self._e_prev = None
        self._ed = np.zeros(n)
        self._int = np.zeros(n)
        self._T = int(samples)
        self._force = np.full((self._T, n), np.nan)
        self._saturated = np.zeros((self._T, n), bool)

    def params_for_sample(self, k: int, z: np.ndarray | None = None) -> None:
        """No estimated parameters enter this law."""
        return None

    def sampled_force(self, k: int, t: float, x_meas: np.ndarray) -> np.ndarray:
        """Force [N] held on ``[t_k, t_{k+1})`` from the encoder reading ``x_meas`` [m]."""
        xs, xd, xdd = self.reference.evaluate(t)
        e = xs - x_meas
        if self._e_prev is not None:
            self._ed += self._alpha * ((e - self._e_prev) / self.dt - self._ed)
        self._e_prev = e
        raw = self.m0 * xdd + self.c0 * xd + self.kp * e + self.kd * self._ed + self.ki * self._int
        u = np.clip(raw, -self.f_max, self.f_max)
        sat = u != raw
        self._int += np.where(sat, 0.0, e * self.dt)
        if k < self._T:
            self._force[k], self._saturated[k] = u, sat
        return u

    def observe(
        self, k: int, t: float, accel: np.ndarray, force: np.ndarray, x_meas: np.ndarray, z: np.ndarray | None = None
    ) -> None:
        """Nothing to learn from the measurements."""

    def reference_motion(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Reference position [m], velocity [m/s] and acceleration [m/s^2] (T, n) at ``t`` [s]."""
        return self.reference.evaluate(t)

    def log(self) -> dict[str, Any]:
        """``x_ref`` (T, n) [m], ``force_command`` (T, n) [N] and ``saturated`` (T, n)."""
        t = np.arange(self._T) * self.dt
        return {
            "t": t,
            "x_ref": self.reference.evaluate(t)[0],
            "force_command": self._force,
            "saturated": self._saturated,
        }
