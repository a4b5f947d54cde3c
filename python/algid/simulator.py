"""Plant simulator of the n-DOF chain of eq. 1, with sensors, unmodelled effects and a
closed loop.

    m_i x_i'' + c_i x_i' + k_i (x_i - x_{i-1}) + k_{i+1} (x_i - x_{i+1}) = u_i + g_i(t, x, x')   (1)

``g`` collects the switched-on :class:`Effect` forces (none by default). Spring ``j``
(1-based, ``j = 1 .. n+1``) joins DOF ``j-1`` and DOF ``j``; DOF 0 and DOF ``n+1`` are the
walls. Its *deformation* is ``d_j = x_j - x_{j-1}`` (wall positions 0); a spring force
``s(d_j)`` pushes DOF ``j`` by ``-s`` and DOF ``j-1`` by ``+s``.

Integration
-----------
Exponential integration, sample interval by sample interval. Everything linear in the
state (the chain of eq. 1, the accelerometer low-pass, the actuator lag) is propagated
*exactly* with the matrix exponential and the phi-functions of ``h L``, precomputed once
per run; a force that is a polynomial over the interval (held, linearly or cubically
interpolated, see below) enters exactly through ``int e^{L(h-s)} B s^j ds``. Whatever is
not linear (the mechanical effects, and the control law in ``continuous`` mode) enters
through the fourth-order exponential Runge-Kutta scheme ETDRK4 of Cox and Matthews (2002),
with ``h = 1 / fs`` (optionally ``substeps`` per interval). So a linear chain is exact to
rounding at any sample rate, and the nonlinear parts are integrated at fourth order with
a 1 ms step or better, as the paper's RKF45 at 1 ms. Steep effects set the step: a
clearance contact of stiffness ``k_c`` gets ``h sqrt(k_c / m) <= 0.25`` by automatic
sub-steps, and the dry-friction regularisation width defaults to
``v_eps = max(1e-4 m/s, F / (m_i f_sub))`` (``f_sub`` the sub-step rate) so that its
relaxation rate ``F / (m v_eps)`` never exceeds one per step (an explicit ``v_eps`` gets
enough sub-steps instead). A step across a switch (a dry-friction velocity changing sign,
a clearance contact engaging or releasing) is redone in 8 sub-steps. Measured against
scipy's ``solve_ivp`` (DOP853, rtol 1e-11) at 1 kHz: linear chains 1e-10 relative,
smooth effects (cubic spring, quadratic damping, drift, low-pass) 1e-8, clearance 1e-6,
dry friction 2e-5 (``tests/test_simulator.py``; a zero-order-hold response matches its
exact discretisation to 1e-12).

Force input
-----------
``force`` is the *command*:

* a callable ``f(t) -> (n,)`` [N] (``t`` in s);
* an array ``(T, n)`` [N] sampled at ``fs_hz`` from ``t = 0`` (``(T,)`` for ``n = 1``);
* ``None``: no force (free response from ``x0, v0``), or the output of ``controller``.

``mode="continuous"``: callables are evaluated at every integrator stage; arrays are
interpolated by a C2 cubic spline through the samples (``force_interp="cubic"``, not-a-knot
ends) or piecewise linearly (``force_interp="linear"``); the recorded samples then equal
the given array. ``mode="sampled"``: the command is sampled at ``t_k`` (array row ``k``,
callable ``f(t_k)``, or the controller evaluated once per sample) and held until
``t_{k+1}`` (zero-order hold, as a DAC does). ``actuator_lag_s > 0`` passes the command
through a first-order lag ``tau w' = u_cmd - w`` (state ``w(0) = 0``); the force sensor
then reads the actuator output ``w``. The ``input_delay`` effect delays what reaches the
plant behind the force sensor; before ``t = 0`` the recorded force is taken as zero
(the plant was at rest), so a delayed channel receives no force until ``t = delay``.

Samples
-------
``T = round(duration_s * fs_hz)`` samples at ``t_k = k / fs_hz``, ``k = 0 .. T-1``.

**Sampling convention.** Force and acceleration are sampled *simultaneously* from the
continuous signals, as a real acquisition does. Where the force jumps at a sample instant
(a held command in ``sampled`` mode, or the controller switching to new estimates, e.g. the
substitution at 0.1 s), the acceleration jumps with it and both signals have two one-sided
limits at ``t_k``. The sample is then the **mean of the two one-sided limits of both the
force and the acceleration** (``a_k = (a(t_k-) + a(t_k+))/2``, the same for ``u``), the value
of the staircase's smooth equivalent at the sample instant. Pairing the limits any other
way (held force with the acceleration just before the update, or the new force with the
acceleration just after) makes the estimator's quadrature of eq. 4 integrate two signals
that are half a sample out of step, and because eq. 4 forms small differences of large
terms, the parameters of a DOF come out biased by 10-60 % instead of a few 1e-4 (Table 1,
multisine of 1.3-7.1 Hz held at 1 kHz, 0.5-2 s, estimated with the numpy reference
:func:`algid.reference.estimate`; ``tests/test_simulator.py`` checks both; noise-free
continuous forcing gives 1e-9, so the remaining few 1e-4 is what a held force costs
the estimator's smooth quadrature, not the simulator). Positions and velocities are continuous and need no convention. The first sample
(``t = 0``) takes the right limit, the recording starting there. The one-sided limits are
kept in :attr:`SimulationResult.limits`.

Sensors
-------
Accelerometers (``a``), force sensors (``u``) and position sensors (``x_meas``) at every
DOF. ``noise_db`` is the signal-to-noise ratio per channel: white Gaussian noise of RMS
``rms(clean channel) * 10**(-noise_db / 20)`` is added to the channels named in
``noise_on`` (any of ``"accel"``, ``"force"``, ``"position"``), drawn from independent
streams per channel kind derived from ``seed`` (reproducible; switching one channel kind
on does not change another's noise). In open loop the clean channel's RMS over the whole
record sets the level. With a controller the noise has to exist while the loop runs, so
the level is set beforehand from the RMS of the nominal closed-loop signals (reference
position, reference acceleration and the exact-model feedforward force along the
reference); the noise RMS actually used and the SNR actually achieved are reported in
:attr:`SimulationResult.noise_rms` and :attr:`SimulationResult.snr_db`.

Closed loop
-----------
With a ``controller`` (see :mod:`algid.controller`), ``continuous`` mode evaluates the
control law inside the ODE (its integrator states are integrated with the plant), with
the parameters it uses held constant over each sample interval; ``sampled`` mode runs the
law once per sample on the measured positions and holds its force. In both modes the
controller's estimator is fed, sample by sample, the measured accelerations and recorded
forces, and the parameters it uses on ``[t_k, t_{k+1})`` depend on samples up to ``k - 1``
(one sample of computation latency), so the force samples of the convention above are
well defined.
"""

from __future__ import annotations

import math
import time
from math import factorial
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Optional, Sequence, Union

import numpy as np

from .chain import Chain

__all__ = [
    "EFFECT_NAMES",
    "COULOMB_V_EPS",
    "Effect",
    "SensorNoise",
    "SimulationResult",
    "effect_forces",
    "simulate",
]

#: Smallest velocity scale [m/s] of the dry-friction regularisation ``F tanh(v / v_eps)``
#: (the default is ``max(COULOMB_V_EPS, F / (m_i f_sub))``, see the module docstring).
COULOMB_V_EPS = 1e-4

#: ``name -> (location key, required params, optional params)``.
_EFFECT_SPECS: dict[str, tuple[str, tuple[str, ...], tuple[str, ...]]] = {
    "coulomb_friction": ("dof", ("force",), ("v_eps",)),
    "quadratic_damping": ("dof", ("c2",), ()),
    "cubic_stiffness": ("spring", ("k3",), ()),
    "clearance": ("spring", ("gap", "stiffness"), ()),
    "input_delay": ("dof", ("delay",), ()),
    "sensor_bias": ("dof", ("bias",), ()),
    "sensor_lowpass": ("dof", ("cutoff_hz",), ()),
    "parameter_drift": ("spring", ("rel_change",), ()),
    "force_offset": ("dof", ("offset",), ()),
    "stribeck_friction": ("dof", ("force", "static", "v_stribeck"), ("v_eps",)),
    "amplitude_damping": ("spring", ("c_amp",), ()),
}

#: The effect names the simulator knows (part of the public interface).
EFFECT_NAMES: tuple[str, ...] = tuple(_EFFECT_SPECS)

CHANNELS = ("accel", "force", "position")


@dataclass(frozen=True)
class Effect:
    """One unmodelled effect switched on in the plant or its sensors.

    Parameters
    ----------
    name : str
        One of :data:`EFFECT_NAMES`:

        ``coulomb_friction``  location ``{"dof": i}``, params ``{"force": F [N]}``
            (optional ``"v_eps"`` [m/s]): a force ``-F tanh(v_i / v_eps)`` on mass i
            (smooth, steep dry friction; default ``v_eps`` in the module docstring).
        ``quadratic_damping``  ``{"dof": i}``, ``{"c2": [N s^2/m^2]}``: ``-c2 v_i |v_i|``.
        ``cubic_stiffness``  ``{"spring": j}``, ``{"k3": [N/m^3]}``: spring force
            ``k3 d_j^3`` added to spring j (negative ``k3`` softens).
        ``clearance``  ``{"spring": j}``, ``{"gap": [m], "stiffness": [N/m]}``: a contact
            in parallel with spring j, force ``stiffness (|d_j| - gap) sign(d_j)`` when
            ``|d_j| > gap``, zero otherwise.
        ``input_delay``  ``{"dof": i}``, ``{"delay": [s]}``: the force reaching mass i lags
            the recorded one by ``delay``.
        ``sensor_bias``  ``{"dof": i}``, ``{"bias": [m/s^2]}``: accelerometer i reads
            ``bias`` more than the truth.
        ``sensor_lowpass``  ``{"dof": i}``, ``{"cutoff_hz": [Hz]}``: accelerometer i is a
            first-order low-pass ``a_meas' = 2 pi f_c (a - a_meas)``, starting settled
            (``a_meas(0) = a(0+)``).
        ``parameter_drift``  ``{"spring": j}``, ``{"rel_change": r}``: stiffness of spring j
            becomes ``k_j (1 + r t / duration)`` (linear over the record).
        ``force_offset``  ``{"dof": i}``, ``{"offset": [N]}``: a constant force on mass i
            that the force sensor does not see (gravity on an inclined axis, a preload,
            a drive's current-sensor offset).
        ``stribeck_friction``  ``{"dof": i}``, ``{"force": F_c [N], "static": F_s [N],
            "v_stribeck": v_s [m/s]}`` (optional ``"v_eps"``): dry friction that breaks
            away at ``F_s`` and falls to ``F_c`` with speed,
            ``-(F_c + (F_s - F_c) exp(-(v_i / v_s)^2)) tanh(v_i / v_eps)``.
        ``amplitude_damping``  ``{"spring": j}``, ``{"c_amp": [N s/m^2]}``: micro-slip in
            the joint of spring j, a damping force ``c_amp |d_j| d_j'`` whose equivalent
            viscous damping grows with the deformation amplitude.
    location : dict
        ``{"dof": i}`` with ``1 <= i <= n`` or ``{"spring": j}`` with ``1 <= j <= n+1``
        (``j <= n`` for a free right end); 1-based as in the paper.
    params : dict
        Effect parameters in SI units as listed above.
    """

    name: str
    location: Mapping[str, int]
    params: Mapping[str, float]

    def __post_init__(self) -> None:
        if self.name not in _EFFECT_SPECS:
            raise ValueError(f"unknown effect {self.name!r}; known: {', '.join(EFFECT_NAMES)}")
        key, required, optional = _EFFECT_SPECS[self.name]
        loc = dict(self.location) if self.location is not None else {}
        if set(loc) != {key}:
            raise ValueError(f"effect {self.name!r} takes location {{{key!r}: index}}, got {loc!r}")
        idx = loc[key]
        if isinstance(idx, bool) or not float(idx).is_integer():
            raise ValueError(f"effect {self.name!r}: {key} index must be an integer, got {idx!r}")
        params = dict(self.params) if self.params is not None else {}
        missing = [p for p in required if p not in params]
        unknown = [p for p in params if p not in required + optional]
        if missing or unknown:
            raise ValueError(f"effect {self.name!r} takes params {required}"
                             + (f" (optional {optional})" if optional else "")
                             + f"; missing {missing}, unknown {unknown}")
        clean = {}
        for p, val in params.items():
            try:
                val = float(val)
            except (TypeError, ValueError):
                raise ValueError(f"effect {self.name!r}: param {p!r} must be a number, got {val!r}") from None
            if not math.isfinite(val):
                raise ValueError(f"effect {self.name!r}: param {p!r} must be finite, got {val}")
            clean[p] = val
        _check_param_ranges(self.name, clean)
        object.__setattr__(self, "location", {key: int(idx)})
        object.__setattr__(self, "params", clean)

    @property
    def dof(self) -> Optional[int]:
        """0-based DOF index, or None for a spring effect."""
        return self.location["dof"] - 1 if "dof" in self.location else None

    @property
    def spring(self) -> Optional[int]:
        """1-based spring index, or None for a DOF effect."""
        return self.location.get("spring")

    def check(self, chain: Chain) -> None:
        """Raise ``ValueError`` if the location does not exist on ``chain``."""
        n = chain.n
        if "dof" in self.location:
            i = self.location["dof"]
            if not 1 <= i <= n:
                raise ValueError(f"effect {self.name!r}: dof {i} outside 1..{n}")
        else:
            j = self.location["spring"]
            top = n + 1 if chain.boundary == "fixed" else n
            if not 1 <= j <= top:
                raise ValueError(f"effect {self.name!r}: spring {j} outside 1..{top} "
                                 f"({chain.boundary} right end)")

    def to_dict(self) -> dict:
        """JSON-friendly ``{"effect", "location", "params"}``."""
        return {"effect": self.name, "location": dict(self.location), "params": dict(self.params)}


def _check_param_ranges(name: str, p: dict) -> None:
    positive = {"cutoff_hz", "v_eps", "v_stribeck"}
    nonneg = {"force", "c2", "gap", "stiffness", "delay", "static", "c_amp"}
    for key, val in p.items():
        if key in positive and not val > 0:
            raise ValueError(f"effect {name!r}: {key} must be > 0, got {val}")
        if key in nonneg and val < 0:
            raise ValueError(f"effect {name!r}: {key} must be >= 0, got {val}")
    if name == "stribeck_friction" and p["static"] < p["force"]:
        raise ValueError(f"effect 'stribeck_friction': static ({p['static']}) must be >= force ({p['force']})")
    if name == "parameter_drift" and not p["rel_change"] > -1.0:
        raise ValueError(f"effect 'parameter_drift': rel_change must be > -1, got {p['rel_change']}")


def _as_effect(e: Union[Effect, Mapping[str, Any]]) -> Effect:
    if isinstance(e, Effect):
        return e
    if isinstance(e, Mapping):
        name = e.get("name", e.get("effect"))
        return Effect(name, e.get("location", {}), e.get("params", {}))
    raise ValueError(f"effects must be Effect instances or dicts, got {type(e).__name__}")


@dataclass(frozen=True)
class SensorNoise:
    """Additive white Gaussian measurement noise.

    Parameters
    ----------
    snr_db : float
        Signal-to-noise ratio per channel [dB]: noise RMS = signal RMS * 10**(-snr_db/20).
    channels : tuple of str
        Which sensor kinds are noisy: any of ``"accel"``, ``"force"``, ``"position"``.
    seed : int or None
        Seed of the noise streams (one independent stream per channel kind).
    """

    snr_db: float
    channels: tuple[str, ...] = ("accel",)
    seed: Optional[int] = None

    def __post_init__(self) -> None:
        if not math.isfinite(float(self.snr_db)):
            raise ValueError(f"snr_db must be finite, got {self.snr_db}")
        chans = (self.channels,) if isinstance(self.channels, str) else tuple(self.channels)
        bad = [c for c in chans if c not in CHANNELS]
        if bad:
            raise ValueError(f"noise channels must be among {CHANNELS}, got {bad}")
        object.__setattr__(self, "channels", chans)
        object.__setattr__(self, "snr_db", float(self.snr_db))

    @property
    def ratio(self) -> float:
        """Noise RMS over signal RMS."""
        return 10.0 ** (-self.snr_db / 20.0)

    def unit_noise(self, T: int, n: int) -> dict[str, np.ndarray]:
        """White Gaussian noise ``(T, n)`` scaled to unit RMS per column, for each channel
        kind named in ``channels``."""
        streams = np.random.SeedSequence(self.seed).spawn(len(CHANNELS))
        out = {}
        for c, s in zip(CHANNELS, streams):
            if c in self.channels:
                w = np.random.default_rng(s).standard_normal((T, n))
                out[c] = w / np.sqrt(np.mean(w**2, axis=0))  # exactly unit RMS: the SNR is exact
        return out


@dataclass
class SimulationResult:
    """Sampled output of :func:`simulate` (``T`` samples, ``n`` DOF).

    Attributes
    ----------
    t : (T,) sample times [s]
    x : (T, n) true positions [m]
    v : (T, n) true velocities [m/s]
    a : (T, n) measured accelerations [m/s^2] (sensor effects and noise included)
    a_true : (T, n) true accelerations [m/s^2] (mean of one-sided limits at jumps)
    u : (T, n) recorded forces [N]: what the force sensors read (noisy if asked)
    u_applied : (T, n) forces acting on the masses [N]
    x_meas : (T, n) measured positions [m] (noisy if asked)
    chain : the simulated :class:`~algid.chain.Chain`
    effects : the effects switched on
    fs_hz : sample rate [Hz]
    mode : "continuous" or "sampled"
    limits : one-sided limits at the sample instants, noise-free: ``a_minus``, ``a_plus``
        [m/s^2], ``u_minus``, ``u_plus`` (recorded) and ``u_applied_minus``,
        ``u_applied_plus`` [N], each (T, n)
    noise_rms : noise RMS used per noisy channel kind, each (n,) [SI units]
    snr_db : SNR achieved per noisy channel kind, each (n,) [dB]
    x_ref : (T, n) reference positions [m] when a controller ran, else None
    estimates : estimator history when a controller ran (see
        :meth:`algid.controller.TrackingController.log`), else None
    controller_log : the controller's full log, else None
    stats : integrator statistics (steps, rejected steps, wall time [s])
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    a_true: np.ndarray
    u: np.ndarray
    u_applied: np.ndarray
    x_meas: np.ndarray
    chain: Chain
    effects: tuple[Effect, ...]
    fs_hz: float
    mode: str = "continuous"
    limits: dict[str, np.ndarray] = field(default_factory=dict)
    noise_rms: dict[str, np.ndarray] = field(default_factory=dict)
    snr_db: dict[str, np.ndarray] = field(default_factory=dict)
    x_ref: Optional[np.ndarray] = None
    estimates: Optional[dict[str, np.ndarray]] = None
    controller_log: Optional[dict[str, Any]] = None
    stats: dict[str, float] = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of DOF."""
        return int(self.x.shape[1])

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return 1.0 / self.fs_hz

    def to_arrays(self) -> dict[str, np.ndarray]:
        """The recording format: ``t``, ``u1..un`` [N], ``a1..an`` [m/s^2], ``x1..xn`` [m]
        (measured signals, 1-based names)."""
        out = {"t": self.t.copy()}
        for name, arr in (("u", self.u), ("a", self.a), ("x", self.x_meas)):
            for i in range(self.n):
                out[f"{name}{i + 1}"] = arr[:, i].copy()
        return out


# --------------------------------------------------------------------------------------
# exponential integration


def _phi(Z: np.ndarray, p: int) -> list[np.ndarray]:
    """``[e^Z, phi_1(Z), .., phi_p(Z)]`` (``phi_j(Z) = sum_k Z^k / (k + j)!``) from one
    exponential of the block matrix ``[[Z, I, 0..], [0, 0, I, ..], .., [0 ..]]``."""
    from scipy.linalg import expm

    m = Z.shape[0]
    big = np.zeros(((p + 1) * m, (p + 1) * m))
    big[:m, :m] = Z
    for j in range(p):
        big[j * m:(j + 1) * m, (j + 1) * m:(j + 2) * m] = np.eye(m)
    Eb = expm(big)
    return [Eb[:m, j * m:(j + 1) * m] for j in range(p + 1)]


class _Propagator:
    """Matrices of one step of length ``ell`` [s] for ``s' = L s + B u(t) + N(t, s)``.

    ``G[j]`` maps the coefficient of ``tau^j`` of a polynomial input to its exact effect on
    the state after the step; ``E2, Gh, Q, F1..F3`` are the ETDRK4 matrices (Cox and
    Matthews 2002) for the nonlinear part, which enters as ``Bn @ N(t, s)``.
    """

    def __init__(self, L: np.ndarray, B: np.ndarray, ell: float, rk: bool,
                 Bn: Optional[np.ndarray] = None) -> None:
        ph = _phi(ell * L, 4)
        self.ell = ell
        self.E = ph[0]
        self.G = np.stack([factorial(j) * ell ** (j + 1) * (ph[j + 1] @ B) for j in range(4)])
        self.rk = rk
        if rk:
            hf = _phi(0.5 * ell * L, 4)
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

    def step(self, s: np.ndarray, t0: float, wf: np.ndarray, wh: np.ndarray, w2: np.ndarray,
             N: Callable[[float, np.ndarray], np.ndarray], n0: Optional[np.ndarray] = None) -> np.ndarray:
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


def _shift(c: np.ndarray, tau0: Union[float, np.ndarray]) -> np.ndarray:
    """Re-expand cubic pieces ``c[..., j, :]`` (coefficient of ``tau^j``) about ``tau0``."""
    c0, c1, c2, c3 = c[..., 0, :], c[..., 1, :], c[..., 2, :], c[..., 3, :]
    return np.stack([c0 + tau0 * (c1 + tau0 * (c2 + tau0 * c3)),
                     c1 + tau0 * (2.0 * c2 + 3.0 * tau0 * c3),
                     c2 + 3.0 * tau0 * c3,
                     c3], axis=-2)


def _peval(c: np.ndarray, tau: float) -> np.ndarray:
    """Value of cubic pieces ``c[..., 4, n]`` at local time ``tau``."""
    return c[..., 0, :] + tau * (c[..., 1, :] + tau * (c[..., 2, :] + tau * c[..., 3, :]))


# --------------------------------------------------------------------------------------
# the plant


class _Plant:
    """Linear part of eq. 1 and the effect forces."""

    def _effect_force_1(self, t: float, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """:meth:`effect_force` for one state, in scalar arithmetic."""
        return self.state_force(t, np.concatenate((x, v)))

    def state_force(self, t: float, state: np.ndarray) -> np.ndarray:
        """Effect forces [N] from a state vector starting ``[x, v, ..]`` (the integrator's
        hot path: plain float arithmetic, faster than numpy on a few entries)."""
        n = self.n
        vals = state.tolist()
        xs = vals[:n]
        vs = vals[n:2 * n]
        f = [0.0] * n
        for kind, i, a, fs, vs_, eps in self.dof_terms:
            vi = vs[i]
            if kind == "fo":
                f[i] += a
            elif kind == "cf":
                level = a if fs == a else a + (fs - a) * math.exp(-(vi / vs_) ** 2)
                f[i] -= level * math.tanh(vi / eps)
            else:
                f[i] -= a * vi * abs(vi)
        for kind, j, a, b in self.spring_terms:  # spring j (0-based) joins DOF j-1 and DOF j
            d = (xs[j] if j < n else 0.0) - (xs[j - 1] if j >= 1 else 0.0)
            if kind == "cs":
                s = a * d * d * d
            elif kind == "cl":
                ad = abs(d) - a
                s = b * ad * (1.0 if d > 0 else -1.0) if ad > 0 else 0.0
            elif kind == "ad":
                dd = (vs[j] if j < n else 0.0) - (vs[j - 1] if j >= 1 else 0.0)
                s = a * abs(d) * dd
            else:
                s = a * t * d
            if j < n:
                f[j] -= s
            if j >= 1:
                f[j - 1] += s
        return np.array(f)

    def __init__(self, chain: Chain, effects: Sequence[Effect], duration_s: float,
                 v_eps: dict[int, float]) -> None:
        n = chain.n
        _, _, K = chain.matrices()
        self.n = n
        self.minv = 1.0 / chain.mass
        self.c = chain.damping.copy()
        self.K = K
        D = np.zeros((n + 1, n))  # d = D x, d_j = x_j - x_{j-1} (walls 0)
        for j in range(n + 1):
            if j < n:
                D[j, j] = 1.0
            if j >= 1:
                D[j, j - 1] = -1.0
        self.D = D
        # (kind, dof, level, static level, Stribeck velocity, regularisation velocity)
        self.dof_terms: list[tuple[str, int, float, float, float, float]] = []
        for q, e in enumerate(effects):
            p = e.params
            if e.name == "coulomb_friction":
                self.dof_terms.append(("cf", e.dof, p["force"], p["force"], 1.0, v_eps[q]))
            elif e.name == "stribeck_friction":
                self.dof_terms.append(("cf", e.dof, p["force"], p["static"], p["v_stribeck"], v_eps[q]))
            elif e.name == "quadratic_damping":
                self.dof_terms.append(("qd", e.dof, p["c2"], 0.0, 0.0, 0.0))
            elif e.name == "force_offset":
                self.dof_terms.append(("fo", e.dof, p["offset"], 0.0, 0.0, 0.0))

        def rows(kind: str) -> tuple[Optional[np.ndarray], list[Effect]]:
            sel = [e for e in effects if e.name == kind]
            return (D[[e.spring - 1 for e in sel]] if sel else None), sel

        self.cs_D, cs = rows("cubic_stiffness")
        self.cs_k3 = np.array([e.params["k3"] for e in cs])
        self.cl_D, cl = rows("clearance")
        self.cl_gap = np.array([e.params["gap"] for e in cl])
        self.cl_k = np.array([e.params["stiffness"] for e in cl])
        self.dr_D, dr = rows("parameter_drift")
        self.dr_rate = np.array([chain.stiffness[e.spring - 1] * e.params["rel_change"] / duration_s
                                 for e in dr])
        self.ad_D, ad = rows("amplitude_damping")
        self.ad_c = np.array([e.params["c_amp"] for e in ad])
        self.spring_terms: list[tuple[str, int, float, float]] = (
            [("cs", e.spring - 1, e.params["k3"], 0.0) for e in cs]
            + [("cl", e.spring - 1, e.params["gap"], e.params["stiffness"]) for e in cl]
            + [("dr", e.spring - 1, r, 0.0) for e, r in zip(dr, self.dr_rate)]
            + [("ad", e.spring - 1, e.params["c_amp"], 0.0) for e in ad])
        self.nonlinear = bool(self.dof_terms or cs or cl or dr or ad)
        self.has_switches = bool(cl) or any(kind == "cf" for kind, *_ in self.dof_terms)

    def switch_state(self, state: np.ndarray) -> tuple:
        """Which side of its switch every steep effect is on: the sign of each dry-friction
        velocity and whether each clearance contact is engaged (a change within a step
        makes the integrator redo that step with finer sub-steps)."""
        n = self.n
        vals = state.tolist()
        out = [vals[n + i] > 0.0 for kind, i, *_ in self.dof_terms if kind == "cf"]
        for kind, j, gap, _ in self.spring_terms:
            if kind == "cl":
                d = (vals[j] if j < n else 0.0) - (vals[j - 1] if j >= 1 else 0.0)
                out.append(abs(d) > gap)
        return tuple(out)

    def effect_force(self, t: Union[float, np.ndarray], x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Sum of the effect forces [N] on each mass; ``x, v`` (n,) or (T, n) with ``t``
        scalar or (T,)."""
        if np.ndim(x) == 1:
            return self._effect_force_1(t, x, v)
        f = np.zeros(np.shape(x))
        for kind, i, a, fs, vs_, eps in self.dof_terms:
            vi = v[..., i]
            if kind == "fo":
                f[..., i] += a
            elif kind == "cf":
                f[..., i] -= (a + (fs - a) * np.exp(-(vi / vs_) ** 2)) * np.tanh(vi / eps)
            else:
                f[..., i] -= a * vi * np.abs(vi)
        if self.cs_D is not None:
            d = x @ self.cs_D.T
            f -= (self.cs_k3 * d * d * d) @ self.cs_D
        if self.cl_D is not None:
            d = x @ self.cl_D.T
            f -= (self.cl_k * np.maximum(np.abs(d) - self.cl_gap, 0.0) * np.sign(d)) @ self.cl_D
        if self.dr_D is not None:
            d = x @ self.dr_D.T
            tt = np.asarray(t)[..., None] if np.ndim(t) else t
            f -= (self.dr_rate * tt * d) @ self.dr_D
        if self.ad_D is not None:
            d, dd = x @ self.ad_D.T, v @ self.ad_D.T
            f -= (self.ad_c * np.abs(d) * dd) @ self.ad_D
        return f


# --------------------------------------------------------------------------------------
# simulate


def simulate(
    chain: Chain,
    force: Union[Callable[[float], np.ndarray], np.ndarray, None],
    duration_s: float,
    fs_hz: float = 1000.0,
    *,
    effects: Sequence[Union[Effect, Mapping[str, Any]]] = (),
    noise_db: Optional[float] = None,
    noise_on: Sequence[str] = ("accel",),
    seed: Optional[int] = None,
    controller: Any = None,
    mode: str = "continuous",
    actuator_lag_s: float = 0.0,
    x0: Optional[np.ndarray] = None,
    v0: Optional[np.ndarray] = None,
    progress: Optional[Callable[[float], None]] = None,
    noise: Optional[SensorNoise] = None,
    force_interp: str = "cubic",
    substeps: Optional[int] = None,
    encoder_resolution_m: float = 0.0,
) -> SimulationResult:
    """Simulate the chain and sample its sensors (conventions in the module docstring).

    Parameters
    ----------
    chain : Chain
        Plant parameters and boundary.
    force : callable, array or None
        Force command [N]: ``f(t) -> (n,)``, samples ``(T, n)`` at ``fs_hz`` (at least
        ``T = round(duration_s * fs_hz)`` rows), or None (no force, or a controller).
    duration_s : float
        Record length [s].
    fs_hz : float
        Sample rate [Hz] of the sensors (and of a sampled controller).
    effects : sequence of Effect (or dicts ``{"name", "location", "params"}``)
        Unmodelled effects to switch on.
    noise_db : float or None
        Sensor SNR per channel [dB]; None for noise-free sensors.
    noise_on : sequence of str
        Noisy sensor kinds among ``"accel"``, ``"force"``, ``"position"``.
    seed : int or None
        Seed of the noise.
    controller : algid.controller.TrackingController or None
        Closed-loop controller producing the force (``force`` must then be None).
    mode : {"continuous", "sampled"}
        Continuous-time force (callables, interpolated arrays, controller inside the ODE)
        or a zero-order-held force updated at every sample.
    actuator_lag_s : float
        Time constant [s] of a first-order actuator lag (0 = none).
    x0, v0 : array (n,) or None
        Initial positions [m] and velocities [m/s] (default rest).
    progress : callable or None
        Called with the fraction done (0..1) about every 1 % of the samples.
    noise : SensorNoise or None
        Alternative to ``noise_db / noise_on / seed``.
    force_interp : {"cubic", "linear"}
        Interpolation of a force array in continuous mode (cubic: C2 not-a-knot spline).
    substeps : int or None
        Integration steps per sample interval (None: 1, or more if a steep effect needs).
    encoder_resolution_m : float
        Position sensors that count increments of this size [m] (an incremental encoder:
        the reading is ``q round(x / q)``, after any position noise); 0 = exact readings.
        A closed loop sees the quantised readings too.

    Returns
    -------
    SimulationResult
    """
    wall0 = time.perf_counter()
    if not isinstance(chain, Chain):
        raise ValueError(f"chain must be an algid.Chain, got {type(chain).__name__}")
    n = chain.n
    if mode not in ("continuous", "sampled"):
        raise ValueError(f"mode must be 'continuous' or 'sampled', got {mode!r}")
    if force_interp not in ("cubic", "linear"):
        raise ValueError(f"force_interp must be 'cubic' or 'linear', got {force_interp!r}")
    duration_s = float(duration_s)
    fs_hz = float(fs_hz)
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise ValueError(f"duration_s must be > 0, got {duration_s}")
    if not (math.isfinite(fs_hz) and fs_hz > 0):
        raise ValueError(f"fs_hz must be > 0, got {fs_hz}")
    T = int(round(duration_s * fs_hz))
    if T < 2:
        raise ValueError("duration_s * fs_hz must give at least 2 samples")
    h = 1.0 / fs_hz
    tgrid = np.arange(T) / fs_hz
    actuator_lag_s = float(actuator_lag_s)
    if not (math.isfinite(actuator_lag_s) and actuator_lag_s >= 0):
        raise ValueError(f"actuator_lag_s must be >= 0, got {actuator_lag_s}")
    if substeps is not None and (int(substeps) != substeps or substeps < 1):
        raise ValueError(f"substeps must be a positive integer, got {substeps}")
    encoder_resolution_m = float(encoder_resolution_m)
    if not (math.isfinite(encoder_resolution_m) and encoder_resolution_m >= 0):
        raise ValueError(f"encoder_resolution_m must be >= 0, got {encoder_resolution_m}")

    def encoder(x: np.ndarray) -> np.ndarray:
        q = encoder_resolution_m
        return x if q == 0 else q * np.round(x / q)

    effs = tuple(_as_effect(e) for e in effects)
    for e in effs:
        e.check(chain)
    for kind in ("input_delay", "sensor_lowpass"):
        dofs = [e.dof for e in effs if e.name == kind]
        if len(dofs) != len(set(dofs)):
            raise ValueError(f"effect {kind!r} given twice for the same dof")

    # ---- noise
    if noise is not None and noise_db is not None:
        raise ValueError("give either noise or noise_db, not both")
    if noise is None and noise_db is not None:
        noise = SensorNoise(float(noise_db), tuple(noise_on), seed)
    unit = noise.unit_noise(T, n) if noise is not None else {}

    # ---- initial state
    x_init = np.zeros(n) if x0 is None else np.asarray(x0, dtype=float).reshape(-1)
    v_init = np.zeros(n) if v0 is None else np.asarray(v0, dtype=float).reshape(-1)
    if x_init.size != n or v_init.size != n:
        raise ValueError(f"x0 and v0 need {n} entries")

    # ---- force source
    closed = controller is not None
    if closed and force is not None:
        raise ValueError("give either a force or a controller, not both")
    U_arr = None
    f_call = None
    if force is None:
        pass
    elif callable(force):
        f_call = force
        probe = np.asarray(force(0.0), dtype=float).reshape(-1)
        if probe.size != n:
            raise ValueError(f"force(t) must return {n} values, got {probe.size}")
    else:
        U_arr = np.asarray(force, dtype=float)
        if U_arr.ndim == 1 and n == 1:
            U_arr = U_arr[:, None]
        if U_arr.ndim != 2 or U_arr.shape[1] != n:
            raise ValueError(f"force array must have shape (T, {n}), got {U_arr.shape}")
        if U_arr.shape[0] < T:
            raise ValueError(f"force array has {U_arr.shape[0]} samples, the record needs {T}")
        U_arr = U_arr[:T]
        if not np.all(np.isfinite(U_arr)):
            raise ValueError("force array contains non-finite values")

    delays = np.zeros(n)
    for e in effs:
        if e.name == "input_delay":
            delays[e.dof] = e.params["delay"]
    has_delay = bool(np.any(delays > 0))
    if has_delay and actuator_lag_s > 0:
        raise ValueError("input_delay together with actuator_lag_s is not supported")
    if has_delay and closed and mode == "continuous":
        raise ValueError("input_delay inside a continuous-time control loop makes a delay "
                         "differential equation; use mode='sampled'")
    if np.any(delays >= duration_s):
        raise ValueError("input_delay must be shorter than the record")

    # ---- steps: sub-intervals split at delay fractions and substeps
    ns = 1 if substeps is None else int(substeps)
    for e in effs:  # a clearance contact must be resolved: h_sub sqrt(k_c / m) <= 0.25
        if e.name == "clearance" and substeps is None:
            j = e.spring - 1
            adj = [chain.mass[i] for i in (j - 1, j) if 0 <= i < n]
            w = math.sqrt(e.params["stiffness"] / min(adj))
            ns = max(ns, int(math.ceil(h * w / 0.25)))
    v_eps: dict[int, float] = {}
    dry = ("coulomb_friction", "stribeck_friction")
    peak = {q: e.params.get("static", e.params.get("force")) for q, e in enumerate(effs) if e.name in dry}
    for q, e in enumerate(effs):
        if e.name in dry:
            mi = chain.mass[e.dof]
            if "v_eps" in e.params:
                v_eps[q] = e.params["v_eps"]
                if substeps is None:
                    ns = max(ns, int(math.ceil(peak[q] * h / (mi * v_eps[q]))))
    for q, e in enumerate(effs):
        if e.name in dry and q not in v_eps:
            v_eps[q] = max(COULOMB_V_EPS, peak[q] * h / ns / chain.mass[e.dof])
    cuts = {round(q / ns, 12) for q in range(1, ns)}
    if has_delay:
        cuts |= {round((d * fs_hz) % 1.0, 12) for d in delays if d > 0}
    cuts = sorted(c for c in cuts if 1e-9 < c < 1 - 1e-9)
    bnds = [0.0] + cuts + [1.0]
    J = len(bnds) - 1
    lens = [(bnds[q + 1] - bnds[q]) * h for q in range(J)]

    # ---- plant and state layout: [x, v, low-pass states, actuator states, controller states]
    plant = _Plant(chain, effs, duration_s, v_eps)
    minv, cdamp, Kmat = plant.minv, plant.c, plant.K
    lp = sorted((e.dof, 2 * np.pi * e.params["cutoff_hz"]) for e in effs if e.name == "sensor_lowpass")
    lp_idx = np.array([i for i, _ in lp], dtype=int)
    lp_wc = np.array([w for _, w in lp])
    bias = np.zeros(n)
    for e in effs:
        if e.name == "sensor_bias":
            bias[e.dof] += e.params["bias"]
    n_lp = lp_idx.size
    lag = actuator_lag_s > 0
    n_w = n if lag else 0
    ctrl_cont = closed and mode == "continuous"
    if closed:
        controller.start(chain_n=n, dt=h, boundary=chain.boundary, samples=T, mode=mode)
    n_z = int(controller.n_states) if ctrl_cont else 0
    o_lp = 2 * n
    o_w = o_lp + n_lp
    o_z = o_w + n_w
    m_state = o_z + n_z

    Lm = np.zeros((m_state, m_state))
    Lm[:n, n:2 * n] = np.eye(n)
    Lm[n:2 * n, :n] = -minv[:, None] * Kmat
    Lm[n:2 * n, n:2 * n] = -np.diag(minv * cdamp)
    Bg = np.zeros((m_state, n))  # how a force on the masses enters
    Bg[n:2 * n] = np.diag(minv)
    if lag:
        Lm[n:2 * n, o_w:o_z] = np.diag(minv)
        Lm[o_w:o_z, o_w:o_z] = -np.eye(n) / actuator_lag_s
    if n_lp:
        Lm[o_lp:o_w] = lp_wc[:, None] * Lm[n + lp_idx]
        Lm[o_lp:o_w, o_lp:o_w] -= np.diag(lp_wc)
        Bg[o_lp:o_w] = lp_wc[:, None] * Bg[n + lp_idx]
    if lag:
        B_in = np.zeros((m_state, n))
        B_in[o_w:o_z] = np.eye(n) / actuator_lag_s
    else:
        B_in = Bg
    nonlinear = plant.nonlinear
    rk = nonlinear or ctrl_cont
    props: dict[float, _Propagator] = {}
    for ell in lens:
        key = round(ell * fs_hz, 12)
        if key not in props:
            props[key] = _Propagator(Lm, B_in, ell, rk, None if ctrl_cont else Bg)
    P = [props[round(ell * fs_hz, 12)] for ell in lens]
    # a step across a friction reversal or a contact switch is redone in REFINE sub-steps
    REFINE = 8
    P_fine: list[_Propagator] = []
    if plant.has_switches:
        fine: dict[float, _Propagator] = {}
        for ell in lens:
            key = round(ell * fs_hz, 12)
            if key not in fine:
                fine[key] = _Propagator(Lm, B_in, ell / REFINE, True, None if ctrl_cont else Bg)
        P_fine = [fine[round(ell * fs_hz, 12)] for ell in lens]
    n_refined = [0]
    sw_cache: list[Any] = [None, None]  # (state, its switch state)

    def rk_step(q: int, s0: np.ndarray, t0: float, coef: Optional[np.ndarray], wf: np.ndarray,
                wh: np.ndarray, w2: np.ndarray, N: Callable, n0: Optional[np.ndarray] = None) -> np.ndarray:
        """One ETDRK4 step over sub-interval ``q``, redone finely across a switch;
        ``coef`` (4, n) is the polynomial input on the sub-interval (None: no input)."""
        s1 = P[q].step(s0, t0, wf, wh, w2, N, n0)
        if not P_fine:
            return s1
        sw0 = sw_cache[1] if sw_cache[0] is s0 else plant.switch_state(s0)
        sw1 = plant.switch_state(s1)
        if sw1 == sw0:
            sw_cache[0], sw_cache[1] = s1, sw1
            return s1
        n_refined[0] += 1
        Pf = P_fine[q]
        ell = Pf.ell
        s1 = s0
        for j in range(REFINE):
            if coef is None:
                s1 = Pf.step(s1, t0 + j * ell, wf * 0.0, wh * 0.0, w2 * 0.0, N)
            else:
                c = _shift(coef, j * ell)
                fwf = np.einsum("jmn,jn->m", Pf.G, c)
                fwh = np.einsum("jmn,jn->m", Pf.Gh, c)
                s1 = Pf.step(s1, t0 + j * ell, fwf, fwh, fwf - Pf.E2 @ fwh, N)
        return s1

    # ---- recorded force pieces per interval (open loop): rec[k, j] = coefficient of tau^j
    rec = None
    if not closed:
        rec = np.zeros((T, 4, n))
        if mode == "sampled":
            if U_arr is not None:
                rec[:, 0] = U_arr
            elif f_call is not None:
                rec[:, 0] = [np.asarray(f_call(tk), dtype=float).reshape(n) for tk in tgrid]
        elif U_arr is not None:
            if force_interp == "cubic" and T >= 4:
                from scipy.interpolate import CubicSpline

                cs = CubicSpline(tgrid, U_arr, axis=0, bc_type="not-a-knot")
                rec[:-1] = np.transpose(cs.c[::-1], (1, 0, 2))
            else:
                rec[:-1, 0] = U_arr[:-1]
                rec[:-1, 1] = (U_arr[1:] - U_arr[:-1]) / h
            rec[-1] = _shift(rec[-2], h)
        elif f_call is not None:
            tn = np.arange(3 * T + 1) * (h / 3.0)
            vals = np.array([np.asarray(f_call(tt), dtype=float).reshape(n) for tt in tn])
            nodes = np.arange(4) * (h / 3.0)
            Vinv = np.linalg.inv(nodes[:, None] ** np.arange(4)[None, :])
            idx = 3 * np.arange(T)[:, None] + np.arange(4)[None, :]
            rec = np.einsum("jq,kqn->kjn", Vinv, vals[idx])

    # ---- what reaches the plant on each sub-interval: delayed channels read earlier pieces
    src_off = np.zeros((J, n), dtype=int)
    src_tau = np.zeros((J, n))
    for q in range(J):
        sq = bnds[q] - delays * fs_hz
        j0 = np.floor(sq + 1e-7).astype(int)
        src_off[q] = j0
        src_tau[q] = np.maximum(sq - j0, 0.0) * h

    def applied_pieces(recp: np.ndarray) -> np.ndarray:
        """(T, J, 4, n) applied pieces from recorded pieces (T, 4, n)."""
        out = np.zeros((recp.shape[0], J, 4, n))
        kk = np.arange(recp.shape[0])
        for q in range(J):
            for i in range(n):
                src = kk + src_off[q, i]
                ok = src >= 0
                out[ok, q, :, i] = _shift(recp[src[ok], :, i:i + 1], src_tau[q, i])[..., 0]
        return out

    # ---- noise scale for a closed loop (must exist while the loop runs)
    noise_scale: dict[str, np.ndarray] = {}
    if closed and noise is not None:
        nominal = _nominal_closed_loop_rms(chain, controller, tgrid)
        noise_scale = {c: nominal[c] * noise.ratio for c in noise.channels}

    s = np.zeros(m_state)
    s[:n] = x_init
    s[n:2 * n] = v_init
    every = max(1, T // 100)

    def report(k: int) -> None:
        if progress is not None and k % every == 0:
            progress(k / T)

    N_open = plant.state_force  # N(t, s) = effect forces, entering as Bg @ N

    lim = {k: np.empty((T, n)) for k in ("a_minus", "a_plus", "u_minus", "u_plus",
                                         "u_applied_minus", "u_applied_plus")}

    if not closed:
        # ---------------- open loop: inputs known beforehand
        app = applied_pieces(rec)
        Wf = np.empty((T, J, m_state))
        for q in range(J):
            Wf[:, q] = np.einsum("jmn,kjn->km", P[q].G, app[:, q])
        if nonlinear:
            Wh = np.empty((T, J, m_state))
            W2 = np.empty((T, J, m_state))
            for q in range(J):
                Wh[:, q] = np.einsum("jmn,kjn->km", P[q].Gh, app[:, q])
                W2[:, q] = Wf[:, q] - Wh[:, q] @ P[q].E2.T
        app_r = app[:, 0, 0]
        app_l = np.empty((T, n))
        app_l[0] = app_r[0]
        app_l[1:] = _peval(app[:-1, J - 1], lens[-1])
        if n_lp:  # the low-pass accelerometers start settled on a(0+)
            f0 = (s[o_w:o_z] if lag else app_r[0]) - cdamp * s[n:2 * n] - Kmat @ s[:n]
            if nonlinear:
                f0 = f0 + plant.effect_force(0.0, s[:n], s[n:2 * n])
            s[o_lp:o_w] = (f0 * minv)[lp_idx]
        S = np.empty((T, m_state))
        Es = [p.E for p in P]
        for k in range(T):
            S[k] = s
            if k == T - 1:
                break
            report(k)
            if nonlinear:
                tq = tgrid[k]
                for q in range(J):
                    s = rk_step(q, s, tq, app[k, q], Wf[k, q], Wh[k, q], W2[k, q], N_open)
                    tq += lens[q]
            else:
                for q in range(J):
                    s = Es[q] @ s + Wf[k, q]
            if k % 256 == 0 and not np.all(np.isfinite(s)):
                raise RuntimeError(f"the simulation diverged before t = {tgrid[k + 1]:.6g} s")
        X, V = S[:, :n], S[:, n:2 * n]
        g_all = plant.effect_force(tgrid, X, V) if nonlinear else 0.0
        if lag:
            app_l = app_r = S[:, o_w:o_z]
            rec_l = rec_r = S[:, o_w:o_z]
        else:
            rec_r = rec[:, 0]
            rec_l = np.empty((T, n))
            rec_l[0] = rec_r[0]
            rec_l[1:] = _peval(rec[:-1], h)
        base = g_all - V * cdamp - X @ Kmat.T
        lim["a_minus"][:] = (app_l + base) * minv
        lim["a_plus"][:] = (app_r + base) * minv
        lim["u_minus"][:], lim["u_plus"][:] = rec_l, rec_r
        lim["u_applied_minus"][:], lim["u_applied_plus"][:] = app_l, app_r
        A_true = 0.5 * (lim["a_minus"] + lim["a_plus"])
        U_rec = 0.5 * (rec_l + rec_r)
        U_app = 0.5 * (app_l + app_r)
        A_clean = A_true.copy()
        if n_lp:
            A_clean[:, lp_idx] = S[:, o_lp:o_w]
        A_clean += bias
        X = X.copy()
        V = V.copy()
    else:
        # ---------------- closed loop: the controller acts sample by sample
        X = np.empty((T, n))
        V = np.empty((T, n))
        A_true = np.empty((T, n))
        A_clean = np.empty((T, n))
        U_rec = np.empty((T, n))
        U_app = np.empty((T, n))
        A_meas = np.empty((T, n))
        U_meas = np.empty((T, n))
        X_meas = np.empty((T, n))
        rec_hist = np.zeros((T, n))
        cur_params: list[Any] = [None]

        last_u: list[Any] = [None]

        def N_ctrl(t: float, st: np.ndarray) -> np.ndarray:
            x = st[:n]
            u, dz = controller.continuous(t, x, st[o_z:], cur_params[0])
            last_u[0] = u
            out = B_in @ u
            if nonlinear:
                out = out + Bg @ plant.effect_force(t, x, st[n:2 * n])
            out[o_z:] = dz
            return out

        left_rec = left_app = None
        zero_w = np.zeros(m_state)
        for k in range(T):
            tk = tgrid[k]
            params = controller.params_for_sample(k, s[o_z:] if ctrl_cont else None)
            cur_params[0] = params
            x = s[:n]
            v = s[n:2 * n]
            base = -cdamp * v - Kmat @ x
            if nonlinear:
                base = base + plant.effect_force(tk, x, v)
            xm_k = x + noise_scale["position"] * unit["position"][k] if "position" in noise_scale else x.copy()
            xm_k = encoder(xm_k)
            if mode == "sampled":
                xm = xm_k.copy()
                u_k = np.asarray(controller.sampled_force(k, tk, xm), dtype=float).reshape(n)
                rec_hist[k] = u_k
                app_q = np.empty((J, n))
                for q in range(J):
                    src = k + src_off[q]
                    app_q[q] = np.where(src >= 0, rec_hist[np.clip(src, 0, T - 1), np.arange(n)], 0.0)
                cmd_r, app_r = u_k, app_q[0]
            else:
                n0 = N_ctrl(tk, s)
                cmd_r = app_r = last_u[0]
            if lag:
                rec_r = app_r = s[o_w:o_z].copy()
            else:
                rec_r = cmd_r
            a_r = (app_r + base) * minv
            if k == 0:
                if n_lp:
                    s[o_lp:o_w] = a_r[lp_idx]
                left_rec, left_app = rec_r, app_r
            a_l = (left_app + base) * minv
            lim["a_minus"][k], lim["a_plus"][k] = a_l, a_r
            lim["u_minus"][k], lim["u_plus"][k] = left_rec, rec_r
            lim["u_applied_minus"][k], lim["u_applied_plus"][k] = left_app, app_r
            X[k], V[k] = x, v
            A_true[k] = 0.5 * (a_l + a_r)
            U_rec[k] = 0.5 * (left_rec + rec_r)
            U_app[k] = 0.5 * (left_app + app_r)
            am = A_true[k].copy()
            if n_lp:
                am[lp_idx] = s[o_lp:o_w]
            am += bias
            A_clean[k] = am
            if "accel" in noise_scale:
                am = am + noise_scale["accel"] * unit["accel"][k]
            um = U_rec[k] + noise_scale["force"] * unit["force"][k] if "force" in noise_scale else U_rec[k].copy()
            A_meas[k], U_meas[k], X_meas[k] = am, um, xm_k
            controller.observe(k, tk, am, um, x.copy() if ctrl_cont else xm_k, s[o_z:].copy() if ctrl_cont else None)
            report(k)
            if k == T - 1:
                break
            # -- integrate interval k
            if mode == "sampled":
                tq = tk
                for q in range(J):
                    wf = P[q].G[0] @ app_q[q]
                    if rk:
                        wh = P[q].Gh[0] @ app_q[q]
                        coef = np.zeros((4, n))
                        coef[0] = app_q[q]
                        s = rk_step(q, s, tq, coef, wf, wh, wf - P[q].E2 @ wh, N_open)
                    else:
                        s = P[q].E @ s + wf
                    tq += lens[q]
                left_app = app_q[J - 1]
                left_rec = u_k
            else:
                tq = tk
                for q in range(J):
                    s = rk_step(q, s, tq, None, zero_w, zero_w, zero_w, N_ctrl, n0 if q == 0 else None)
                    tq += lens[q]
                u_l, _ = controller.continuous(tgrid[k + 1], s[:n], s[o_z:], params)
                left_app = left_rec = u_l
            if lag:
                left_app = left_rec = s[o_w:o_z].copy()
            if not np.all(np.isfinite(s)):
                raise RuntimeError(f"the simulation diverged before t = {tgrid[k + 1]:.6g} s")

    # ---- sensors and noise
    noise_rms: dict[str, np.ndarray] = {}
    snr: dict[str, np.ndarray] = {}
    level = {"accel": A_true, "force": U_rec, "position": X}
    if closed:
        a_out, u_out, x_out = A_meas, U_meas, X_meas
        for c, sc in noise_scale.items():
            noise_rms[c] = sc * np.sqrt(np.mean(unit[c] ** 2, axis=0))
    else:
        clean = {"accel": A_clean, "force": U_rec, "position": X}
        noisy = {}
        for c in CHANNELS:
            if c in unit:
                sc = _rms(level[c]) * noise.ratio
                noisy[c] = clean[c] + sc * unit[c]
                noise_rms[c] = sc * np.sqrt(np.mean(unit[c] ** 2, axis=0))
        a_out = noisy.get("accel", A_clean)
        u_out = noisy.get("force", U_rec.copy())
        x_out = encoder(noisy.get("position", X.copy()))
    for c, r in noise_rms.items():
        with np.errstate(divide="ignore", invalid="ignore"):
            snr[c] = 20 * np.log10(_rms(level[c]) / np.where(r > 0, r, np.nan))

    res = SimulationResult(
        t=tgrid, x=X, v=V, a=a_out, a_true=A_true, u=u_out, u_applied=U_app, x_meas=x_out,
        chain=chain, effects=effs, fs_hz=fs_hz, mode=mode, limits=lim, noise_rms=noise_rms,
        snr_db=snr,
    )
    if closed:
        log = controller.log()
        res.controller_log = log
        res.x_ref = log.get("x_ref")
        res.estimates = log.get("estimates")
    if progress is not None:
        progress(1.0)
    res.stats = {"substeps_per_sample": J, "refined_steps": n_refined[0], "v_eps": {effs[q].dof + 1: v for q, v in v_eps.items()},
                 "integrator": "etdrk4" if rk else "exact", "wall_s": time.perf_counter() - wall0}
    return res


def effect_forces(chain: Chain, effects: Sequence[Union[Effect, Mapping[str, Any]]], t: np.ndarray,
                  x: np.ndarray, v: np.ndarray, duration_s: Optional[float] = None) -> np.ndarray:
    """The forces [N] (T, n) the effects put on the masses along a prescribed motion
    ``x`` [m], ``v`` [m/s] (T, n) at times ``t`` [s] (T,): what the simulator adds to eq. 1.
    A device driven in displacement needs ``M a + C v + K x - effect_forces(...)`` from its
    actuator. Dry friction uses ``v_eps`` if given, else ``COULOMB_V_EPS``."""
    effs = tuple(_as_effect(e) for e in effects)
    for e in effs:
        e.check(chain)
    duration = float(t[-1] - t[0]) if duration_s is None else float(duration_s)
    v_eps = {q: e.params.get("v_eps", COULOMB_V_EPS) for q, e in enumerate(effs)
             if e.name in ("coulomb_friction", "stribeck_friction")}
    return _Plant(chain, effs, duration, v_eps).effect_force(np.asarray(t, dtype=float), np.asarray(x, dtype=float),
                                                             np.asarray(v, dtype=float))


def _rms(a: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(np.asarray(a) ** 2, axis=0))


def _nominal_closed_loop_rms(chain: Chain, controller: Any, t: np.ndarray) -> dict[str, np.ndarray]:
    """RMS per DOF of the signals a perfectly tracking loop would produce: reference
    position [m], reference acceleration [m/s^2] and the exact-model force [N]."""
    ref = controller.reference
    if ref is None:
        from .controller import BezierReference

        ref = BezierReference.paper(chain.n)
    xs, xd, xdd = ref.evaluate(t)
    M, C, K = chain.matrices()
    u = xdd @ M.T + xd @ C.T + xs @ K.T
    return {"position": _rms(xs), "accel": _rms(xdd), "force": _rms(u)}
