"""What a simulation returns (:class:`SimulationResult`) and the noise-free samples a
driver hands to the sensors (:class:`Samples`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..model.chain import Chain
from ..model.network import NetworkModel
from .effects import Effect

__all__ = ["LIMIT_NAMES", "Samples", "SimulationResult"]

#: The one-sided limits kept at every sample instant (:attr:`SimulationResult.limits`).
LIMIT_NAMES = ("a_minus", "a_plus", "u_minus", "u_plus", "u_applied_minus", "u_applied_plus")


@dataclass
class SimulationResult:
    """Sampled output of :func:`algid.simulator.simulate` (``T`` samples, ``n`` DOF).

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
    chain : the simulated :class:`~algid.model.chain.Chain` (or :class:`~algid.model.network.NetworkModel`)
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
        :meth:`algid.control.controller.TrackingController.log`), else None
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
    chain: Chain | NetworkModel
    effects: tuple[Effect, ...]
    fs_hz: float
    mode: str = "continuous"
    limits: dict[str, np.ndarray] = field(default_factory=dict)
    noise_rms: dict[str, np.ndarray] = field(default_factory=dict)
    snr_db: dict[str, np.ndarray] = field(default_factory=dict)
    x_ref: np.ndarray | None = None
    estimates: dict[str, np.ndarray] | None = None
    controller_log: dict[str, Any] | None = None
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


@dataclass
class Samples:
    """Noise-free signals at the ``T`` sample instants, as a driver produces them.

    ``x`` [m], ``v`` [m/s], ``a_true`` [m/s^2] (mean of the one-sided limits), ``a_clean``
    (the accelerometers' reading without noise: low-pass and bias included), ``u_rec``
    (what the force sensors read) and ``u_applied`` [N], each (T, n); ``limits`` as
    :attr:`SimulationResult.limits`. A closed loop also fills ``a_meas``, ``u_meas``,
    ``x_meas``: the noisy readings the controller saw.
    """

    x: np.ndarray
    v: np.ndarray
    a_true: np.ndarray
    a_clean: np.ndarray
    u_rec: np.ndarray
    u_applied: np.ndarray
    limits: dict[str, np.ndarray]
    a_meas: np.ndarray | None = None
    u_meas: np.ndarray | None = None
    x_meas: np.ndarray | None = None

    @classmethod
    def empty(cls, T: int, n: int) -> Samples:
        """Room for a closed loop's ``T`` samples of ``n`` DOF, filled sample by sample."""

        def room() -> np.ndarray:
            return np.empty((T, n))

        return cls(
            x=room(),
            v=room(),
            a_true=room(),
            a_clean=room(),
            u_rec=room(),
            u_applied=room(),
            limits={name: room() for name in LIMIT_NAMES},
            a_meas=room(),
            u_meas=room(),
            x_meas=room(),
        )
