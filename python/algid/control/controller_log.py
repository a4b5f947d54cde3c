"""The per-sample history of a tracking run: the estimator's output after every sample,
the parameters the law used on every interval, and the law's velocity estimate and force."""

from __future__ import annotations

from typing import Any

import numpy as np

from .control_law import LawParameters

__all__ = ["ControllerLog"]


class ControllerLog:
    """Room for ``T`` samples of an ``n``-DOF run (samples ``k >= T`` are not kept).

    ``estimator`` tells whether each DOF's own estimates (``theta(dof)``) and the
    uncertainties (``sigma``) exist; they stay NaN otherwise.
    """

    def __init__(self, T: int, n: int, estimator: Any) -> None:
        self.T, self.n = T, n
        self.has_theta = callable(getattr(estimator, "theta", None))
        self.has_sigma = getattr(estimator, "sigma", None) is not None
        self.est_mass = np.full((T, n), np.nan)
        self.est_damping = np.full((T, n), np.nan)
        self.est_stiffness = np.full((T, n + 1), np.nan)
        self.est_valid = np.zeros((T, n), bool)
        self.est_theta = np.full((T, n, 4), np.nan)
        self.est_sigma = np.full((T, 3 * n + 1), np.nan)
        self.status = np.zeros(T, int)
        self.used_mass = np.zeros((T, n))
        self.used_damping = np.zeros((T, n))
        self.used_stiffness = np.zeros((T, n + 1))
        self.velocity_estimate = np.full((T, n), np.nan)
        self.force_command = np.full((T, n), np.nan)

    def used(self, k: int, p: LawParameters) -> None:
        """The parameters in use on ``[t_k, t_{k+1})``."""
        if k < self.T:
            self.used_mass[k] = p[0]
            self.used_damping[k] = p[1]
            self.used_stiffness[k] = p[3]

    def law(self, k: int, xd: np.ndarray, u: np.ndarray) -> None:
        """Velocity estimate of eq. 10 [m/s] and force [N] at ``t_k``."""
        if k < self.T:
            self.velocity_estimate[k] = xd
            self.force_command[k] = u

    def estimates(
        self, k: int, estimator: Any, m: np.ndarray, c: np.ndarray, kk: np.ndarray, valid: np.ndarray, status: int
    ) -> None:
        """The estimator's output after sample ``k``."""
        if k >= self.T:
            return
        self.est_mass[k], self.est_damping[k], self.est_stiffness[k] = m, c, kk
        self.est_valid[k] = valid
        if self.has_sigma:
            self.est_sigma[k] = np.asarray(estimator.sigma, dtype=float)
        if self.has_theta:
            for i in range(self.n):
                self.est_theta[k, i] = estimator.theta(i)
        self.status[k] = int(status)

    def history(self) -> dict[str, Any]:
        """``estimates``, ``used``, ``velocity_estimate`` and ``force_command`` as in
        :meth:`algid.control.controller.TrackingController.log`."""
        return {
            "estimates": {
                "mass": self.est_mass,
                "damping": self.est_damping,
                "stiffness": self.est_stiffness,
                "valid": self.est_valid,
                "theta": self.est_theta,
                "sigma": self.est_sigma,
                "status": self.status,
            },
            "used": {"mass": self.used_mass, "damping": self.used_damping, "stiffness": self.used_stiffness},
            "velocity_estimate": self.velocity_estimate,
            "force_command": self.force_command,
        }
