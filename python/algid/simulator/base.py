"""Base excitation (a shake table, a seismic or transmissibility test): the support, the left
wall of eq. 1, moves by a prescribed ``x_0(t)`` and its acceleration is measured beside the
masses'.

    m_i x_i'' + c_i x_i' + k_i (x_i - x_{i-1}) + k_{i+1} (x_i - x_{i+1}) = u_i,   x_0 = x_0(t)

The dampers act on the absolute velocities (to ground, as eq. 1 has them), so the support
enters DOF 1's equation through spring ``k_1`` alone: the chain moves as the chain with a fixed
wall under the extra force ``k_1 x_0(t)`` on DOF 1, which is how :func:`simulate_base` runs
it (:func:`algid.simulator.simulate` in continuous mode, the force a callable). The record
holds the measured forces only (the support's push is no force a sensor reads).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..model.chain import Chain
from ..recording import Recording

#: Default band of the support acceleration [Hz].
BASE_BAND_HZ = (0.5, 25.0)


@dataclass(frozen=True)
class SupportMotion:
    """A band-limited random support motion: sines at every multiple of ``1 / duration_s``
    within ``band_hz`` with random phases and equal acceleration amplitudes (a flat
    acceleration spectrum), scaled to the acceleration RMS ``rms`` [m/s^2]; the displacement
    [m], velocity [m/s] and acceleration [m/s^2] are its exact integrals and derivative."""

    omega: np.ndarray  #: angular frequencies [rad/s]
    amplitude: np.ndarray  #: acceleration amplitudes [m/s^2]
    phase: np.ndarray  #: phases [rad]

    @classmethod
    def random(
        cls, duration_s: float, band_hz: tuple[float, float] = BASE_BAND_HZ, rms: float = 1.0, seed: int | None = 0
    ) -> SupportMotion:
        rng = np.random.default_rng(seed)
        f = np.arange(np.ceil(band_hz[0] * duration_s), np.floor(band_hz[1] * duration_s) + 1) / duration_s
        if f.size == 0:
            raise ValueError(f"band {band_hz} Hz holds no multiple of 1 / {duration_s} s")
        amp = np.full(f.size, rms * np.sqrt(2.0 / f.size))
        return cls(2 * np.pi * f, amp, rng.uniform(0.0, 2 * np.pi, f.size))

    def _sum(self, t, power: int, shift: float) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        arg = np.multiply.outer(t, self.omega) + self.phase + shift
        return np.sin(arg) @ (self.amplitude / self.omega**power)

    def acceleration(self, t) -> np.ndarray:
        """``x_0''(t)`` [m/s^2]."""
        return self._sum(t, 0, 0.0)

    def velocity(self, t) -> np.ndarray:
        """``x_0'(t)`` [m/s]."""
        return self._sum(t, 1, -np.pi / 2)

    def displacement(self, t) -> np.ndarray:
        """``x_0(t)`` [m]."""
        return self._sum(t, 2, -np.pi)


def simulate_base(
    chain: Chain,
    support: SupportMotion,
    duration_s: float,
    fs_hz: float = 1000.0,
    *,
    force: Callable[[float], np.ndarray] | None = None,
    noise_db: float | None = None,
    seed: int | None = 0,
) -> Recording:
    """The record of a base-excited chain (module docstring): support acceleration ``a0``
    [m/s^2], the masses' accelerations ``a1..an`` [m/s^2] and the measured forces ``u1..un``
    [N] (``force(t) -> (n,)``, or None: no force, a record without force columns).
    ``noise_db``: white noise of that SNR on every measured acceleration, ``a0`` included
    (the DOFs' from :func:`~algid.simulator.simulate`'s stream of ``seed``, the support's
    from a stream of its own); forces noise-free."""
    from . import simulate

    k1, n = float(chain.stiffness[0]), chain.n

    def driven(t: float) -> np.ndarray:
        u = np.zeros(n) if force is None else np.asarray(force(t), dtype=float).reshape(n).copy()
        u[0] += k1 * float(support.displacement(t))
        return u

    res = simulate(chain, driven, duration_s, fs_hz, noise_db=noise_db, noise_on=("accel",), seed=seed)
    a0 = support.acceleration(res.t)
    if noise_db is not None:
        rng = np.random.default_rng([0 if seed is None else seed, 1])
        a0 = a0 + rng.standard_normal(a0.size) * np.sqrt(np.mean(a0**2)) * 10 ** (-noise_db / 20)
    u = None if force is None else np.array([force(t) for t in res.t], dtype=float).reshape(-1, n)
    return Recording(t=res.t, u=u, a=res.a, base=a0, base_kind="a")
