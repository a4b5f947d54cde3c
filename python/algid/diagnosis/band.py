"""The signal band ``[0, f_hi]`` of a recording, in which the withheld errors are scored.

Band rule (from the recording alone, :func:`signal_band`): Welch PSD (Hann, segments of
about 1 s) of every recorded force and every measured acceleration; per signal a noise
floor = median PSD over the upper third of the spectrum; the bins more than
:data:`BAND_DETECT` times above it carry signal; the signal frequency ``f_exc`` is the
frequency below which :data:`BAND_POWER` of that signal's above-floor power lies
(maximum over the signals: the band is never narrower than where either the forces or
the responses carry signal; accelerations derived from velocities or displacements are
left out, their differentiated noise rising with frequency). ``f_hi = min(f_Nyquist, max(BAND_HARMONICS f_exc,
BAND_MODES f_n,max))`` with ``f_n,max`` the highest natural frequency of the linear chain
fitted first: the band keeps the harmonics up to the third that polynomial nonlinearities
(cubic spring, clearance, Coulomb friction, quadratic damping) create from the
excitation, and every mode. The low edge is 0 (bias and drift live there; the
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..recording.noise import white_floor

__all__ = [
    "BAND_DETECT",
    "BAND_HARMONICS",
    "BAND_MODES",
    "BAND_POWER",
    "Band",
    "derived_noise_limit",
    "excitation_frequency",
    "signal_band",
]

#: Band rule (see the module docstring): a PSD bin carries signal above this multiple of
#: the noise floor; f_exc holds this share of the above-floor power; the band edge is at
#: least this multiple of f_exc and of the highest natural frequency.
BAND_DETECT = 10.0
BAND_POWER = 0.99
BAND_HARMONICS = 3.0
BAND_MODES = 1.25


@dataclass
class Band:
    """Signal band ``[0, f_hi]`` of a recording (:func:`signal_band`).

    f_hi : upper edge [Hz]; f_exc : signal frequency [Hz] (nan if no signal found);
    f_modes : highest natural frequency used [Hz] (nan if none); nyquist [Hz];
    f_derived_noise : where derived accelerations sink into their differentiated noise
    [Hz] (nan for measured accelerations);
    source : the signal that sets f_exc ("force 1", "acceleration 2", ...; "" if none);
    f_signals : f_exc of every signal used (nan: nothing above its floor);
    floors : noise-floor PSD of every signal used [unit^2/Hz].
    """

    f_hi: float
    f_exc: float
    f_modes: float
    nyquist: float
    source: str
    floors: list
    f_signals: dict = field(default_factory=dict)
    f_derived_noise: float = float("nan")

    @property
    def full(self) -> bool:
        return bool(self.f_hi >= self.nyquist)

    def to_json(self) -> dict:
        return {
            "band_hz": [0.0, self.f_hi],
            "f_excitation_hz": self.f_exc,
            "f_natural_max_hz": self.f_modes,
            "nyquist_hz": self.nyquist,
            "source": self.source,
            "f_derived_noise_hz": self.f_derived_noise,
            "f_signals_hz": self.f_signals,
            "noise_floor_psd": self.floors,
            "rule": f"f_hi = min(Nyquist, max({BAND_HARMONICS:g} f_exc, {BAND_MODES:g} f_n,max)); f_exc: "
            f"largest over the forces and accelerations of the frequency below which "
            f"{BAND_POWER:.0%} of the PSD power in bins above {BAND_DETECT:g}x the median PSD of "
            "the upper third of the spectrum lies",
        }


def excitation_frequency(x: np.ndarray, dt: float) -> tuple[float, float]:
    """``(f_exc, floor)`` of one signal: Welch PSD (Hann, ~1 s segments), noise floor =
    median PSD over the upper third of the spectrum, f_exc = frequency below which
    :data:`BAND_POWER` of the power in bins above :data:`BAND_DETECT` x floor lies (above
    the floor); nan when no bin is above."""
    from scipy.signal import welch

    x = np.asarray(x, dtype=float)
    T = x.size
    nper = int(min(T, max(256, min(T // 4, round(1.0 / dt)))))
    f, S = welch(x, fs=1.0 / dt, nperseg=nper)
    floor = float(white_floor(f, S))
    exc = np.where(S > BAND_DETECT * floor, S - floor, 0.0)
    tot = exc.sum()
    if not tot > 0:
        return float("nan"), floor
    c = np.cumsum(exc) / tot
    return float(f[min(int(np.searchsorted(c, BAND_POWER)), f.size - 1)]), floor


def derived_noise_limit(a: np.ndarray, motion: np.ndarray, dt: float, order: int) -> float:
    """Highest frequency [Hz] at which accelerations differentiated ``order`` times from
    ``motion`` stand :data:`BAND_DETECT` times above their own noise: the motion's white
    floor (median PSD of its upper third) times ``(2 pi f)^(2 order)``, the gain of
    differentiation. Above it the derived accelerations are noise whatever the model."""
    from scipy.signal import welch

    nper = int(min(a.shape[0], max(256, min(a.shape[0] // 4, round(1.0 / dt)))))
    f, Sa = welch(a, fs=1.0 / dt, nperseg=nper, axis=0)
    _, Sm = welch(motion, fs=1.0 / dt, nperseg=nper, axis=0)
    floor = white_floor(f, Sm)
    noise = floor[None, :] * (2 * np.pi * f[:, None]) ** (2 * order)
    above = np.any(Sa > BAND_DETECT * noise, axis=1)
    above[0] = False
    return float(f[np.nonzero(above)[0].max()]) if above.any() else float(f[1])


def signal_band(a: np.ndarray, u: np.ndarray, dt: float, natural_hz=(), derived: tuple | None = None) -> Band:
    """The band ``[0, f_hi]`` in which the recording carries signal (module docstring):
    from the forces of the forced DOFs, the accelerations and the natural frequencies of a
    first linear fit. Never uses anything but the recording.

    ``derived = (motion, order)``: the accelerations were differentiated ``order`` times
    from the recorded ``motion`` (velocities or displacements). Their noise then grows
    like ``f^order``: no flat floor tells it from signal, so the forces (and the modes)
    set the band, which is cut where the accelerations sink into their differentiated
    noise (:func:`derived_noise_limit`)."""
    a = np.atleast_2d(np.asarray(a, dtype=float).T).T
    u = np.atleast_2d(np.asarray(u, dtype=float).T).T
    nyq = 0.5 / dt
    forced = np.any(u != 0.0, axis=0)
    cols = {f"force {i + 1}": u[:, i] for i in np.nonzero(forced)[0]}
    if derived is None or not cols:
        cols.update({f"acceleration {i + 1}": a[:, i] for i in range(a.shape[1])})
    res = {name: excitation_frequency(c, dt) for name, c in cols.items()}
    fe = {name: f for name, (f, _) in res.items() if np.isfinite(f)}
    source = max(fe, key=fe.get) if fe else ""
    f_exc = fe[source] if fe else float("nan")
    fn = np.asarray(natural_hz, dtype=float)
    fn = fn[np.isfinite(fn) & (fn > 0)]
    f_modes = float(fn.max()) if fn.size else float("nan")
    if not fe:
        f_hi = nyq
    else:
        f_hi = min(nyq, max(BAND_HARMONICS * f_exc, BAND_MODES * f_modes if fn.size else 0.0))
    f_noise = float("nan")
    if derived is not None:
        f_noise = derived_noise_limit(a, np.atleast_2d(np.asarray(derived[0], dtype=float).T).T, dt, derived[1])
        f_hi = min(f_hi, max(f_noise, f_exc if np.isfinite(f_exc) else 0.0))
    return Band(
        f_hi=float(f_hi),
        f_exc=f_exc,
        f_modes=f_modes,
        nyquist=nyq,
        source=source,
        floors=[fl for _, fl in res.values()],
        f_signals={k: f for k, (f, _) in res.items()},
        f_derived_noise=f_noise,
    )
