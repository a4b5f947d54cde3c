"""Trajectory-tracking controller of eqs. 8-10, fed by the on-line estimator.

Per DOF ``i`` (walls ``x_0 = x_{n+1} = 0``; hats are the parameters in use)::

    u_i   = m_i v_i + c_i xd_i + k_i (x_i - x_{i-1}) + k_{i+1} (x_i - x_{i+1})                  (8)
    v_i   = x*_i'' - beta_2 (xd_i - x*_i') - beta_1 (x_i - x*_i) - beta_0 int_0^t (x_i - x*_i)   (9)
    xd_i  = [ -c_i x_i - k_i int_0^t (x_i - x_{i-1}) - k_{i+1} int_0^t (x_i - x_{i+1})
              + int_0^t u_i ] / m_i                                                           (10)

``xd_i`` is the velocity reconstructed from positions and forces (no velocity sensor),
with the *estimated* mass where the paper writes ``m_i``; eq. 10 assumes the chain starts
at rest. ``int u_i`` integrates the force applied: in continuous mode the law's own force
(the ODE's state); in sampled mode, as on a rig, the force sensors' samples (trapezoidal up
to the latest sample, plus the command held since). Behind an actuator lag ``tau`` the
commanded force's integral exceeds the applied one's by ``tau w``, a velocity error
``tau w_i / m_i`` that grows with the force.

**Position feedback in eq. 10 (the rig variant, ``velocity_pole``).** Eq. 10 rebuilds the
velocity from the forces without feedback, so a parameter error integrates into it: with a
spring off by ``dk``, ``xd_i`` drifts at ``dk x / m_i`` while a mass holds at ``x``, and the
loop's integral action turns that ramp into a steady tracking error
``(beta_2 - c_i / m_i) dk x / (m_i beta_0)``. A rig measures the positions, so in sampled
mode the law can pull the integral of its velocity estimate onto them::

    xd_i <- xd_i - 2 p (P_i - x_i) - p^2 Q_i,    P_i = int_0^t xd_i,   Q_i = int_0^t (P_i - x_i)   (10c)

The error ``r = P - x`` then obeys ``r'' + 2 p r' + p^2 r = delta'`` for a velocity error
``delta`` of eq. 10, so a drifting ``delta`` (a ramp) leaves no velocity error in the steady
state. At the first substitution ``P`` restarts at ``x`` and ``Q`` at 0: the correction made
up for the nominal model's error, which the new parameters do not have, and carried over it
disturbs the loop (and with it the estimates) for about ``1 / p``. ``velocity_pole=None``
(the default, and continuous mode always) is the paper's eq. 10.

**Eq. 10 with moving estimates.** By default (``eq10="integrated"``) the stiffness
estimates sit *inside* the integrals, ``int_0^t k_i(s) (x_i - x_{i-1})(s) ds``: identical to
the paper's form for constant estimates, but when the estimates move, the paper's product
``k_i(t) int_0^t (x_i - x_{i-1})`` makes the velocity estimate jump by
``Delta k_i int_0^t (x_i - x_{i-1}) / m_i`` at every update, an error that grows with the
length of the record. The first substitution of a DOF's estimates (at ``switch_time_s``,
or later if they are accepted later) still re-bases the integral as the product form
does (``int K x <- int K x + (K_new - K_old) int x``), so the first estimates model the
whole past instead of the nominal stiffness-free model. ``eq10="product"`` is kept for
comparison.

With exact parameters, eqs. 8-10 make every DOF a chain of integrators and the tracking
error ``e = x - x*`` obeys ``e''' + beta_2 e'' + beta_1 e' + beta_0 e = 0``. The gains come
from pole placement on that polynomial: :data:`DEFAULT_POLES` puts a triple pole at
``s = -20 rad/s`` (``beta_2 = 60 1/s``, ``beta_1 = 1200 1/s^2``, ``beta_0 = 8000 1/s^3``): an
error settles in about 0.3 s without overshoot (fast against the 2 s moves of the
references), and the loop's 20 rad/s stay far below the 1 kHz sample rate, so the
sampled mode behaves like the continuous one.

As in the paper, until ``switch_time_s`` (0.1 s) the law uses ``m_i = 1 kg`` and zero
damping and stiffness; from then on it uses the estimator's current eq. 7 estimates. The
estimates used on ``[t_k, t_{k+1})`` come from samples up to ``k - 1`` (one sample of
computation latency).

**Which estimates are taken.** Early in a record, and under noise, eq. 7 can return
estimates the estimator flags valid but that are far off (under accelerometer noise the
first 0.1 s of the paper's references carry almost no signal). Substituting
them can destabilise the loop, so by default (``accept="settled"``) the four estimates
of DOF ``i`` are taken only when they are finite and physically admissible (``m > 0``,
``c >= 0``, ``k >= 0``) and have changed by less than ``settle_tol`` (2 %) over the last
``settle_window_s`` (20 ms; for the damping the change is measured against at least 1 %
of the critical damping); the first substitution waits until all DOFs pass together.
Otherwise the last accepted values of that DOF stay in use, or the nominal ones if
none was accepted yet. Noise-free, the estimates settle well within
the first 0.1 s, so the rule changes nothing there; ``accept="valid"`` takes every valid
estimate with a positive mass. An estimate that never steadies is never taken: the law then
keeps the nominal parameters, and the loop stays stable but does not track.
``accept="sigma"`` is for estimators that carry an uncertainty, such as
:class:`ContinuousAdapter`: a DOF's estimates are taken when the estimator flags it valid
(every relative one-sigma uncertainty of the DOF at most 5 % by default) and they are
physically admissible; the first substitution waits until all DOFs pass, afterwards each
DOF follows the estimates while they pass and keeps its last accepted values otherwise.

What these choices change on Table 1 (the forces of eq. 10, the position feedback, the two
forms of eq. 10, the acceptance rules) is measured in ``docs/demo.md``, built from
``bench/results/demo_report.json``.

The references (:class:`~algid.control.trajectories.BezierReference`) and the probing multisine
(:class:`~algid.control.trajectories.Multisine`) are in :mod:`algid.control.trajectories`; the law of eqs. 8-10
in :mod:`algid.control.control_law`, the acceptance rule in :mod:`algid.control.estimate_gate`.

The estimator is any object with ``update(accel (n,), force (n,)) -> status`` and the
attributes ``mass (n,)``, ``damping (n,)``, ``stiffness (n+1,)``, ``valid (n,)``; the default
is ``algid.ChainEstimator(n, dt, boundary)`` (imported when the controller starts). An
estimator may also expose ``theta(dof)`` (each DOF's own four estimates), ``sigma``
(3n+1,) (logged as ``estimates["sigma"]``) and ``running_from`` (logged as
``running_from_s``).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import partial
from typing import Any, Callable

import numpy as np

from ..estimator.continuous import PackedParameters
from .control_law import DEFAULT_POLES, ControlLaw, LawParameters, pole_placement_gains
from .controller_log import ControllerLog
from .estimate_gate import ACCEPT_RULES, EstimateGate
from .held_input import RigInput
from .trajectories import BezierReference, bezier

__all__ = [
    "ContinuousAdapter",
    "DEFAULT_POLES",
    "BezierReference",
    "TrackingController",
    "bezier",
    "pole_placement_gains",
]


def _default_estimator(n: int, dt: float, boundary: str) -> Any:
    from .. import ChainEstimator  # the compiled core; imported only when a loop starts

    return ChainEstimator(n, dt, boundary=boundary)


class ContinuousAdapter(PackedParameters):
    """:class:`algid.ContinuousEstimator` behind the ChainEstimator-like face the controller
    reads (``update``, ``mass``, ``damping``, ``stiffness``, ``valid``, ``delay_samples``),
    with a per-DOF validity from the running estimate's uncertainty.

    The running estimate needs its first window results (``window_s``, 0.3 s by default)
    before it exists. Until then (``phase == "bootstrap"``) the adapter serves the growing
    window of a plain ChainEstimator fed the same samples, the paper's estimator, so the
    noise-free loop still has its estimates within 0.1 s; its relative uncertainty is taken
    as the largest relative change of each estimate over the last ``bootstrap_window_s``
    (a steadiness proxy, as the controller's ``accept="settled"`` rule), and only until the
    running estimate's first window is due (``window_s``): under noise the growing window
    wanders off later, however steady it looks over 20 ms. From the first
    sample at which the running estimate is :attr:`~algid.ContinuousEstimator.ready` on
    (``phase == "running"``) the adapter serves the running estimate and its ``sigma``.

    ``valid[i]`` is True when every parameter of DOF ``i`` (``m_i``, ``c_i``, ``k_i``,
    ``k_{i+1}``) is finite with a relative uncertainty :attr:`rel_sigma` at most
    ``rel_sigma_tol`` (``bootstrap_tol`` in the bootstrap phase); the damping's uncertainty
    is measured against at least 1 % of the DOF's critical damping, so a light damper does
    not block a DOF whose masses and springs are well known.

    Parameters
    ----------
    n, dt, boundary
        As :class:`algid.ContinuousEstimator` (dt [s]).
    rel_sigma_tol : float
        Largest relative one-sigma uncertainty [-] of a valid DOF (default 0.05).
    bootstrap_window_s : float
        Window [s] of the bootstrap phase's steadiness proxy (default 0.02).
    bootstrap_tol : float or None
        Largest steadiness proxy [-] of a valid DOF in the bootstrap phase (None: as
        ``rel_sigma_tol``). Noise-free the growing window changes by far less than 1 % in
        20 ms from a few tens of ms on; under noise it wanders by more, so a tight value
        leaves a noisy loop on the nominal parameters until the running estimate passes
        (the rig's 0.01; ``docs/demo.md`` gives what it changes).
    **options
        Passed to :class:`algid.ContinuousEstimator` (``window_s``, ``stagger``, ...).
    """

    def __init__(
        self,
        n: int,
        dt: float,
        boundary: str = "fixed",
        rel_sigma_tol: float = 0.05,
        bootstrap_window_s: float = 0.02,
        bootstrap_tol: float | None = None,
        **options: Any,
    ) -> None:
        from .. import ChainEstimator, ContinuousEstimator

        if not rel_sigma_tol > 0:
            raise ValueError("rel_sigma_tol must be > 0")
        self.n, self.dt, self.boundary = int(n), float(dt), boundary
        self.rel_sigma_tol = float(rel_sigma_tol)
        self.bootstrap_tol = self.rel_sigma_tol if bootstrap_tol is None else float(bootstrap_tol)
        # The bootstrap hand-over and the sigma rule were set up with the algebraic windows
        # (0.3 s, first estimate at 0.31 s); the weak-form default has its first estimate after
        # 0.5 s. method="weak_form" selects it here too.
        options.setdefault("method", "algebraic")
        self.continuous = ContinuousEstimator(n, dt, boundary, **options)
        self.bootstrap = ChainEstimator(n, dt, boundary=boundary)
        self.delay_samples = int(getattr(self.bootstrap, "delay_samples", 0))
        self._W = max(2, int(round(bootstrap_window_s / dt)))
        self._hist = np.full((self._W, 3 * self.n + 1), np.nan)
        self._k = 0
        self.phase = "bootstrap"
        #: sample index (0-based) from which the running estimate is served; None before
        self.running_from: int | None = None
        self.estimate = np.full(3 * self.n + 1, np.nan)
        self.sigma = np.full(3 * self.n + 1, np.nan)
        self.valid = np.zeros(self.n, bool)
        absent = np.zeros(3 * self.n + 1, bool)
        if boundary == "free" or self.n == 1:
            absent[-1] = True  # k_{n+1}: known 0 (free end) or folded into k_1 (n = 1, walls)
        self._absent = absent

    @property
    def rel_sigma(self) -> np.ndarray:
        """Relative one-sigma uncertainty of each served estimate (3n+1,) [-] (damping against
        at least 1 % of the critical damping; 0 for a parameter that is not estimated)."""
        n = self.n
        est = self.estimate
        m, k = est[:n], est[2 * n :]
        k_sum = k[:n] + np.where(np.isnan(k[1:]) & self._absent[2 * n + 1 :], 0.0, k[1:])
        with np.errstate(invalid="ignore", divide="ignore"):
            scale = np.abs(est).copy()
            scale[n : 2 * n] = np.maximum(scale[n : 2 * n], 0.02 * np.sqrt(np.abs(k_sum * m)))
            r = self.sigma / scale
        r[self._absent] = 0.0
        return r

    def update(self, accel: np.ndarray, force: np.ndarray) -> int:
        """Feed one sample (accelerations [m/s^2], forces [N], (n,)); returns the running
        estimator's status."""
        status = self.continuous.update(accel, force)
        n = self.n
        if self.phase == "bootstrap":
            self.bootstrap.update(accel, force)
            est = np.concatenate(
                [
                    np.asarray(self.bootstrap.mass, float),
                    np.asarray(self.bootstrap.damping, float),
                    np.asarray(self.bootstrap.stiffness, float),
                ]
            )
            # the growing window is served until the running estimate's first window is
            # due; after that only the running estimate may be accepted
            ok_b = np.asarray(self.bootstrap.valid, bool) & (self._k < self.continuous.window_samples)
            self._hist[self._k % self._W] = est
            with np.errstate(invalid="ignore"):
                spread = (
                    np.max(np.abs(self._hist - est), axis=0) if self._k + 1 >= self._W else np.full(est.size, np.inf)
                )
            self.estimate, self.sigma = est, spread
            if self.continuous.ready:
                self.phase, self.running_from = "running", self._k
        else:
            ok_b = np.ones(n, bool)
        if self.phase == "running":
            self.estimate = np.asarray(self.continuous.estimate, float).copy()
            self.sigma = np.asarray(self.continuous.sigma, float).copy()
        r = self.rel_sigma
        tol = self.bootstrap_tol if self.phase == "bootstrap" else self.rel_sigma_tol
        good = np.isfinite(r) & (r <= tol) & (np.isfinite(self.estimate) | self._absent)
        idx = np.arange(n)
        self.valid = ok_b & good[idx] & good[n + idx] & good[2 * n + idx] & good[2 * n + idx + 1]
        self._k += 1
        return int(status)


class TrackingController:
    """Eqs. 8-10 with parameters switched from nominal to on-line estimates.

    Parameters
    ----------
    reference : BezierReference or None
        Reference trajectory; None uses :meth:`BezierReference.paper` for the chain's n.
    poles : three poles [rad/s]
        Error poles for the gains (:func:`pole_placement_gains`).
    switch_time_s : float
        Time [s] from which the estimates replace the nominal parameters (the paper: 0.1).
    nominal_mass_kg : float
        Mass [kg] used before the switch (damping and stiffness are 0 then).
    estimator_factory : callable ``(n, dt, boundary) -> estimator`` or None
        Builds the on-line estimator; None uses ``algid.ChainEstimator``.
    use_estimates : bool
        False keeps the nominal parameters for the whole run (a baseline).
    eq10 : {"integrated", "product"}
        Stiffness estimates inside the integrals of eq. 10 (default) or multiplying them
        (the paper's literal form); see the module docstring.
    accept : {"settled", "valid", "sigma", "better"}
        Which estimates of a DOF the law takes (see the module docstring): ``"settled"``
        (default) needs them physically admissible and steady within ``settle_tol`` over
        the last ``settle_window_s``; ``"valid"`` takes every finite estimate the estimator
        flags valid with a positive mass; ``"sigma"`` every physically admissible one the
        estimator flags valid (its validity carries an uncertainty test); ``"better"`` those
        of ``"sigma"`` that never replace accepted ones by ones of larger uncertainty or
        inconsistent ones (the estimator's ``rel_sigma``, ``sigma`` and ``phase``; see
        :mod:`algid.control.estimate_gate`).
    settle_window_s : float
        Window [s] of the steadiness test.
    settle_tol : float
        Largest relative change [-] over that window.
    hold : bool
        Keep the first accepted estimates for the rest of the run (the estimator keeps
        running and is logged); default False, the law follows the estimates.
    excitation : callable ``t [s] -> (n,)`` [N] or None
        A known probing force added to the commanded force of eq. 8 (see
        :class:`~algid.control.trajectories.Multisine`); it is part of ``u`` in eq. 10 and in what
        the estimator sees.
    velocity_pole : float or None
        Sampled mode: the pole ``p`` [rad/s] of the position feedback (10c); None: the paper's.
    actuator_lag_s : float, "estimate" or None
        Sampled mode on a rig: the time constant [s] of the first-order actuator behind the
        held command (0: none), or ``"estimate"``: identify it on line from the commands and
        the measured forces (:class:`~algid.control.held_input.LagEstimator`). The estimator is then
        fed the smooth-equivalent samples of :class:`~algid.control.held_input.HeldLaggedInput`
        (with the accepted masses, two samples late) instead of the raw ones; the samples
        before the masses were accepted are smoothed again at the switch
        (:class:`~algid.control.held_input.RigInput`).
        None (default) feeds the raw samples.

    Notes
    -----
    A :class:`algid.simulator.ContinuousController`: the simulator drives it through
    :meth:`start`, :meth:`params_for_sample`, :meth:`continuous` (continuous mode) or
    :meth:`sampled_force` (sampled mode), and :meth:`observe`; :meth:`reference_motion`
    sets the noise level of a noisy loop and :meth:`log` returns the history. The law is a
    :class:`~algid.control.control_law.ControlLaw`, the acceptance rule an
    :class:`~algid.control.estimate_gate.EstimateGate`, the history a
    :class:`~algid.control.controller_log.ControllerLog` (all made by :meth:`start`).
    """

    def __init__(
        self,
        reference: BezierReference | None = None,
        poles: Sequence[complex] = DEFAULT_POLES,
        switch_time_s: float = 0.1,
        nominal_mass_kg: float = 1.0,
        estimator_factory: Callable[[int, float, str], Any] | None = None,
        use_estimates: bool = True,
        eq10: str = "integrated",
        accept: str = "settled",
        settle_window_s: float = 0.02,
        settle_tol: float = 0.02,
        hold: bool = False,
        excitation: Callable[[float], np.ndarray] | None = None,
        actuator_lag_s: float | str | None = None,
        velocity_pole: float | None = None,
    ) -> None:
        self.velocity_pole = velocity_pole  # checked by ControlLaw at start()
        if actuator_lag_s is not None and actuator_lag_s != "estimate" and not actuator_lag_s >= 0:
            raise ValueError("actuator_lag_s must be >= 0, 'estimate' or None")
        self.actuator_lag_s = actuator_lag_s
        self.excitation = excitation
        if accept not in ACCEPT_RULES:
            raise ValueError(f"accept must be one of {ACCEPT_RULES}, got {accept!r}")
        if not (settle_window_s > 0 and settle_tol > 0):
            raise ValueError("settle_window_s and settle_tol must be > 0")
        self.accept = accept
        self.hold = bool(hold)
        self.settle_window_s = float(settle_window_s)
        self.settle_tol = float(settle_tol)
        if eq10 not in ("integrated", "product"):
            raise ValueError(f"eq10 must be 'integrated' or 'product', got {eq10!r}")
        self.eq10 = eq10
        self.poles = tuple(poles)
        self.beta0, self.beta1, self.beta2 = pole_placement_gains(poles)
        if not switch_time_s >= 0:
            raise ValueError("switch_time_s must be >= 0")
        if not nominal_mass_kg > 0:
            raise ValueError("nominal_mass_kg must be > 0")
        self.reference = reference
        self.switch_time_s = float(switch_time_s)
        self.nominal_mass_kg = float(nominal_mass_kg)
        self.estimator_factory = estimator_factory or _default_estimator
        self.use_estimates = bool(use_estimates)
        self.estimator: Any = None

    def start(
        self, chain_n: int, dt: float, boundary: str = "fixed", samples: int = 0, mode: str = "continuous"
    ) -> None:
        """Prepare a run of ``samples`` samples every ``dt`` [s] on an ``chain_n``-DOF chain."""
        n = int(chain_n)
        if self.reference is None:
            self.reference = BezierReference.paper(n)
        if self.reference.n != n:
            raise ValueError(f"reference has {self.reference.n} DOF, the chain {n}")
        self.n, self.dt, self.boundary, self.mode = n, float(dt), boundary, mode
        self.k_switch = int(round(self.switch_time_s / self.dt))
        self.estimator = self.estimator_factory(n, self.dt, boundary)
        if self.velocity_pole is not None and mode != "sampled":
            raise ValueError("velocity_pole (position feedback in eq. 10) is for sampled mode only")
        gains = (self.beta0, self.beta1, self.beta2)
        self.law = ControlLaw(self.reference, gains, self.eq10, self.excitation, n, self.dt, self.velocity_pole)
        self.gate = EstimateGate(
            n, boundary, self.dt, self.accept, self.settle_window_s, self.settle_tol, self.hold, self.nominal_mass_kg
        )
        self.history = ControllerLog(int(samples), n, self.estimator)
        rig = self.actuator_lag_s is not None and mode == "sampled"
        new_estimator = partial(self.estimator_factory, n, self.dt, boundary)
        self.rig = RigInput(n, self.dt, self.actuator_lag_s, self.k_switch, new_estimator) if rig else None
        self._command = np.zeros(n)  # the command held from the latest sample [N]
        self._nominal = LawParameters.pack(np.full(n, self.nominal_mass_kg), np.zeros(n), np.zeros(n + 1))
        self._used_accepted = np.zeros(n, bool)  # DOFs whose estimates the law used so far
        self._p_prev = self._nominal  # parameters of the interval before
        self._p_k = self._nominal  # parameters of the current interval

    @property
    def gains(self) -> dict[str, float]:
        """``beta_0`` [1/s^3], ``beta_1`` [1/s^2], ``beta_2`` [1/s] of eq. 9."""
        return {"beta0": self.beta0, "beta1": self.beta1, "beta2": self.beta2}

    @property
    def n_states(self) -> int:
        """Continuous-mode controller states ``z = [int (x - x*), int x, int K x, int u]``."""
        return 4 * self.n

    def reference_motion(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Reference position [m], velocity [m/s] and acceleration [m/s^2] (T, n) at ``t`` [s]."""
        return self.reference.evaluate(t)

    def params_for_sample(self, k: int, z: np.ndarray | None = None) -> LawParameters:
        """Parameters the law uses on ``[t_k, t_{k+1})`` (``z``: the continuous-mode
        controller states at ``t_k``); logged as ``used_*``."""
        if k < self.k_switch or not self.use_estimates:
            p = self._nominal
            used_acc = np.zeros(self.n, bool)
        else:
            p = self.gate.parameters()
            used_acc = self.gate.accepted.copy()
        first = np.any(used_acc & ~self._used_accepted)
        if self.eq10 == "integrated" and first:
            # a first substitution: the new stiffnesses model the whole past (as in the
            # paper's product form); later changes enter the integral as they come
            X = z[self.n : 2 * self.n] if z is not None else self.law.X
            self.law.rebase(p.K, self._p_prev.K, X)
        if first:
            self.law.restart_velocity_feedback()
        self._used_accepted |= used_acc
        self._p_prev = p
        self.history.used(k, p)
        self._p_k = p
        return p

    def continuous(self, t: float, x: np.ndarray, z: np.ndarray, p: LawParameters) -> tuple[np.ndarray, np.ndarray]:
        """Continuous-time law: force [N] and the derivative of the controller states
        ``z = [int (x - x*), int x, int K x, int u]`` (4n)."""
        return self.law.continuous(t, x, z, p)

    def sampled_force(self, k: int, t: float, x_meas: np.ndarray) -> np.ndarray:
        """Sampled law at ``t_k`` from measured positions [m]: the force [N] held until
        ``t_{k+1}``. Integrals: trapezoidal for positions, exact for the held force."""
        u, xd = self.law.sampled(k, t, x_meas, self._p_k)
        self.history.law(k, xd, u)
        self._command = u
        return u

    def observe(
        self, k: int, t: float, accel: np.ndarray, force: np.ndarray, x_meas: np.ndarray, z: np.ndarray | None = None
    ) -> None:
        """Feed sample ``k`` (accelerations [m/s^2], forces [N]) to the estimator and keep
        its valid estimates for the following intervals. On a rig the estimator gets the
        smooth sample ``k - 2`` instead, and a new estimator at the switch
        (:class:`~algid.control.held_input.RigInput`)."""
        n = self.n
        if z is not None and k < self.history.T:
            u, xd, _ = self.law.force(t, x_meas, z[:n], z[n : 2 * n], z[2 * n : 3 * n], z[3 * n :], self._p_k)
            self.history.law(k, xd, u)
        if z is None:
            self.law.measured(force)
        if self.rig is None:
            status = self.estimator.update(accel, force)
        else:  # (H4) with the masses the law has accepted
            mass = np.where(self.gate.accepted, self.gate.good_m, np.nan)
            self.estimator, status = self.rig.update(k, self._command, accel, force, mass, self.estimator)
        m = np.asarray(self.estimator.mass, dtype=float)
        c = np.asarray(self.estimator.damping, dtype=float)
        kk = np.asarray(self.estimator.stiffness, dtype=float)
        valid = np.asarray(self.estimator.valid, dtype=bool)
        self.history.estimates(k, self.estimator, m, c, kk, valid, status)
        unc = None
        if self.accept == "better":
            rel = getattr(self.estimator, "rel_sigma", None)
            sig = getattr(self.estimator, "sigma", None)
            if rel is not None and sig is not None:
                rank = int(getattr(self.estimator, "phase", "running") == "running")
                unc = (np.asarray(rel, float), np.asarray(sig, float), rank)
        self.gate.offer(k, m, c, kk, valid, unc)

    def log(self) -> dict[str, Any]:
        """History of the run (``T`` samples): reference ``x_ref``, ``xd_ref``, ``xdd_ref``
        (T, n); ``estimates`` = estimator output after each sample (``mass``, ``damping``
        (T, n), ``stiffness`` (T, n+1) fused, ``valid`` (T, n), ``status`` (T,), and ``theta``
        (T, n, 4): each DOF's own ``[m_i, c_i, k_i, k_{i+1}]`` when the estimator has
        ``theta(dof)``, else NaN); ``used`` = the
        parameters the law used on each interval; ``velocity_estimate`` (eq. 10) and
        ``force_command`` (T, n) at the samples; gains, poles, switch time and the
        estimator's ``delay_samples``."""
        t = np.arange(self.history.T) * self.dt
        xs, xd, xdd = self.reference.evaluate(t)
        running_from = getattr(self.estimator, "running_from", None)
        first = self.gate.first_accept
        return {
            "t": t,
            "x_ref": xs,
            "xd_ref": xd,
            "xdd_ref": xdd,
            **self.history.history(),
            "gains": self.gains,
            "poles": [complex(p) for p in self.poles],
            "eq10": self.eq10,
            "switch_time_s": self.switch_time_s,
            "k_switch": self.k_switch,
            "delay_samples": int(getattr(self.estimator, "delay_samples", 0)),
            "accept": self.accept,
            "hold": self.hold,
            "running_from_s": None if running_from is None else running_from * self.dt,
            "first_accepted_s": None if first is None else first * self.dt,
        }
