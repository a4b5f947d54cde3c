"""What the tracking loop follows and adds: the rest-to-rest Bezier references of the
paper (:class:`BezierReference`) and a known probing multisine force (:class:`Multisine`).

References: Bezier rest-to-rest polynomials
``psi(tau) = tau^5 (252 - 1050 tau + 1800 tau^2 - 1575 tau^3 + 700 tau^4 - 126 tau^5)``
(``psi(0) = 0``, ``psi(1) = 1``, derivatives 1-4 zero at both ends) move each DOF from rest
to its target over ``t_out`` and back to rest over ``t_back``. The paper's targets are
``(0.005, 0.005, -0.005) m``; :meth:`BezierReference.paper` generalises to any ``n`` by
repeating the pattern ``+, +, -`` (``n = 1``: ``+5 mm``; ``n = 5``: ``+, +, -, +, +``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["BEZIER_COEFFS", "BezierReference", "Multisine", "bezier"]

#: Coefficients of ``psi(tau)`` for ``tau^5 .. tau^10``.
BEZIER_COEFFS = (252.0, -1050.0, 1800.0, -1575.0, 700.0, -126.0)


def bezier(tau: float | np.ndarray) -> tuple[Any, Any, Any]:
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

    def __init__(
        self,
        targets_m: Sequence[float],
        t_out: tuple[float, float] = (0.0, 2.0),
        t_back: tuple[float, float] = (2.5, 4.5),
    ) -> None:
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
    def paper(cls, n: int, stroke_m: float = 0.005, **kw: Any) -> BezierReference:
        """The paper's targets ``(+s, +s, -s)`` for n = 3, the pattern repeated for other n."""
        pattern = np.array([1.0, 1.0, -1.0])
        return cls(stroke_m * np.resize(pattern, int(n)), **kw)

    def evaluate(self, t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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


class Multisine:
    """Probing force ``f_i(t) = amplitude * sum_q sin(2 pi f_q t + phi_iq)`` [N] per DOF.

    The paper's references are slow (2 s rest-to-rest moves): their accelerations carry so
    little information that accelerometer noise buries it (``docs/demo.md``). A small known
    multisine added to the commanded force keeps the chain excited; its motion stays small
    under the loop's feedback. Phases are fixed per DOF
    (``seed``), so every run gets the same probe.
    """

    FREQS_HZ = (3.1, 4.7, 6.3, 8.9, 12.1, 15.7)

    def __init__(self, n: int, amplitude_n: float, freqs_hz: Sequence[float] = FREQS_HZ, seed: int = 0) -> None:
        if not amplitude_n >= 0:
            raise ValueError("amplitude_n must be >= 0")
        self.amplitude_n = float(amplitude_n)
        self.freqs_hz = np.asarray(freqs_hz, dtype=float)
        self._w = 2 * np.pi * self.freqs_hz
        self.phases = np.random.default_rng(seed).uniform(0, 2 * np.pi, (int(n), self.freqs_hz.size))

    def __call__(self, t: float) -> np.ndarray:
        """Force [N] (n,) at time ``t`` [s]."""
        return self.amplitude_n * np.sin(self._w * t + self.phases).sum(axis=1)
