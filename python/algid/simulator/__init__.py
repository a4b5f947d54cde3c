"""Plant simulator of the n-DOF chain of eq. 1, with sensors, unmodelled effects and a
closed loop.

    m_i x_i'' + c_i x_i' + k_i (x_i - x_{i-1}) + k_{i+1} (x_i - x_{i+1}) = u_i + g_i(t, x, x')   (1)

``g`` collects the switched-on :class:`Effect` forces (none by default). Spring ``j``
(1-based, ``j = 1 .. n+1``) joins DOF ``j-1`` and DOF ``j``; DOF 0 and DOF ``n+1`` are the
walls. Its *deformation* is ``d_j = x_j - x_{j-1}`` (wall positions 0); a spring force
``s(d_j)`` pushes DOF ``j`` by ``-s`` and DOF ``j-1`` by ``+s``. A spring network
(:class:`~algid.model.network.NetworkModel`) is simulated the same way, open loop: its spring
``s = (a, b)`` has ``d_s = x_b - x_a`` and pushes DOF ``b`` by ``-s``, DOF ``a`` by ``+s``.

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
a clearance contact engaging or releasing) is redone in 8 sub-steps.
``tests/test_simulator.py`` checks every kind of run against scipy's ``solve_ivp`` and a
zero-order-hold response against its exact discretisation (the agreement: ``docs/theory.md``).

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
terms, the parameters of a DOF come out biased (``tests/test_simulator.py`` checks both
pairings; ``docs/theory.md`` gives the figures). Positions and velocities are
continuous and need no convention. The first sample
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
With a ``controller`` (see :mod:`algid.control.controller`), ``continuous`` mode evaluates the
control law inside the ODE (its integrator states are integrated with the plant), with
the parameters it uses held constant over each sample interval; ``sampled`` mode runs the
law once per sample on the measured positions and holds its force. In both modes the
controller's estimator is fed, sample by sample, the measured accelerations and recorded
forces, and the parameters it uses on ``[t_k, t_{k+1})`` depend on samples up to ``k - 1``
(one sample of computation latency), so the force samples of the convention above are
well defined. The simulator asks of a controller only what :class:`Controller` (sampled
mode) or :class:`ContinuousController` (continuous mode) names.

Package
-------
:mod:`.inputs` validates the arguments, :mod:`.schedule` cuts every sample interval into
steps, :mod:`.state_space` holds the state layout, the linear system and the stepper,
:mod:`.pieces` the force pieces, :mod:`.open_loop` and :mod:`.closed_loop` drive a run and
:mod:`.sensors` reads it; :mod:`.plant` and :mod:`.effects` are the plant, :mod:`.result`
what a run returns and :mod:`.protocol` what a controller provides.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from typing import Any, Callable

import numpy as np

from ..model.chain import Chain
from ..model.network import NetworkModel
from .closed_loop import ClosedLoop
from .effects import COULOMB_V_EPS, EFFECT_NAMES, Effect
from .inputs import ForceInput, RunInputs, validate_inputs
from .open_loop import run_open_loop
from .plant import effect_forces
from .protocol import ContinuousController, Controller
from .result import Samples, SimulationResult
from .run import Progress, Run, build_run
from .sensors import Readings, SensorNoise, closed_loop_noise_scale, readings

__all__ = [
    "EFFECT_NAMES",
    "COULOMB_V_EPS",
    "ContinuousController",
    "Controller",
    "Effect",
    "SensorNoise",
    "SimulationResult",
    "effect_forces",
    "simulate",
]


def simulate(
    chain: Chain | NetworkModel,
    force: ForceInput,
    duration_s: float,
    fs_hz: float = 1000.0,
    *,
    effects: Sequence[Effect | Mapping[str, Any]] = (),
    noise_db: float | None = None,
    noise_on: Sequence[str] = ("accel",),
    seed: int | None = None,
    controller: Controller | None = None,
    mode: str = "continuous",
    actuator_lag_s: float = 0.0,
    x0: np.ndarray | None = None,
    v0: np.ndarray | None = None,
    progress: Callable[[float], None] | None = None,
    noise: SensorNoise | None = None,
    force_interp: str = "cubic",
    substeps: int | None = None,
    encoder_resolution_m: float = 0.0,
) -> SimulationResult:
    """Simulate the chain and sample its sensors (conventions in the module docstring).

    Parameters
    ----------
    chain : Chain or NetworkModel
        Plant parameters and boundary, or a spring network's
        (:class:`~algid.model.network.NetworkModel`: open loop only; effects at its springs
        by the network's spring numbers).
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
    controller : Controller or None
        Closed-loop controller producing the force (``force`` must then be None), e.g.
        :class:`algid.control.controller.TrackingController`; in continuous mode a
        :class:`ContinuousController`.
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
    inp = validate_inputs(
        chain,
        force,
        duration_s,
        fs_hz,
        effects=effects,
        noise_db=noise_db,
        noise_on=noise_on,
        seed=seed,
        noise=noise,
        controller=controller,
        mode=mode,
        actuator_lag_s=actuator_lag_s,
        x0=x0,
        v0=v0,
        force_interp=force_interp,
        substeps=substeps,
        encoder_resolution_m=encoder_resolution_m,
    )
    run = build_run(inp, Progress(progress, inp.T))
    unit = inp.noise.unit_noise(inp.T, inp.n) if inp.noise is not None else {}
    noise_scale: dict[str, np.ndarray] = {}
    if inp.closed:
        noise_scale = closed_loop_noise_scale(inp.chain, inp.controller, inp.noise, inp.t)
        samples = ClosedLoop(run, noise_scale, unit).drive()
    else:
        samples = run_open_loop(run)
    res = _result(inp, samples, readings(samples, unit, inp.noise, noise_scale, inp.encoder_resolution_m))
    if inp.closed:
        log = inp.controller.log()
        res.controller_log = log
        res.x_ref = log.get("x_ref")
        res.estimates = log.get("estimates")
    run.report.done()
    res.stats = _stats(run, time.perf_counter() - wall0)
    return res


def _result(inp: RunInputs, samples: Samples, read: Readings) -> SimulationResult:
    return SimulationResult(
        t=inp.t,
        x=samples.x,
        v=samples.v,
        a=read.a,
        a_true=samples.a_true,
        u=read.u,
        u_applied=samples.u_applied,
        x_meas=read.x_meas,
        chain=inp.chain,
        effects=inp.effects,
        fs_hz=inp.fs_hz,
        mode=inp.mode,
        limits=samples.limits,
        noise_rms=read.noise_rms,
        snr_db=read.snr_db,
    )


def _stats(run: Run, wall_s: float) -> dict[str, Any]:
    """Integrator statistics of a finished run."""
    effs = run.inputs.effects
    return {
        "substeps_per_sample": run.schedule.J,
        "refined_steps": run.stepper.refined,
        "v_eps": {effs[q].dof + 1: v for q, v in run.schedule.v_eps.items()},
        "integrator": "etdrk4" if run.rk else "exact",
        "wall_s": wall_s,
    }
