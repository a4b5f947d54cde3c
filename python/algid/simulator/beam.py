"""Impact-hammer test of a continuous Euler-Bernoulli beam: ``hammer_test(beam, ...)``.

The beam (bending stiffness ``EI`` [N m^2], mass per length ``rho A`` [kg/m], length ``L``
[m]) is clamped at ``x = 0`` and free or clamped at ``x = L``. Its modes are the closed
forms of the Euler-Bernoulli equation: ``omega_r = (beta_r L)^2 sqrt(EI / (rho A L^4))`` with
``beta_r L`` the roots of ``cos(bL) cosh(bL) = -1`` (clamped-free: 1.875, 4.694, 7.855, ...)
or ``= +1`` (clamped-clamped: 4.730, 7.853, 10.996, ...), and the mode shapes

    phi_r(x) = [cosh(b x) - cos(b x) - s_r (sinh(b x) - sin(b x))] / sqrt(rho A L),

``s_r = (cosh bL + cos bL) / (sinh bL + sin bL)`` (clamped-free) or
``(cosh bL - cos bL) / (sinh bL - sin bL)`` (clamped-clamped), normalised to unit modal mass.

A force ``F(t)`` at the driving point ``x_d`` drives every modal coordinate
``q_r'' + 2 zeta_r omega_r q_r' + omega_r^2 q_r = phi_r(x_d) F``; the driving-point
acceleration is ``sum_r phi_r(x_d) q_r''`` (modal superposition, modal damping). Each mode is
integrated exactly for a force piecewise linear between the samples of a grid
``oversample`` times finer than the recording (first-order hold), then both channels pass the
same zero-phase anti-alias low-pass (0.4 of the recording's rate) and are sampled at ``fs_hz``,
as a data acquisition system's identical channels do.

The hammer: half-sine pulses of ``pulse_s`` [s] (0.5-2 ms), optionally a double hit (a second,
smaller pulse shortly after the first, the hammer bouncing); every hit has ``pretrigger_s`` of
quiet before it and ``record_s`` in all, and ``hits`` of them follow one another in one record.
The force *sensor* reads the force plus a baseline drift after each hit (the undershoot of an
AC-coupled charge amplifier, which the beam does not feel): the force's running integral
forgotten with ``drift_tau_s``, ``-drift * peak * (e^(-t / drift_tau_s) * F)(t) / I`` (``I`` one
hit's impulse), so it grows with the charge passed during a hit and is
``-drift * peak * exp(-t / drift_tau_s)`` after it. White noise of RMS
``rms(channel) * 10**(-noise_db / 20)`` (over the whole record) is added to every channel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..recording import Recording

#: ``beta_r L`` of the first modes (roots of the frequency equations, to 1e-6).
BETA_L = {
    "clamped-free": (1.875104, 4.694091, 7.854757, 10.995541, 14.137168, 17.278760, 20.420352, 23.561945),
    "clamped-clamped": (4.730041, 7.853205, 10.995608, 14.137165, 17.278760, 20.420352, 23.561945, 26.703538),
}


@dataclass(frozen=True)
class Beam:
    """A uniform Euler-Bernoulli beam and its modal damping.

    ``EI`` [N m^2], ``rho_A`` [kg/m], ``length_m`` [m], ``boundary`` ``"clamped-free"`` or
    ``"clamped-clamped"``, ``zeta`` damping ratio of every mode, ``modes`` modes superposed.
    """

    EI: float = 43.75
    rho_A: float = 0.785
    length_m: float = 0.172
    boundary: str = "clamped-free"
    zeta: float = 0.0013
    modes: int = 5

    def __post_init__(self) -> None:
        if self.boundary not in BETA_L:
            raise ValueError(f"boundary must be one of {tuple(BETA_L)}, got {self.boundary!r}")
        if not 1 <= self.modes <= len(BETA_L[self.boundary]):
            raise ValueError(f"modes must be 1..{len(BETA_L[self.boundary])}, got {self.modes}")
        if min(self.EI, self.rho_A, self.length_m) <= 0 or self.zeta < 0:
            raise ValueError("EI, rho_A and length_m must be positive and zeta not negative")

    @property
    def beta_L(self) -> np.ndarray:
        return np.array(BETA_L[self.boundary][: self.modes])

    def natural_frequencies_hz(self) -> np.ndarray:
        """Undamped natural frequencies [Hz] of the superposed modes."""
        return self.beta_L**2 * np.sqrt(self.EI / (self.rho_A * self.length_m**4)) / (2 * np.pi)

    def mode_shapes(self, x_m: float) -> np.ndarray:
        """Mass-normalised mode shapes at ``x_m`` [m] (1/sqrt(kg))."""
        bL = self.beta_L
        b = bL / self.length_m
        if self.boundary == "clamped-free":
            s = (np.cosh(bL) + np.cos(bL)) / (np.sinh(bL) + np.sin(bL))
        else:
            s = (np.cosh(bL) - np.cos(bL)) / (np.sinh(bL) - np.sin(bL))
        bx = b * x_m
        shape = np.cosh(bx) - np.cos(bx) - s * (np.sinh(bx) - np.sin(bx))
        return shape / np.sqrt(self.rho_A * self.length_m)


def half_sine(t_s: np.ndarray, start_s: float, width_s: float, peak: float) -> np.ndarray:
    """A half-sine pulse of ``width_s`` [s] and ``peak`` starting at ``start_s`` [s]."""
    tau = (t_s - start_s) / width_s
    return np.where((tau >= 0) & (tau <= 1), peak * np.sin(np.pi * np.clip(tau, 0, 1)), 0.0)


def hammer_force(
    t_s: np.ndarray, starts_s, pulse_s: float, peak_N: float, double_hit: tuple[float, float] | None
) -> np.ndarray:
    """The force on the beam [N]: a half-sine at each of ``starts_s``; ``double_hit = (delay_s,
    share)`` adds a second pulse ``delay_s`` after each, of ``share`` of the peak."""
    F = np.zeros_like(t_s)
    for t0 in starts_s:
        F += half_sine(t_s, t0, pulse_s, peak_N)
        if double_hit is not None:
            F += half_sine(t_s, t0 + double_hit[0], pulse_s, double_hit[1] * peak_N)
    return F


def modal_response(beam: Beam, x_m: float, F: np.ndarray, h_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Driving-point acceleration [m/s^2] and velocity [m/s] at ``x_m`` of the force samples
    ``F`` [N] spaced ``h_s`` [s], linear between samples, the beam at rest before."""
    from scipy.signal import cont2discrete, lfilter, ss2tf

    phi = beam.mode_shapes(x_m)
    a, v = np.zeros_like(F), np.zeros_like(F)
    for w, p in zip(2 * np.pi * beam.natural_frequencies_hz(), phi):
        A = np.array([[0.0, 1.0], [-(w**2), -2 * beam.zeta * w]])
        B = np.array([[0.0], [p]])
        for C, D, out in (([[-(w**2) * p, -2 * beam.zeta * w * p]], [[p * p]], a), ([[0.0, p]], [[0.0]], v)):
            Ad, Bd, Cd, Dd, _ = cont2discrete((A, B, np.array(C), np.array(D)), h_s, method="foh")
            num, den = ss2tf(Ad, Bd, Cd, Dd)
            out += lfilter(num[0], den, F)
    return a, v


def hammer_test(
    beam: Beam | None = None,
    fs_hz: float = 10_000.0,
    record_s: float = 1.0,
    hits: int = 1,
    pretrigger_s: float = 0.05,
    pulse_s: float = 1e-3,
    peak_N: float = 100.0,
    double_hit: tuple[float, float] | None = None,
    drift: float = 0.02,
    drift_tau_s: float = 0.3,
    driving_point: float = 0.8,
    noise_db: float = 40.0,
    motion: str = "acceleration",
    oversample: int = 8,
    seed: int = 0,
) -> Recording:
    """A hammer test of ``beam`` as a :class:`~algid.recording.Recording` (module docstring).

    ``hits`` hits, each with ``pretrigger_s`` [s] of quiet before it and ``record_s`` [s] in all;
    ``double_hit = (delay_s, share)`` or None; ``drift`` the force sensor's undershoot after a hit
    as a share of its peak, decaying with ``drift_tau_s`` [s]; ``driving_point`` the hammer's and
    the accelerometer's place as a share of the length; ``noise_db`` the SNR of every channel
    (``inf``: none); ``motion`` ``"acceleration"``, ``"velocity"`` or ``"both"``.
    """
    from scipy.signal import filtfilt, firwin, lfilter

    beam = Beam() if beam is None else beam
    if motion not in ("acceleration", "velocity", "both"):
        raise ValueError(f"motion must be 'acceleration', 'velocity' or 'both', got {motion!r}")
    if not 0.5e-4 <= pulse_s <= 0.1 * record_s or not 0 <= pretrigger_s < record_s - pulse_s:
        raise ValueError("pulse_s and pretrigger_s must fit in record_s")
    T = int(round(hits * record_s * fs_hz))
    h = 1.0 / (fs_hz * oversample)
    t_fine = np.arange(T * oversample) * h
    starts = pretrigger_s + record_s * np.arange(hits)
    F = hammer_force(t_fine, starts, pulse_s, peak_N, double_hit)
    a, v = modal_response(beam, driving_point * beam.length_m, F, h)
    # the sensor's undershoot (not felt by the beam): the running impulse, forgotten with drift_tau_s
    impulse = lfilter([h], [1.0, -np.exp(-h / drift_tau_s)], F)
    measured_F = F - drift * peak_N * impulse / (np.sum(F) * h / hits)
    aa = firwin(16 * oversample + 1, 0.4 / oversample * 2)  # anti-alias at 0.4 fs, the same on every channel
    chans = {k: filtfilt(aa, [1.0], s)[::oversample] for k, s in (("u", measured_F), ("a", a), ("v", v))}
    rng = np.random.default_rng(seed)
    for s in chans.values():
        if np.isfinite(noise_db):
            s += rng.normal(0.0, np.sqrt(np.mean(s**2)) * 10 ** (-noise_db / 20), s.size)
    return Recording(
        t=np.arange(T) / fs_hz,
        u=chans["u"][:, None],
        a=chans["a"][:, None] if motion in ("acceleration", "both") else None,
        v=chans["v"][:, None] if motion in ("velocity", "both") else None,
        notes=[f"simulated hammer test of a {beam.boundary} beam ({beam.modes} modes)"],
    )
