"""The sensors: accelerometers, force sensors and position sensors at every DOF, their
bias, encoder quantisation and additive white noise (:class:`SensorNoise`), and the noise
level of a closed loop set beforehand from the loop's nominal signals."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.chain import Chain
from .effects import Effect
from .protocol import Controller
from .result import Samples

__all__ = [
    "CHANNELS",
    "Readings",
    "SensorNoise",
    "accelerometer_bias",
    "closed_loop_noise_scale",
    "encoder",
    "nominal_closed_loop_rms",
    "readings",
]

#: The sensor kinds, in the order their noise streams are drawn.
CHANNELS = ("accel", "force", "position")


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
    seed: int | None = None

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


def accelerometer_bias(effects: tuple[Effect, ...], n: int) -> np.ndarray:
    """What every accelerometer reads above the truth [m/s^2] (n,) (``sensor_bias``)."""
    bias = np.zeros(n)
    for e in effects:
        if e.name == "sensor_bias":
            bias[e.dof] += e.params["bias"]
    return bias


def encoder(x: np.ndarray, resolution_m: float) -> np.ndarray:
    """Position readings [m] of an incremental encoder counting ``resolution_m`` [m]
    (``q round(x / q)``; 0: exact readings)."""
    q = resolution_m
    return x if q == 0 else q * np.round(x / q)


def rms(a: np.ndarray) -> np.ndarray:
    """RMS per column."""
    return np.sqrt(np.mean(np.asarray(a) ** 2, axis=0))


def nominal_closed_loop_rms(chain: Chain, controller: Controller, t: np.ndarray) -> dict[str, np.ndarray]:
    """RMS per DOF of the signals a perfectly tracking loop would produce: reference
    position [m], reference acceleration [m/s^2] and the exact-model force [N]."""
    xs, xd, xdd = controller.reference_motion(t)
    M, C, K = chain.matrices()
    u = xdd @ M.T + xd @ C.T + xs @ K.T
    return {"position": rms(xs), "accel": rms(xdd), "force": rms(u)}


def closed_loop_noise_scale(
    chain: Chain, controller: Controller, noise: SensorNoise | None, t: np.ndarray
) -> dict[str, np.ndarray]:
    """Noise RMS per noisy channel kind (n,) of a closed loop, from its nominal signals
    (the noise has to exist while the loop runs); empty without noise."""
    if noise is None:
        return {}
    nominal = nominal_closed_loop_rms(chain, controller, t)
    return {c: nominal[c] * noise.ratio for c in noise.channels}


@dataclass
class Readings:
    """What the sensors read: ``a`` [m/s^2], ``u`` [N], ``x_meas`` [m] (T, n), the noise
    RMS used and the SNR achieved [dB] per noisy channel kind."""

    a: np.ndarray
    u: np.ndarray
    x_meas: np.ndarray
    noise_rms: dict[str, np.ndarray]
    snr_db: dict[str, np.ndarray]


def readings(
    samples: Samples,
    unit: dict[str, np.ndarray],
    noise: SensorNoise | None,
    noise_scale: dict[str, np.ndarray],
    encoder_resolution_m: float,
) -> Readings:
    """The sensor readings of a run. A closed loop measured while it ran (``samples.a_meas``
    etc., noise of RMS ``noise_scale``); an open loop gets noise of ``noise.ratio`` times
    each clean channel's RMS over the whole record. ``unit``: unit-RMS noise per channel kind."""
    level = {"accel": samples.a_true, "force": samples.u_rec, "position": samples.x}
    noise_rms: dict[str, np.ndarray] = {}
    if samples.a_meas is not None:
        a_out, u_out, x_out = samples.a_meas, samples.u_meas, samples.x_meas
        for c, sc in noise_scale.items():
            noise_rms[c] = sc * np.sqrt(np.mean(unit[c] ** 2, axis=0))
    else:
        clean = {"accel": samples.a_clean, "force": samples.u_rec, "position": samples.x}
        noisy = {}
        for c in CHANNELS:
            if c in unit:
                sc = rms(level[c]) * noise.ratio
                noisy[c] = clean[c] + sc * unit[c]
                noise_rms[c] = sc * np.sqrt(np.mean(unit[c] ** 2, axis=0))
        a_out = noisy.get("accel", samples.a_clean)
        u_out = noisy.get("force", samples.u_rec.copy())
        x_out = encoder(noisy.get("position", samples.x.copy()), encoder_resolution_m)
    snr: dict[str, np.ndarray] = {}
    for c, r in noise_rms.items():
        with np.errstate(divide="ignore", invalid="ignore"):
            snr[c] = 20 * np.log10(rms(level[c]) / np.where(r > 0, r, np.nan))
    return Readings(a=a_out, u=u_out, x_meas=x_out, noise_rms=noise_rms, snr_db=snr)
