"""Trajectory-tracking controller of eqs. 8-10, fed by the on-line estimator.

Per DOF ``i`` (walls ``x_0 = x_{n+1} = 0``; hats are the parameters in use)::

    u_i   = m_i v_i + c_i xd_i + k_i (x_i - x_{i-1}) + k_{i+1} (x_i - x_{i+1})                  (8)
    v_i   = x*_i'' - beta_2 (xd_i - x*_i') - beta_1 (x_i - x*_i) - beta_0 int_0^t (x_i - x*_i)   (9)
    xd_i  = [ -c_i x_i - k_i int_0^t (x_i - x_{i-1}) - k_{i+1} int_0^t (x_i - x_{i+1})
              + int_0^t u_i ] / m_i                                                           (10)

``xd_i`` is the velocity reconstructed from positions and forces (no velocity sensor),
with the *estimated* mass where the paper writes ``m_i``; eq. 10 assumes the chain starts
at rest. ``int u_i`` integrates the force the controller commands.

**Eq. 10 with moving estimates.** By default (``eq10="integrated"``) the stiffness
estimates sit *inside* the integrals, ``int_0^t k_i(s) (x_i - x_{i-1})(s) ds``: identical to
the paper's form for constant estimates, but when the estimates move, the paper's product
``k_i(t) int_0^t (x_i - x_{i-1})`` makes the velocity estimate jump by
``Delta k_i int_0^t (x_i - x_{i-1}) / m_i`` at every update, an error that grows with the
length of the record. The first substitution of a DOF's estimates (at ``switch_time_s``,
or later if they are accepted later) still re-bases the integral as the product form
does (``int K x <- int K x + (K_new - K_old) int x``), so the first estimates model the
whole past instead of the nominal stiffness-free model. On Table 1 in continuous mode
with the estimates updated every sample, the peak tracking error after 1 s is 0.04 % of
the stroke with the integrated form and 7.6 % with the product form (``eq10="product"``,
kept for comparison; ``bench/demo_report.py``).

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
estimates the estimator flags valid but that are far off (with 40 dB of accelerometer
noise the first 0.1 s of the paper's references carry almost no signal). Substituting
them can destabilise the loop, so by default (``accept="settled"``) the four estimates
of DOF ``i`` are taken only when they are finite and physically admissible (``m > 0``,
``c >= 0``, ``k >= 0``) and have changed by less than ``settle_tol`` (2 %) over the last
``settle_window_s`` (20 ms; for the damping the change is measured against at least 1 %
of the critical damping); the first substitution waits until all DOFs pass together.
Otherwise the last accepted values of that DOF stay in use, or the nominal ones if
none was accepted yet. Noise-free, the estimates settle well within
the first 0.1 s, so the rule changes nothing there; ``accept="valid"`` takes every valid
estimate with a positive mass. With 40 dB of accelerometer noise the single growing window
never passes the rule on the paper's references alone (its error stays above 40 %), so the
law keeps the nominal parameters: the loop stays stable but does not track.
``accept="sigma"`` is for estimators that carry an uncertainty, such as
:class:`ContinuousAdapter`: a DOF's estimates are taken when the estimator flags it valid
(every relative one-sigma uncertainty of the DOF at most 5 % by default) and they are
physically admissible; the first substitution waits until all DOFs pass, afterwards each
DOF follows the estimates while they pass and keeps its last accepted values otherwise.
With 40 dB on the accelerations and a 0.05 N-per-line probe multisine (:class:`Multisine`)
the demo substitutes at about 0.2 s and the peak tracking error after 1 s is 1.8-2.8 % of
the stroke over three seeds (the single window in the same loop: 12.6 %;
``bench/demo_report.py``).

References (:class:`BezierReference`): Bezier rest-to-rest polynomials
``psi(tau) = tau^5 (252 - 1050 tau + 1800 tau^2 - 1575 tau^3 + 700 tau^4 - 126 tau^5)``
(``psi(0) = 0``, ``psi(1) = 1``, derivatives 1-4 zero at both ends) move each DOF from rest
to its target over ``t_out`` and back to rest over ``t_back``. The paper's targets are
``(0.005, 0.005, -0.005) m``; :meth:`BezierReference.paper` generalises to any ``n`` by
repeating the pattern ``+, +, -`` (``n = 1``: ``+5 mm``; ``n = 5``: ``+, +, -, +, +``).

The estimator is any object with ``update(accel (n,), force (n,)) -> status`` and the
attributes ``mass (n,)``, ``damping (n,)``, ``stiffness (n+1,)``, ``valid (n,)``; the default
is ``algid.ChainEstimator(n, dt, boundary)`` (imported when the controller starts). An
estimator may also expose ``theta(dof)`` (each DOF's own four estimates), ``sigma``
(3n+1,) (logged as ``estimates["sigma"]``) and ``running_from`` (logged as
``running_from_s``).
"""

from __future__ import annotations

from typing import Any, Callable, Optional, Sequence, Union

import numpy as np

from .continuous import PackedParameters

__all__ = [
    "BEZIER_COEFFS",
    "ContinuousAdapter",
    "Multisine",
    "DEFAULT_POLES",
    "BezierReference",
    "TrackingController",
    "bezier",
    "pole_placement_gains",
]

#: Error poles [rad/s] of the default gains (a triple real pole).
DEFAULT_POLES: tuple[float, float, float] = (-20.0, -20.0, -20.0)

#: Coefficients of ``psi(tau)`` for ``tau^5 .. tau^10``.
BEZIER_COEFFS = (252.0, -1050.0, 1800.0, -1575.0, 700.0, -126.0)


def bezier(tau: Union[float, np.ndarray]) -> tuple[Any, Any, Any]:
    """``psi``, ``dpsi/dtau``, ``d2psi/dtau2`` of the rest-to-rest Bezier polynomial, with
    ``tau`` clipped to ``[0, 1]``."""
    tau = np.clip(tau, 0.0, 1.0)
    p = dp = ddp = 0.0 * tau
    for q, c in enumerate(BEZIER_COEFFS):
        e = q + 5
        p = p + c * tau**e
        dp = dp + c * e * tau ** (e - 1)
        ddp = ddp + c * e * (e - 1) * tau ** (e - 2)
    return p, dp, ddp


def _bezier_scalar(tau: float) -> tuple[float, float, float]:
    if tau <= 0.0:
        return 0.0, 0.0, 0.0
    if tau >= 1.0:
        return 1.0, 0.0, 0.0
    t2 = tau * tau
    t3 = t2 * tau
    # Horner in tau of the three polynomials (coefficients of tau^0.. after factoring)
    p = t3 * t2 * (252.0 + tau * (-1050.0 + tau * (1800.0 + tau * (-1575.0 + tau * (700.0 - 126.0 * tau)))))
    dp = t2 * t2 * (1260.0 + tau * (-6300.0 + tau * (12600.0 + tau * (-12600.0 + tau * (6300.0 - 1260.0 * tau)))))
    ddp = t3 * (5040.0 + tau * (-31500.0 + tau * (75600.0 + tau * (-88200.0 + tau * (50400.0 - 11340.0 * tau)))))
    return p, dp, ddp


class BezierReference:
    """Rest-to-rest reference: rest -> ``targets`` over ``t_out``, back to rest over ``t_back``.

    Parameters
    ----------
    targets_m : array (n,)
        Positions [m] held between the two moves.
    t_out : (start, end) [s]
        Interval of the outward move.
    t_back : (start, end) [s]
        Interval of the return move (after ``t_out``).
    """

    def __init__(self, targets_m: Sequence[float], t_out: tuple[float, float] = (0.0, 2.0),
                 t_back: tuple[float, float] = (2.5, 4.5)) -> None:
        self.targets = np.asarray(targets_m, dtype=float).reshape(-1)
        if self.targets.size < 1 or not np.all(np.isfinite(self.targets)):
            raise ValueError("targets_m must be finite with at least one entry")
        a, b = map(float, t_out)
        c, d = map(float, t_back)
        if not (0.0 <= a < b <= c < d):
            raise ValueError(f"need 0 <= t_out[0] < t_out[1] <= t_back[0] < t_back[1], got {t_out}, {t_back}")
        self.t_out = (a, b)
        self.t_back = (c, d)

    @property
    def n(self) -> int:
        """Number of DOF."""
        return int(self.targets.size)

    @property
    def stroke_m(self) -> float:
        """Largest target magnitude [m]."""
        return float(np.max(np.abs(self.targets)))

    @classmethod
    def paper(cls, n: int, stroke_m: float = 0.005, **kw: Any) -> "BezierReference":
        """The paper's targets ``(+s, +s, -s)`` for n = 3, the pattern repeated for other n."""
        pattern = np.array([1.0, 1.0, -1.0])
        return cls(stroke_m * np.resize(pattern, int(n)), **kw)

    def evaluate(self, t: Union[float, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Reference position [m], velocity [m/s] and acceleration [m/s^2] at ``t`` [s].

        A scalar ``t`` gives three ``(n,)`` arrays, an array ``(T,)`` three ``(T, n)``.
        """
        if np.ndim(t) == 0:
            t = float(t)
            (a, b), (c, d) = self.t_out, self.t_back
            if t < c:
                L = b - a
                p, dp, ddp = _bezier_scalar((t - a) / L)
                return self.targets * p, self.targets * (dp / L), self.targets * (ddp / (L * L))
            L = d - c
            p, dp, ddp = _bezier_scalar((t - c) / L)
            return self.targets * (1.0 - p), self.targets * (-dp / L), self.targets * (-ddp / (L * L))
        t = np.asarray(t, dtype=float)
        (a, b), (c, d) = self.t_out, self.t_back
        p1, d1, dd1 = bezier((t - a) / (b - a))
        p2, d2, dd2 = bezier((t - c) / (d - c))
        shape = p1 - p2
        vel = d1 / (b - a) - d2 / (d - c)
        acc = dd1 / (b - a) ** 2 - dd2 / (d - c) ** 2
        X = self.targets
        return shape[:, None] * X, vel[:, None] * X, acc[:, None] * X


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


def _default_estimator(n: int, dt: float, boundary: str) -> Any:
    from . import ChainEstimator  # the compiled core; imported only when a loop starts

    return ChainEstimator(n, dt, boundary=boundary)


class Multisine:
    """Probing force ``f_i(t) = amplitude * sum_q sin(2 pi f_q t + phi_iq)`` [N] per DOF.

    The paper's references are slow (2 s rest-to-rest moves): their accelerations carry so
    little information that 40 dB of accelerometer noise buries it (neither the growing
    window nor the continuous estimator gets a usable estimate from them, even with the
    loop tracking on the true parameters). A small known multisine added to the commanded
    force keeps the chain excited; with the default 3-16 Hz lines each DOF moves by some
    10 um (0.2 % of the stroke) under the loop's feedback. Phases are fixed per DOF
    (``seed``), so every run gets the same probe.
    """

    FREQS_HZ = (3.1, 4.7, 6.3, 8.9, 12.1, 15.7)

    def __init__(self, n: int, amplitude_n: float, freqs_hz: Sequence[float] = FREQS_HZ,
                 seed: int = 0) -> None:
        if not amplitude_n >= 0:
            raise ValueError("amplitude_n must be >= 0")
        self.amplitude_n = float(amplitude_n)
        self.freqs_hz = np.asarray(freqs_hz, dtype=float)
        self._w = 2 * np.pi * self.freqs_hz
        self.phases = np.random.default_rng(seed).uniform(0, 2 * np.pi, (int(n), self.freqs_hz.size))

    def __call__(self, t: float) -> np.ndarray:
        """Force [N] (n,) at time ``t`` [s]."""
        return self.amplitude_n * np.sin(self._w * t + self.phases).sum(axis=1)


class ContinuousAdapter(PackedParameters):
    """:class:`algid.ContinuousEstimator` behind the ChainEstimator-like face the controller
    reads (``update``, ``mass``, ``damping``, ``stiffness``, ``valid``, ``delay_samples``),
    with a per-DOF validity from the running estimate's uncertainty.

    The running estimate needs its first window results (``window_s``, 0.3 s by default)
    before it exists. Until then (``phase == "bootstrap"``) the adapter serves the growing
    window of a plain ChainEstimator fed the same samples, the paper's estimator, so the
    noise-free loop still has its estimates within 0.1 s; its relative uncertainty is taken
    as the largest relative change of each estimate over the last ``bootstrap_window_s``
    (a steadiness proxy, as the controller's ``accept="settled"`` rule). From the first
    sample at which the running estimate is :attr:`~algid.ContinuousEstimator.ready` on
    (``phase == "running"``) the adapter serves the running estimate and its ``sigma``.

    ``valid[i]`` is True when every parameter of DOF ``i`` (``m_i``, ``c_i``, ``k_i``,
    ``k_{i+1}``) is finite with a relative uncertainty :attr:`rel_sigma` at most
    ``rel_sigma_tol``; the damping's uncertainty is measured against at least 1 % of the
    DOF's critical damping, so a light damper does not block a DOF whose masses and
    springs are well known.

    Parameters
    ----------
    n, dt, boundary
        As :class:`algid.ContinuousEstimator` (dt [s]).
    rel_sigma_tol : float
        Largest relative one-sigma uncertainty [-] of a valid DOF (default 0.05).
    bootstrap_window_s : float
        Window [s] of the bootstrap phase's steadiness proxy (default 0.02).
    **options
        Passed to :class:`algid.ContinuousEstimator` (``window_s``, ``stagger``, ...).
    """

    def __init__(self, n: int, dt: float, boundary: str = "fixed", rel_sigma_tol: float = 0.05,
                 bootstrap_window_s: float = 0.02, **options: Any) -> None:
        from . import ChainEstimator, ContinuousEstimator

        if not rel_sigma_tol > 0:
            raise ValueError("rel_sigma_tol must be > 0")
        self.n, self.dt, self.boundary = int(n), float(dt), boundary
        self.rel_sigma_tol = float(rel_sigma_tol)
        self.continuous = ContinuousEstimator(n, dt, boundary, **options)
        self.bootstrap = ChainEstimator(n, dt, boundary=boundary)
        self.delay_samples = int(getattr(self.bootstrap, "delay_samples", 0))
        self._W = max(2, int(round(bootstrap_window_s / dt)))
        self._hist = np.full((self._W, 3 * self.n + 1), np.nan)
        self._k = 0
        self.phase = "bootstrap"
        #: sample index (0-based) from which the running estimate is served; None before
        self.running_from: Optional[int] = None
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
        m, k = est[:n], est[2 * n:]
        k_sum = k[:n] + np.where(np.isnan(k[1:]) & self._absent[2 * n + 1:], 0.0, k[1:])
        with np.errstate(invalid="ignore", divide="ignore"):
            scale = np.abs(est).copy()
            scale[n:2 * n] = np.maximum(scale[n:2 * n], 0.02 * np.sqrt(np.abs(k_sum * m)))
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
            est = np.concatenate([np.asarray(self.bootstrap.mass, float),
                                  np.asarray(self.bootstrap.damping, float),
                                  np.asarray(self.bootstrap.stiffness, float)])
            ok_b = np.asarray(self.bootstrap.valid, bool)
            self._hist[self._k % self._W] = est
            with np.errstate(invalid="ignore"):
                spread = np.max(np.abs(self._hist - est), axis=0) if self._k + 1 >= self._W \
                    else np.full(est.size, np.inf)
            self.estimate, self.sigma = est, spread
            if self.continuous.ready:
                self.phase, self.running_from = "running", self._k
        else:
            ok_b = np.ones(n, bool)
        if self.phase == "running":
            self.estimate = np.asarray(self.continuous.estimate, float).copy()
            self.sigma = np.asarray(self.continuous.sigma, float).copy()
        r = self.rel_sigma
        good = np.isfinite(r) & (r <= self.rel_sigma_tol) & (np.isfinite(self.estimate) | self._absent)
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
    accept : {"settled", "valid"}
        Which estimates of a DOF the law takes (see the module docstring): ``"settled"``
        (default) needs them physically admissible and steady within ``settle_tol`` over
        the last ``settle_window_s``; ``"valid"`` takes every finite estimate the estimator
        flags valid with a positive mass.
    settle_window_s : float
        Window [s] of the steadiness test.
    settle_tol : float
        Largest relative change [-] over that window.
    hold : bool
        Keep the first accepted estimates for the rest of the run (the estimator keeps
        running and is logged); default False, the law follows the estimates.
    excitation : callable ``t [s] -> (n,)`` [N] or None
        A known probing force added to the commanded force of eq. 8 (see
        :class:`Multisine`); it is part of ``u`` in eq. 10 and in what the estimator sees.

    Notes
    -----
    The simulator drives the controller through :meth:`start`, :meth:`params_for_sample`,
    :meth:`continuous` (continuous mode) or :meth:`sampled_force` (sampled mode), and
    :meth:`observe`; :meth:`log` returns the history.
    """

    def __init__(self, reference: Optional[BezierReference] = None,
                 poles: Sequence[complex] = DEFAULT_POLES, switch_time_s: float = 0.1,
                 nominal_mass_kg: float = 1.0,
                 estimator_factory: Optional[Callable[[int, float, str], Any]] = None,
                 use_estimates: bool = True, eq10: str = "integrated", accept: str = "settled",
                 settle_window_s: float = 0.02, settle_tol: float = 0.02, hold: bool = False,
                 excitation: Optional[Callable[[float], np.ndarray]] = None) -> None:
        self.excitation = excitation
        if accept not in ("settled", "valid", "sigma"):
            raise ValueError(f"accept must be 'settled', 'valid' or 'sigma', got {accept!r}")
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
        self._started = False

    # ---- set-up -------------------------------------------------------------------
    def start(self, chain_n: int, dt: float, boundary: str = "fixed", samples: int = 0,
              mode: str = "continuous") -> None:
        """Prepare a run of ``samples`` samples every ``dt`` [s] on an ``chain_n``-DOF chain."""
        n = int(chain_n)
        if self.reference is None:
            self.reference = BezierReference.paper(n)
        if self.reference.n != n:
            raise ValueError(f"reference has {self.reference.n} DOF, the chain {n}")
        self.n, self.dt, self.boundary, self.mode = n, float(dt), boundary, mode
        self.k_switch = int(round(self.switch_time_s / self.dt))
        self.estimator = self.estimator_factory(n, self.dt, boundary)
        self._has_theta = callable(getattr(self.estimator, "theta", None))
        self._has_sigma = getattr(self.estimator, "sigma", None) is not None
        T = int(samples)
        self._T = T
        self._good_m = np.full(n, self.nominal_mass_kg)
        self._good_c = np.zeros(n)
        self._good_k = np.zeros(n + 1)
        self._win = max(2, int(round(self.settle_window_s / self.dt)))
        self._hist_m = np.zeros((self._win, n))
        self._hist_c = np.zeros((self._win, n))
        self._hist_k = np.zeros((self._win, n + 1))
        self._hist_n = 0
        self._first_accept = None
        self._k_right_absent = np.zeros(n, bool)
        self._k_right_absent[-1] = (boundary == "free") or n == 1
        self._nominal = self._pack(np.full(n, self.nominal_mass_kg), np.zeros(n), np.zeros(n + 1))
        self._current = self._nominal
        self._dirty = True
        # discrete integrals of sampled mode: int (x - x*), int x, int K x, int u
        self._E = np.zeros(n)
        self._X = np.zeros(n)
        self._S = np.zeros(n)
        self._U = np.zeros(n)
        self._x_prev = np.zeros(n)
        self._kx_prev = np.zeros(n)
        # eq10="integrated": K int x = S + R, R re-based at first substitutions
        self._R = np.zeros(n)
        self._accepted = np.zeros(n, bool)
        self._used_accepted = np.zeros(n, bool)
        self._p_prev = self._nominal
        self._p_k = self._nominal
        self._e_prev = np.zeros(n)
        self._u_prev = np.zeros(n)
        self._log = {
            "est_mass": np.full((T, n), np.nan), "est_damping": np.full((T, n), np.nan),
            "est_stiffness": np.full((T, n + 1), np.nan), "est_valid": np.zeros((T, n), bool),
            "est_theta": np.full((T, n, 4), np.nan), "est_sigma": np.full((T, 3 * n + 1), np.nan),
            "status": np.zeros(T, int), "used_mass": np.zeros((T, n)),
            "used_damping": np.zeros((T, n)), "used_stiffness": np.zeros((T, n + 1)),
            "velocity_estimate": np.full((T, n), np.nan), "force_command": np.full((T, n), np.nan),
        }
        self._started = True

    def _pack(self, m: np.ndarray, c: np.ndarray, k: np.ndarray) -> tuple:
        n = self.n
        K = np.zeros((n, n))
        for i in range(n):
            K[i, i] = k[i] + k[i + 1]
            if i + 1 < n:
                K[i, i + 1] = K[i + 1, i] = -k[i + 1]
        return (m.copy(), c.copy(), K, k.copy())

    @property
    def gains(self) -> dict[str, float]:
        """``beta_0`` [1/s^3], ``beta_1`` [1/s^2], ``beta_2`` [1/s] of eq. 9."""
        return {"beta0": self.beta0, "beta1": self.beta1, "beta2": self.beta2}

    @property
    def n_states(self) -> int:
        """Continuous-mode controller states ``z = [int (x - x*), int x, int K x, int u]``."""
        return 4 * self.n

    # ---- parameters in use ------------------------------------------------------------
    def params_for_sample(self, k: int, z: Optional[np.ndarray] = None) -> tuple:
        """Parameters ``(m (n,), c (n,), K (n, n), k (n+1,))`` the law uses on
        ``[t_k, t_{k+1})`` (``z``: the continuous-mode controller states at ``t_k``);
        logged as ``used_*``."""
        if k < self.k_switch or not self.use_estimates:
            p = self._nominal
            used_acc = np.zeros(self.n, bool)
        else:
            if self._dirty:
                self._current = self._pack(self._good_m, self._good_c, self._good_k)
                self._dirty = False
            p = self._current
            used_acc = self._accepted.copy()
        if self.eq10 == "integrated" and np.any(used_acc & ~self._used_accepted):
            # a first substitution: the new stiffnesses model the whole past (as in the
            # paper's product form); later changes enter the integral as they come
            X = z[self.n:2 * self.n] if z is not None else self._X
            self._R = self._R + (p[2] - self._p_prev[2]) @ X
        self._used_accepted |= used_acc
        self._p_prev = p
        if k < self._T:
            self._log["used_mass"][k] = p[0]
            self._log["used_damping"][k] = p[1]
            self._log["used_stiffness"][k] = p[3]
        self._p_k = p
        return p

    # ---- the law ------------------------------------------------------------------------
    def _law(self, t: float, x: np.ndarray, E: np.ndarray, X: np.ndarray, S: np.ndarray,
             U: np.ndarray, p: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Eqs. 8-10 with ``X = int x`` and ``S = int K x`` (the integrated form's)."""
        m, c, K, _ = p
        xs, xsd, xsdd = self.reference.evaluate(t)
        # eq. 10: K int x = k_i int(x_i - x_{i-1}) + k_{i+1} int(x_i - x_{i+1})
        KX = S + self._R if self.eq10 == "integrated" else K @ X
        xd = (U - c * x - KX) / m
        v = xsdd - self.beta2 * (xd - xsd) - self.beta1 * (x - xs) - self.beta0 * E  # eq. 9
        u = m * v + c * xd + K @ x  # eq. 8
        if self.excitation is not None:
            u = u + self.excitation(t)  # known probing force; eq. 10 integrates it with u
        return u, xd, xs

    def continuous(self, t: float, x: np.ndarray, z: np.ndarray, p: tuple) -> tuple[np.ndarray, np.ndarray]:
        """Continuous-time law: force [N] and the derivative of the controller states
        ``z = [int (x - x*), int x, int K x, int u]`` (4n)."""
        n = self.n
        u, _, xs = self._law(t, x, z[:n], z[n:2 * n], z[2 * n:3 * n], z[3 * n:], p)
        return u, np.concatenate((x - xs, x, p[2] @ x, u))

    def sampled_force(self, k: int, t: float, x_meas: np.ndarray) -> np.ndarray:
        """Sampled law at ``t_k`` from measured positions [m]: the force [N] held until
        ``t_{k+1}``. Integrals: trapezoidal for positions, exact for the held force."""
        xs = self.reference.evaluate(t)[0]
        e = x_meas - xs
        kx = self._p_k[2] @ x_meas
        if k > 0:
            h2 = 0.5 * self.dt
            self._E = self._E + h2 * (self._e_prev + e)
            self._X = self._X + h2 * (self._x_prev + x_meas)
            self._S = self._S + h2 * (self._kx_prev + kx)
            self._U = self._U + self.dt * self._u_prev
        u, xd, _ = self._law(t, x_meas, self._E, self._X, self._S, self._U, self._p_k)
        self._x_prev, self._kx_prev, self._e_prev, self._u_prev = x_meas.copy(), kx, e, u
        if k < self._T:
            self._log["velocity_estimate"][k] = xd
            self._log["force_command"][k] = u
        return u

    # ---- estimator ----------------------------------------------------------------------
    def observe(self, k: int, t: float, accel: np.ndarray, force: np.ndarray,
                x_meas: np.ndarray, z: Optional[np.ndarray] = None) -> None:
        """Feed sample ``k`` (accelerations [m/s^2], forces [N]) to the estimator and keep
        its valid estimates for the following intervals."""
        n = self.n
        if z is not None and k < self._T:
            u, xd, _ = self._law(t, x_meas, z[:n], z[n:2 * n], z[2 * n:3 * n], z[3 * n:], self._p_k)
            self._log["velocity_estimate"][k] = xd
            self._log["force_command"][k] = u
        status = self.estimator.update(accel, force)
        m = np.asarray(self.estimator.mass, dtype=float)
        c = np.asarray(self.estimator.damping, dtype=float)
        kk = np.asarray(self.estimator.stiffness, dtype=float)
        valid = np.asarray(self.estimator.valid, dtype=bool)
        if k < self._T:
            L = self._log
            L["est_mass"][k], L["est_damping"][k], L["est_stiffness"][k] = m, c, kk
            L["est_valid"][k] = valid
            if self._has_sigma:
                L["est_sigma"][k] = np.asarray(self.estimator.sigma, dtype=float)
            if self._has_theta:
                for i in range(n):
                    L["est_theta"][k, i] = self.estimator.theta(i)
            L["status"][k] = int(status)
        self._accept(k, m, c, kk, valid)

    def _accept(self, k: int, m: np.ndarray, c: np.ndarray, kk: np.ndarray, valid: np.ndarray) -> None:
        """Take the estimates of every DOF that passes the acceptance rule."""
        n, W = self.n, self._win
        slot = k % W
        self._hist_m[slot], self._hist_c[slot], self._hist_k[slot] = m, c, kk
        self._hist_n = min(self._hist_n + 1, W)
        k_left, k_right = kk[:n], kk[1:]
        # the structurally unidentifiable right spring (n = 1 with walls, free end) is NaN
        kr = np.where(np.isnan(k_right) & self._k_right_absent, 0.0, k_right)
        ok = valid & np.isfinite(m) & np.isfinite(c) & np.isfinite(k_left) & np.isfinite(kr) & (m > 0)
        if self.accept in ("settled", "sigma"):
            ok &= (c >= 0) & (k_left >= 0) & (kr >= 0)
            if self.accept == "sigma":
                pass  # the estimator's valid flag carries the uncertainty test
            elif self._hist_n < W:
                ok[:] = False
            else:
                tol = self.settle_tol
                c_floor = 0.01 * 2.0 * np.sqrt(np.abs((k_left + kr) * m))  # 1 % of critical
                with np.errstate(invalid="ignore"):
                    dm = np.max(np.abs(self._hist_m - m), axis=0) <= tol * np.abs(m)
                    dc = np.max(np.abs(self._hist_c - c), axis=0) <= tol * np.maximum(np.abs(c), c_floor)
                    dk = np.max(np.abs(self._hist_k - kk), axis=0)
                    dk_ok = (dk <= tol * np.abs(kk)) | (np.isnan(kk) & np.append(np.zeros(n, bool), self._k_right_absent[-1]))
                ok &= dm & dc & dk_ok[:n] & dk_ok[1:]
            if self._first_accept is None and not np.all(ok):
                # the first substitution takes all DOFs together: a spring between an
                # accepted and a rejected DOF would otherwise get a half-garbage value
                return
        if self.hold and self._first_accept is not None:
            return
        if not np.any(ok):
            return
        self._good_m[ok] = m[ok]
        self._good_c[ok] = c[ok]
        self._accepted |= ok
        # a spring is estimated by the DOFs at its ends: take it from an accepted neighbour
        near = np.zeros(n + 1, bool)
        near[:n] |= ok
        near[1:] |= ok
        near &= np.isfinite(kk)
        self._good_k[near] = kk[near]
        self._dirty = True
        if self._first_accept is None:
            self._first_accept = k

    # ---- history ------------------------------------------------------------------------
    def log(self) -> dict[str, Any]:
        """History of the run (``T`` samples): reference ``x_ref``, ``xd_ref``, ``xdd_ref``
        (T, n); ``estimates`` = estimator output after each sample (``mass``, ``damping``
        (T, n), ``stiffness`` (T, n+1) fused, ``valid`` (T, n), ``status`` (T,), and ``theta``
        (T, n, 4): each DOF's own ``[m_i, c_i, k_i, k_{i+1}]`` when the estimator has
        ``theta(dof)``, else NaN); ``used`` = the
        parameters the law used on each interval; ``velocity_estimate`` (eq. 10) and
        ``force_command`` (T, n) at the samples; gains, poles, switch time and the
        estimator's ``delay_samples``."""
        T = self._T
        t = np.arange(T) * self.dt
        xs, xd, xdd = self.reference.evaluate(t)
        L = self._log
        return {
            "t": t, "x_ref": xs, "xd_ref": xd, "xdd_ref": xdd,
            "estimates": {"mass": L["est_mass"], "damping": L["est_damping"],
                          "stiffness": L["est_stiffness"], "valid": L["est_valid"],
                          "theta": L["est_theta"], "sigma": L["est_sigma"],
                          "status": L["status"]},
            "used": {"mass": L["used_mass"], "damping": L["used_damping"],
                     "stiffness": L["used_stiffness"]},
            "velocity_estimate": L["velocity_estimate"], "force_command": L["force_command"],
            "gains": self.gains, "poles": [complex(p) for p in self.poles], "eq10": self.eq10,
            "switch_time_s": self.switch_time_s, "k_switch": self.k_switch,
            "delay_samples": int(getattr(self.estimator, "delay_samples", 0)),
            "accept": self.accept, "hold": self.hold,
            "running_from_s": (None if getattr(self.estimator, "running_from", None) is None
                               else self.estimator.running_from * self.dt), "first_accepted_s": (None if self._first_accept is None
                                                       else self._first_accept * self.dt),
        }
