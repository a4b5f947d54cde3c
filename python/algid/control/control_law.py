"""The control law of eqs. 8-10 (see :mod:`algid.control.controller`): the force from the
reference, the measured or integrated positions and the parameters in use, in
continuous time (integrators as ODE states) and sampled (discrete integrals)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Callable, NamedTuple

import numpy as np

from ..model.chain import stiffness_matrix
from .trajectories import BezierReference

__all__ = ["DEFAULT_POLES", "ControlLaw", "LawParameters", "pole_placement_gains"]

#: Error poles [rad/s] of the default gains (a triple real pole).
DEFAULT_POLES: tuple[float, float, float] = (-20.0, -20.0, -20.0)


def pole_placement_gains(poles: Sequence[complex] = DEFAULT_POLES) -> tuple[float, float, float]:
    """Gains ``(beta_0, beta_1, beta_2)`` of eq. 9 placing the roots of
    ``s^3 + beta_2 s^2 + beta_1 s + beta_0`` at ``poles`` [rad/s].

    Raises ``ValueError`` unless there are three poles, all in the open left half-plane,
    complex ones in conjugate pairs.
    """
    p = np.asarray(poles, dtype=complex).reshape(-1)
    if p.size != 3:
        raise ValueError(f"eq. 9 has three error poles, got {p.size}")
    if not np.all(p.real < 0):
        raise ValueError(f"poles must have negative real parts, got {poles}")
    coeffs = np.poly(p)
    if np.max(np.abs(coeffs.imag)) > 1e-9 * np.max(np.abs(coeffs)):
        raise ValueError("complex poles must come in conjugate pairs")
    c = coeffs.real
    return float(c[3]), float(c[2]), float(c[1])


class LawParameters(NamedTuple):
    """The parameters the law uses: masses [kg] (n,), dampings [N s/m] (n,), the
    stiffness matrix [N/m] (n, n) and the springs [N/m] (n+1,)."""

    mass: np.ndarray
    damping: np.ndarray
    K: np.ndarray
    stiffness: np.ndarray

    @classmethod
    def pack(cls, m: np.ndarray, c: np.ndarray, k: np.ndarray) -> LawParameters:
        """Copies of ``m, c, k`` with the stiffness matrix of ``k``."""
        return cls(m.copy(), c.copy(), stiffness_matrix(k), k.copy())


class ControlLaw:
    """Eqs. 8-10 on an ``n``-DOF chain sampled every ``dt`` [s].

    ``gains = (beta_0 [1/s^3], beta_1 [1/s^2], beta_2 [1/s])``; ``eq10`` the form of eq. 10
    (``"integrated"``: stiffness estimates inside the integrals, ``K int x = S + R`` with
    ``R`` re-based at a first substitution, :meth:`rebase`; ``"product"``: ``K int x``);
    ``excitation`` an optional known force ``t -> (n,)`` [N] added to eq. 8. Sampled mode
    keeps the integrals ``E = int (x - x*)``, ``X = int x``, ``S = int K x`` (trapezoidal)
    and ``U = int u``. ``force_source`` says which force ``U`` integrates in sampled mode:
    ``"measured"`` (a rig's eq. 10: the force sensor's samples, trapezoidal up to the
    latest one, :meth:`measured`, plus the command held since) or ``"commanded"`` (the
    held commands, exact; wrong by ``tau w`` behind an actuator lag ``tau``, see
    :mod:`algid.control.controller`). ``velocity_pole`` [rad/s] adds the position feedback (10c) of
    :mod:`algid.control.controller` to eq. 10 in sampled mode (None: the paper's eq. 10).
    """

    def __init__(
        self,
        reference: BezierReference,
        gains: tuple[float, float, float],
        eq10: str,
        excitation: Callable[[float], np.ndarray] | None,
        n: int,
        dt: float,
        velocity_pole: float | None = None,
        force_source: str = "measured",
    ) -> None:
        if force_source not in ("measured", "commanded"):
            raise ValueError(f"force_source must be 'measured' or 'commanded', got {force_source!r}")
        if velocity_pole is not None and not velocity_pole > 0:
            raise ValueError(f"velocity_pole must be > 0 rad/s or None, got {velocity_pole}")
        self.velocity_pole = velocity_pole
        self.force_source = force_source
        self.reference = reference
        self.beta0, self.beta1, self.beta2 = gains
        self.eq10 = eq10
        self.excitation = excitation
        self.dt = dt
        self.E, self.X, self.S, self.U = (np.zeros(n) for _ in range(4))
        self.R = np.zeros(n)
        self._x_prev = np.zeros(n)
        self._kx_prev = np.zeros(n)
        self._e_prev = np.zeros(n)
        self._u_prev = np.zeros(n)
        self.U_meas = np.zeros(n)  # int_0^{t_j} u_meas up to the latest force sample t_j [N s]
        self._f_prev: np.ndarray | None = None
        # (10c): P = int xd [m], Q = int (P - x) [m s], the correction [m/s] xd gets
        self.P, self.Q, self.correction = np.zeros(n), np.zeros(n), np.zeros(n)
        self._restart_feedback = False

    def force(
        self, t: float, x: np.ndarray, E: np.ndarray, X: np.ndarray, S: np.ndarray, U: np.ndarray, p: LawParameters
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Force [N], velocity estimate of eq. 10 [m/s] and reference position [m] at ``t``
        [s] from positions ``x`` [m] and the integrals ``E, X, S, U``."""
        m, c, K, _ = p
        xs, xsd, xsdd = self.reference.evaluate(t)
        # eq. 10: K int x = k_i int(x_i - x_{i-1}) + k_{i+1} int(x_i - x_{i+1})
        KX = S + self.R if self.eq10 == "integrated" else K @ X
        xd = (U - c * x - KX) / m + self.correction
        v = xsdd - self.beta2 * (xd - xsd) - self.beta1 * (x - xs) - self.beta0 * E  # eq. 9
        u = m * v + c * xd + K @ x  # eq. 8
        if self.excitation is not None:
            u = u + self.excitation(t)  # known probing force; eq. 10 integrates it with u
        return u, xd, xs

    def continuous(self, t: float, x: np.ndarray, z: np.ndarray, p: LawParameters) -> tuple[np.ndarray, np.ndarray]:
        """Force [N] and the derivative of the controller states
        ``z = [int (x - x*), int x, int K x, int u]`` (4n)."""
        n = x.size
        u, _, xs = self.force(t, x, z[:n], z[n : 2 * n], z[2 * n : 3 * n], z[3 * n :], p)
        return u, np.concatenate((x - xs, x, p[2] @ x, u))

    def sampled(self, k: int, t: float, x_meas: np.ndarray, p: LawParameters) -> tuple[np.ndarray, np.ndarray]:
        """Force [N] held on ``[t_k, t_{k+1})`` and the velocity estimate [m/s] from the
        positions measured at ``t_k`` [m]; advances the integrals to ``t_k``."""
        xs = self.reference.evaluate(t)[0]
        e = x_meas - xs
        kx = p[2] @ x_meas
        if k > 0:
            h2 = 0.5 * self.dt
            self.E = self.E + h2 * (self._e_prev + e)
            self.X = self.X + h2 * (self._x_prev + x_meas)
            self.S = self.S + h2 * (self._kx_prev + kx)
            if self.force_source == "measured" and self._f_prev is not None:
                # int_0^{t_k} u = (measured up to t_{k-1}) + (command held on [t_{k-1}, t_k))
                self.U = self.U_meas + self.dt * self._u_prev
            else:
                self.U = self.U + self.dt * self._u_prev
        if self.velocity_pole is not None:
            # (10c): the measured positions pull int xd back onto x (a double pole at -p)
            if self._restart_feedback:
                self.P, self.Q, self._restart_feedback = x_meas.copy(), np.zeros_like(x_meas), False
            pole = self.velocity_pole
            self.correction = -2.0 * pole * (self.P - x_meas) - pole**2 * self.Q
        u, xd, _ = self.force(t, x_meas, self.E, self.X, self.S, self.U, p)
        if self.velocity_pole is not None:
            self.Q = self.Q + self.dt * (self.P - x_meas)
            self.P = self.P + self.dt * xd
        self._x_prev, self._kx_prev, self._e_prev, self._u_prev = x_meas.copy(), kx, e, u
        return u, xd

    def measured(self, force: np.ndarray) -> None:
        """The force sensors' next sample [N] (n,): extends ``int u_meas`` by a trapezoid."""
        if self._f_prev is not None:
            self.U_meas = self.U_meas + 0.5 * self.dt * (self._f_prev + force)
        self._f_prev = np.array(force, dtype=float)

    def rebase(self, K_new: np.ndarray, K_old: np.ndarray, X: np.ndarray) -> None:
        """A first substitution in the integrated form: the new stiffnesses model the whole
        past, ``int K x <- int K x + (K_new - K_old) int x`` (``X = int x`` [m s])."""
        self.R = self.R + (K_new - K_old) @ X

    def restart_velocity_feedback(self) -> None:
        """Restart (10c) at the next sample (``P = x``, ``Q = 0``): its correction made up
        for the nominal model's velocity error, which the substituted parameters' eq. 10
        does not have."""
        self._restart_feedback = True
