"""Input validation of :func:`algid.simulator.simulate`: every argument checked and
converted once (SI floats, arrays of the right shape, effects as :class:`Effect`), the
force source resolved and the input delays collected."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Callable, Union

import numpy as np

from ..model.chain import Chain
from ..model.network import NetworkModel
from .effects import Effect, as_effect
from .protocol import Controller
from .sensors import SensorNoise

__all__ = ["RunInputs", "validate_inputs"]

#: A force command: ``f(t [s]) -> (n,)`` [N], samples (T, n) [N], or None.
ForceInput = Union[Callable[[float], np.ndarray], np.ndarray, None]


@dataclass(frozen=True)
class RunInputs:
    """The validated arguments of one simulation (``T`` samples of an ``n``-DOF chain).

    ``t`` (T,) sample times [s]; ``force_samples`` (T, n) [N] or ``force_fn`` ``t -> (n,)``
    [N] (both None: no force, or a controller); ``x0`` [m], ``v0`` [m/s] (n,) initial
    state; ``delays`` (n,) input delay of every DOF [s]; the rest as :func:`algid.simulator.simulate`.
    """

    chain: Chain | NetworkModel
    duration_s: float
    fs_hz: float
    t: np.ndarray
    mode: str
    force_interp: str
    actuator_lag_s: float
    substeps: int | None
    encoder_resolution_m: float
    effects: tuple[Effect, ...]
    noise: SensorNoise | None
    x0: np.ndarray
    v0: np.ndarray
    force_samples: np.ndarray | None
    force_fn: Callable[[float], np.ndarray] | None
    controller: Controller | None
    delays: np.ndarray

    @property
    def n(self) -> int:
        return self.chain.n

    @property
    def T(self) -> int:
        """Number of samples."""
        return int(self.t.size)

    @property
    def h(self) -> float:
        """Sample interval [s]."""
        return 1.0 / self.fs_hz

    @property
    def closed(self) -> bool:
        """A controller produces the force."""
        return self.controller is not None

    @property
    def controller_in_ode(self) -> bool:
        """The control law runs inside the ODE (continuous-mode closed loop)."""
        return self.closed and self.mode == "continuous"


def validate_inputs(
    chain: Chain,
    force: ForceInput,
    duration_s: float,
    fs_hz: float,
    *,
    effects: Sequence[Effect | Mapping[str, Any]],
    noise_db: float | None,
    noise_on: Sequence[str],
    seed: int | None,
    noise: SensorNoise | None,
    controller: Controller | None,
    mode: str,
    actuator_lag_s: float,
    x0: np.ndarray | None,
    v0: np.ndarray | None,
    force_interp: str,
    substeps: int | None,
    encoder_resolution_m: float,
) -> RunInputs:
    """Check the arguments of :func:`algid.simulator.simulate` (same names and units) and
    raise ``ValueError`` on the first one that is wrong."""
    if not isinstance(chain, (Chain, NetworkModel)):
        raise ValueError(f"chain must be an algid.Chain or an algid.NetworkModel, got {type(chain).__name__}")
    if isinstance(chain, NetworkModel) and controller is not None:
        raise ValueError("the controllers drive chains only: simulate a network model open loop (force=...)")
    if mode not in ("continuous", "sampled"):
        raise ValueError(f"mode must be 'continuous' or 'sampled', got {mode!r}")
    if force_interp not in ("cubic", "linear"):
        raise ValueError(f"force_interp must be 'cubic' or 'linear', got {force_interp!r}")
    duration_s, fs_hz, T = _record_length(duration_s, fs_hz)
    actuator_lag_s = _non_negative("actuator_lag_s", actuator_lag_s)
    if substeps is not None and (int(substeps) != substeps or substeps < 1):
        raise ValueError(f"substeps must be a positive integer, got {substeps}")
    encoder_resolution_m = _non_negative("encoder_resolution_m", encoder_resolution_m)
    effs = _checked_effects(chain, effects)
    if noise is not None and noise_db is not None:
        raise ValueError("give either noise or noise_db, not both")
    if noise is None and noise_db is not None:
        noise = SensorNoise(float(noise_db), tuple(noise_on), seed)
    x_init, v_init = _initial_state(chain.n, x0, v0)
    if controller is not None and force is not None:
        raise ValueError("give either a force or a controller, not both")
    U, f_call = _force_source(force, chain.n, T)
    delays = _input_delays(effs, chain.n, duration_s, actuator_lag_s, controller is not None and mode == "continuous")
    return RunInputs(
        chain=chain,
        duration_s=duration_s,
        fs_hz=fs_hz,
        t=np.arange(T) / fs_hz,
        mode=mode,
        force_interp=force_interp,
        actuator_lag_s=actuator_lag_s,
        substeps=None if substeps is None else int(substeps),
        encoder_resolution_m=encoder_resolution_m,
        effects=effs,
        noise=noise,
        x0=x_init,
        v0=v_init,
        force_samples=U,
        force_fn=f_call,
        controller=controller,
        delays=delays,
    )


def _record_length(duration_s: float, fs_hz: float) -> tuple[float, float, int]:
    """``(duration_s, fs_hz, T)`` as floats and the number of samples."""
    duration_s = float(duration_s)
    fs_hz = float(fs_hz)
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise ValueError(f"duration_s must be > 0, got {duration_s}")
    if not (math.isfinite(fs_hz) and fs_hz > 0):
        raise ValueError(f"fs_hz must be > 0, got {fs_hz}")
    T = int(round(duration_s * fs_hz))
    if T < 2:
        raise ValueError("duration_s * fs_hz must give at least 2 samples")
    return duration_s, fs_hz, T


def _non_negative(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f"{name} must be >= 0, got {value}")
    return value


def _checked_effects(chain: Chain, effects: Sequence[Effect | Mapping[str, Any]]) -> tuple[Effect, ...]:
    effs = tuple(as_effect(e) for e in effects)
    for e in effs:
        e.check(chain)
    for kind in ("input_delay", "sensor_lowpass", "sensor_highpass"):
        dofs = [e.dof for e in effs if e.name == kind]
        if len(dofs) != len(set(dofs)):
            raise ValueError(f"effect {kind!r} given twice for the same dof")
    low = {e.dof for e in effs if e.name == "sensor_lowpass"}
    both = sorted(e.dof + 1 for e in effs if e.name == "sensor_highpass" and e.dof in low)
    if both:
        raise ValueError(f"sensor_lowpass and sensor_highpass on the same accelerometer (dof {both}) are not supported")
    return effs


def _initial_state(n: int, x0: np.ndarray | None, v0: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    x_init = np.zeros(n) if x0 is None else np.asarray(x0, dtype=float).reshape(-1)
    v_init = np.zeros(n) if v0 is None else np.asarray(v0, dtype=float).reshape(-1)
    if x_init.size != n or v_init.size != n:
        raise ValueError(f"x0 and v0 need {n} entries")
    return x_init, v_init


def _force_source(force: ForceInput, n: int, T: int) -> tuple[np.ndarray | None, Callable | None]:
    """``(samples (T, n), None)``, ``(None, callable)`` or ``(None, None)``."""
    if force is None:
        return None, None
    if callable(force):
        probe = np.asarray(force(0.0), dtype=float).reshape(-1)
        if probe.size != n:
            raise ValueError(f"force(t) must return {n} values, got {probe.size}")
        return None, force
    U = np.asarray(force, dtype=float)
    if U.ndim == 1 and n == 1:
        U = U[:, None]
    if U.ndim != 2 or U.shape[1] != n:
        raise ValueError(f"force array must have shape (T, {n}), got {U.shape}")
    if U.shape[0] < T:
        raise ValueError(f"force array has {U.shape[0]} samples, the record needs {T}")
    U = U[:T]
    if not np.all(np.isfinite(U)):
        raise ValueError("force array contains non-finite values")
    return U, None


def _input_delays(
    effs: tuple[Effect, ...], n: int, duration_s: float, actuator_lag_s: float, controller_in_ode: bool
) -> np.ndarray:
    """Input delay [s] of every DOF (n,), checked against what the integrator supports."""
    delays = np.zeros(n)
    for e in effs:
        if e.name == "input_delay":
            delays[e.dof] = e.params["delay"]
    has_delay = bool(np.any(delays > 0))
    if has_delay and actuator_lag_s > 0:
        raise ValueError("input_delay together with actuator_lag_s is not supported")
    if has_delay and controller_in_ode:
        raise ValueError(
            "input_delay inside a continuous-time control loop makes a delay differential equation; use mode='sampled'"
        )
    if np.any(delays >= duration_s):
        raise ValueError("input_delay must be shorter than the record")
    return delays
