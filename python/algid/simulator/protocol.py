"""What the simulator asks of a closed-loop controller, as ``typing.Protocol`` classes:
the simulator calls these methods and nothing else of a controller."""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

__all__ = ["ContinuousController", "Controller"]


class Controller(Protocol):
    """A controller run once per sample (``mode="sampled"``).

    Per run the simulator calls :meth:`start`, then for every sample ``k``
    :meth:`params_for_sample`, :meth:`sampled_force` and :meth:`observe`, and at the end
    :meth:`log`; :meth:`reference_motion` sets the noise level of a noisy loop beforehand.
    """

    def start(
        self, chain_n: int, dt: float, boundary: str = "fixed", samples: int = 0, mode: str = "continuous"
    ) -> None:
        """Prepare a run of ``samples`` samples every ``dt`` [s] on a ``chain_n``-DOF chain."""

    def params_for_sample(self, k: int, z: np.ndarray | None = None) -> Any:
        """The parameters the law uses on ``[t_k, t_{k+1})`` (``z``: the controller states
        at ``t_k`` in continuous mode); passed back to :meth:`ContinuousController.continuous`."""

    def sampled_force(self, k: int, t: float, x_meas: np.ndarray) -> np.ndarray:
        """Force command [N] (n,) held on ``[t_k, t_{k+1})`` from measured positions [m]."""

    def observe(
        self, k: int, t: float, accel: np.ndarray, force: np.ndarray, x_meas: np.ndarray, z: np.ndarray | None = None
    ) -> None:
        """Sample ``k`` as measured: accelerations [m/s^2], recorded forces [N], positions [m]
        (and the controller states ``z`` in continuous mode)."""

    def reference_motion(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position [m], velocity [m/s] and acceleration [m/s^2] (T, n) the loop is meant to
        follow at the times ``t`` [s] (T,)."""

    def log(self) -> dict[str, Any]:
        """History of the run; ``x_ref`` (T, n) and ``estimates`` are kept in the result."""


class ContinuousController(Controller, Protocol):
    """A controller whose law runs inside the ODE (``mode="continuous"``), with
    :attr:`n_states` integrator states ``z`` integrated with the plant."""

    @property
    def n_states(self) -> int:
        """Number of controller states."""

    def continuous(self, t: float, x: np.ndarray, z: np.ndarray, params: Any) -> tuple[np.ndarray, np.ndarray]:
        """Force [N] (n,) and ``dz/dt`` at time ``t`` [s] from the true positions ``x`` [m]
        and the controller states ``z``, with the parameters of the current interval."""
