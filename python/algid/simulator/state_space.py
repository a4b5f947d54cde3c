"""The state-space step: the state layout, the linear system ``s' = L s + B u + N(t, s)``
and its exponential integration over the sub-intervals of a sample interval (exact for
the linear part and polynomial inputs, ETDRK4 for the nonlinear part ``N``)."""

from __future__ import annotations

from dataclasses import dataclass
from math import factorial
from typing import Callable

import numpy as np

from .inputs import RunInputs
from .pieces import shift
from .plant import Plant

__all__ = ["Propagator", "StateLayout", "Stepper", "linear_system", "state_layout"]

#: ``N(t [s], s) -> ds/dt``: the nonlinear part of the state equation.
Nonlinear = Callable[[float, np.ndarray], np.ndarray]


def phi(Z: np.ndarray, p: int) -> list[np.ndarray]:
    """``[e^Z, phi_1(Z), .., phi_p(Z)]`` (``phi_j(Z) = sum_k Z^k / (k + j)!``) from one
    exponential of the block matrix ``[[Z, I, 0..], [0, 0, I, ..], .., [0 ..]]``."""
    from scipy.linalg import expm

    m = Z.shape[0]
    big = np.zeros(((p + 1) * m, (p + 1) * m))
    big[:m, :m] = Z
    for j in range(p):
        big[j * m : (j + 1) * m, (j + 1) * m : (j + 2) * m] = np.eye(m)
    Eb = expm(big)
    return [Eb[:m, j * m : (j + 1) * m] for j in range(p + 1)]


class Propagator:
    """Matrices of one step of length ``ell`` [s] for ``s' = L s + B u(t) + N(t, s)``.

    ``G[j]`` maps the coefficient of ``tau^j`` of a polynomial input to its exact effect on
    the state after the step; ``E2, Gh, Q, F1..F3`` are the ETDRK4 matrices (Cox and
    Matthews 2002) for the nonlinear part, which enters as ``Bn @ N(t, s)``.
    """

    def __init__(self, L: np.ndarray, B: np.ndarray, ell: float, rk: bool, Bn: np.ndarray | None = None) -> None:
        ph = phi(ell * L, 4)
        self.ell = ell
        self.E = ph[0]
        self.G = np.stack([factorial(j) * ell ** (j + 1) * (ph[j + 1] @ B) for j in range(4)])
        self.rk = rk
        if rk:
            hf = phi(0.5 * ell * L, 4)
            self.E2 = hf[0]
            self.Gh = np.stack([factorial(j) * (0.5 * ell) ** (j + 1) * (hf[j + 1] @ B) for j in range(4)])
            # N enters as Bn @ N (Bn = identity unless N lives in a smaller space)
            Bn = np.eye(L.shape[0]) if Bn is None else Bn
            self.Q = 0.5 * ell * hf[1] @ Bn
            p1, p2, p3 = ph[1], ph[2], ph[3]
            self.F1 = ell * (p1 - 3.0 * p2 + 4.0 * p3) @ Bn
            self.F2 = ell * (2.0 * p2 - 4.0 * p3) @ Bn
            self.F3 = ell * (4.0 * p3 - p2) @ Bn
            # fused forms: one product per combination of the scheme
            self.E2Q = np.hstack((self.E2, self.Q))
            self.EF = np.hstack((self.E, self.F1, self.F2, self.F3))

    def step(
        self,
        s: np.ndarray,
        t0: float,
        wf: np.ndarray,
        wh: np.ndarray,
        w2: np.ndarray,
        N: Callable[[float, np.ndarray], np.ndarray],
        n0: np.ndarray | None = None,
    ) -> np.ndarray:
        """One ETDRK4 step from ``s`` at ``t0``; ``wf``, ``wh`` are the exact polynomial-input
        contributions over the step and its first half, ``w2 = wf - E2 wh`` over the second
        half; ``n0 = N(t0, s)`` if already known."""
        ell = self.ell
        nu = N(t0, s) if n0 is None else n0
        e2s = self.E2 @ s + wh
        Q = self.Q
        a = e2s + Q @ nu
        na = N(t0 + 0.5 * ell, a)
        b = e2s + Q @ na
        nb = N(t0 + 0.5 * ell, b)
        c = self.E2Q @ np.concatenate((a, 2.0 * nb - nu)) + w2
        nc = N(t0 + ell, c)
        return self.EF @ np.concatenate((s, nu, na + nb, nc)) + wf


@dataclass(frozen=True)
class StateLayout:
    """Where each part of the state ``[x, v, sensor filter states, actuator states, controller
    states]`` sits: ``n`` DOF, first-order accelerometer filters on the DOFs ``lp_idx`` with
    cut-offs ``lp_wc`` [rad/s], each a state ``z' = w_c (a - z)`` that the accelerometer reads
    (``sensor_lowpass``) or subtracts (``sensor_highpass``, where ``lp_high``: it reads
    ``a - z``, the first-order high-pass ``s / (s + w_c)``), ``n_w`` actuator states (``n`` with
    a lag, else 0) and ``n_z`` controller states."""

    n: int
    lp_idx: np.ndarray
    lp_wc: np.ndarray
    lp_high: np.ndarray
    n_w: int
    n_z: int

    @property
    def n_lp(self) -> int:
        return int(self.lp_idx.size)

    @property
    def o_lp(self) -> int:
        """Offset of the low-pass states."""
        return 2 * self.n

    @property
    def o_w(self) -> int:
        """Offset of the actuator states."""
        return self.o_lp + self.n_lp

    @property
    def o_z(self) -> int:
        """Offset of the controller states."""
        return self.o_w + self.n_w

    @property
    def size(self) -> int:
        return self.o_z + self.n_z


def state_layout(inp: RunInputs, n_z: int) -> StateLayout:
    """The layout of a run with ``n_z`` controller states."""
    lp = sorted(
        (e.dof, 2 * np.pi * e.params["cutoff_hz"], e.name == "sensor_highpass")
        for e in inp.effects
        if e.name in ("sensor_lowpass", "sensor_highpass")
    )
    return StateLayout(
        n=inp.n,
        lp_idx=np.array([i for i, _, _ in lp], dtype=int),
        lp_wc=np.array([w for _, w, _ in lp]),
        lp_high=np.array([h for _, _, h in lp], dtype=bool),
        n_w=inp.n if inp.actuator_lag_s > 0 else 0,
        n_z=n_z,
    )


def linear_system(plant: Plant, lay: StateLayout, actuator_lag_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(L, Bg, B_in)``: the linear dynamics of the state, how a force on the masses
    enters (``Bg``, (m, n)) and how the commanded force enters (``B_in``: through the
    actuator lag if there is one, else ``Bg``)."""
    n, minv = lay.n, plant.minv
    o_lp, o_w, o_z, lp_idx, lp_wc = lay.o_lp, lay.o_w, lay.o_z, lay.lp_idx, lay.lp_wc
    Lm = np.zeros((lay.size, lay.size))
    Lm[:n, n : 2 * n] = np.eye(n)
    Lm[n : 2 * n, :n] = -minv[:, None] * plant.K
    Lm[n : 2 * n, n : 2 * n] = -np.diag(minv * plant.c)
    Bg = np.zeros((lay.size, n))
    Bg[n : 2 * n] = np.diag(minv)
    if lay.n_w:
        Lm[n : 2 * n, o_w:o_z] = np.diag(minv)
        Lm[o_w:o_z, o_w:o_z] = -np.eye(n) / actuator_lag_s
    if lay.n_lp:
        Lm[o_lp:o_w] = lp_wc[:, None] * Lm[n + lp_idx]
        Lm[o_lp:o_w, o_lp:o_w] -= np.diag(lp_wc)
        Bg[o_lp:o_w] = lp_wc[:, None] * Bg[n + lp_idx]
    if not lay.n_w:
        return Lm, Bg, Bg
    B_in = np.zeros((lay.size, n))
    B_in[o_w:o_z] = np.eye(n) / actuator_lag_s
    return Lm, Bg, B_in


def _propagators(
    Lm: np.ndarray,
    B_in: np.ndarray,
    lengths_s: list[float],
    fs_hz: float,
    rk: bool,
    Bn: np.ndarray | None,
    parts: int = 1,
) -> list[Propagator]:
    """One propagator per sub-interval, each of its length over ``parts`` (shared between
    sub-intervals of the same length)."""
    by_length: dict[float, Propagator] = {}
    for ell in lengths_s:
        key = round(ell * fs_hz, 12)
        if key not in by_length:
            by_length[key] = Propagator(Lm, B_in, ell / parts, rk, Bn)
    return [by_length[round(ell * fs_hz, 12)] for ell in lengths_s]


class Stepper:
    """Steps over sub-interval ``q`` of a sample interval; a step across a switch of a
    steep effect (a friction reversal, a contact engaging or releasing) is redone in
    :attr:`REFINE` sub-steps.

    Parameters
    ----------
    Lm, B_in : the linear system and how the commanded force enters it.
    Bn : how ``N`` enters (None: ``N`` is a full state derivative, as with a controller
        inside the ODE).
    lengths_s : sub-interval lengths [s]; fs_hz : sample rate [Hz].
    rk : ETDRK4 matrices needed (a nonlinear part exists).
    plant : tells the switch state of a state.
    """

    REFINE = 8

    def __init__(
        self,
        Lm: np.ndarray,
        B_in: np.ndarray,
        Bn: np.ndarray | None,
        lengths_s: list[float],
        fs_hz: float,
        rk: bool,
        plant: Plant,
    ) -> None:
        self.P = _propagators(Lm, B_in, lengths_s, fs_hz, rk, Bn)
        self.P_fine = _propagators(Lm, B_in, lengths_s, fs_hz, True, Bn, self.REFINE) if plant.has_switches else []
        self.plant = plant
        #: steps redone in sub-steps so far
        self.refined = 0
        self._last_state: np.ndarray | None = None  # the latest state reached without a switch
        self._last_switch: tuple = ()  # its switch state

    def step(
        self,
        q: int,
        s0: np.ndarray,
        t0: float,
        coef: np.ndarray | None,
        wf: np.ndarray,
        wh: np.ndarray,
        w2: np.ndarray,
        N: Nonlinear,
        n0: np.ndarray | None = None,
    ) -> np.ndarray:
        """One ETDRK4 step over sub-interval ``q`` from ``s0`` at ``t0`` [s], redone finely
        across a switch; ``coef`` (4, n) is the polynomial input on the sub-interval (None:
        no input), ``wf, wh, w2`` its contributions (:meth:`Propagator.step`)."""
        s1 = self.P[q].step(s0, t0, wf, wh, w2, N, n0)
        if not self.P_fine:
            return s1
        sw0 = self._last_switch if self._last_state is s0 else self.plant.switch_state(s0)
        sw1 = self.plant.switch_state(s1)
        if sw1 == sw0:
            self._last_state, self._last_switch = s1, sw1
            return s1
        self.refined += 1
        return self._refined(q, s0, t0, coef, wf, wh, w2, N)

    def _refined(
        self,
        q: int,
        s0: np.ndarray,
        t0: float,
        coef: np.ndarray | None,
        wf: np.ndarray,
        wh: np.ndarray,
        w2: np.ndarray,
        N: Nonlinear,
    ) -> np.ndarray:
        Pf = self.P_fine[q]
        ell = Pf.ell
        s1 = s0
        for j in range(self.REFINE):
            if coef is None:
                s1 = Pf.step(s1, t0 + j * ell, wf * 0.0, wh * 0.0, w2 * 0.0, N)
            else:
                c = shift(coef, j * ell)
                fwf = np.einsum("jmn,jn->m", Pf.G, c)
                fwh = np.einsum("jmn,jn->m", Pf.Gh, c)
                s1 = Pf.step(s1, t0 + j * ell, fwf, fwh, fwf - Pf.E2 @ fwh, N)
        return s1
