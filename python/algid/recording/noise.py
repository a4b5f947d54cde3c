"""What a recording carries: signal band, noise floor and encoder resolution per channel.

Everything here is read off the recording alone (no model), so that the identification and
the diagnosis can choose their settings, and describe the sensor noise, on records nobody
labelled.

Per channel (every force, and every measured acceleration or displacement):

* **PSD** by Welch's method (Hann, segments of :func:`segment_length` samples: about 4 s,
  so that the slow motions of a positioning axis are resolved, and at least 8 segments).
* **Noise floor** (:func:`white_floor`): the median PSD over the upper third of the
  spectrum [unit^2/Hz], or, below an anti-alias roll-off, over the top of the flat part;
  the white-noise standard deviation it stands for is ``sqrt(floor fs / 2)``.
* **Signal**: the PSD bins more than :data:`DETECT` times above the floor; ``f_hi`` is the
  frequency below which :data:`POWER` of their power above the floor lies, ``f_mid`` the
  median frequency of that power (half below, half above).
* **Broadband forcing**: a force whose spectrum is flat to the Nyquist rate stands nowhere
  above "its floor". When a forced channel shows no signal, the multiple coherence of the
  motions with the forces decides (:func:`coherent_share`): over the upper third of the
  spectrum noise coheres with nothing, signal does; if it coheres, every floor is read from
  the share of the spectrum the forces do not explain.
* **Encoder resolution** of a displacement channel: the largest ``q`` such that every
  reading is a whole multiple of ``q`` (to 1e-6 q) with at least 3 distinct counts; 0 when
  the readings are not quantised. Quantisation adds white noise of variance ``q^2 / 12``:
  the floor of a quantised channel is at least ``q^2 / 12 / (fs / 2)``
  (:func:`quantisation_psd`), whatever its upper third shows.

The **signal band** of the record is ``[0, f_hi]`` with ``f_hi`` the largest ``f_hi`` of the
forces and, where accelerations are measured, of the accelerations. Accelerations derived
from velocities or encoder counts carry differentiated noise that grows like ``f`` or
``f^2``, which no band rule on their own spectrum could tell from signal, so then only the
forces set the band. The characteristic frequency ``f_mid`` of the record is that of the forces.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .derivatives import MOTION_FIELDS

#: A PSD bin carries signal above this multiple of the channel's noise floor.
DETECT = 10.0
#: ``f_hi`` holds this share of a channel's above-floor power.
POWER = 0.99
#: What the motion channels of a recording can measure.
KINDS = ("acceleration", "velocity", "displacement")


@dataclass(frozen=True)
class Channel:
    """Spectral summary of one recorded signal.

    Attributes
    ----------
    name : "u1", "a2", "x1", ...
    floor_psd : noise floor [unit^2/Hz] (one-sided PSD).
    sigma : white-noise standard deviation of that floor [unit].
    f_hi : frequency below which :data:`POWER` of the above-floor power lies [Hz] (nan if
        no bin is above the floor).
    f_mid : median frequency of the above-floor power [Hz] (nan if none).
    f_low : frequency below which a tenth of the above-floor power lies [Hz] (nan if none).
    snr_db : above-floor power over the floor's power in ``[0, f_hi]`` [dB] (nan if none).
    quantum : encoder resolution of a displacement channel [unit] (0: not quantised).
    rms : RMS of the channel about its mean [unit].
    """

    name: str
    floor_psd: float
    sigma: float
    f_hi: float
    f_mid: float
    snr_db: float
    quantum: float = 0.0
    rms: float = 0.0
    f_low: float = float("nan")

    def to_json(self) -> dict:
        return {k: _num(v) for k, v in self.__dict__.items()}


@dataclass(frozen=True)
class NoiseModel:
    """Signal band and per-channel noise of a recording (:func:`analyse`).

    Attributes
    ----------
    dt : sample period [s].
    motion : "acceleration" (measured), "velocity" or "displacement" (accelerations derived).
    forces, motions : per DOF :class:`Channel` of ``u_i`` and of ``a_i`` or ``x_i``.
    f_hi : upper edge of the signal band [Hz] (Nyquist when nothing stands out).
    f_mid : median frequency of the force power [Hz] (nan when no force stands out).
    band_source : the channel that sets ``f_hi``.
    """

    dt: float
    motion: str
    forces: list[Channel]
    motions: list[Channel]
    f_hi: float
    f_mid: float
    band_source: str
    extra: dict = field(default_factory=dict)

    @property
    def nyquist(self) -> float:
        return 0.5 / self.dt

    @property
    def quantised(self) -> bool:
        """True when displacement readings come in encoder counts."""
        return any(c.quantum > 0 for c in self.motions)

    def to_json(self) -> dict:
        return {
            "motion": self.motion,
            "band_hz": [0.0, _num(self.f_hi)],
            "f_mid_hz": _num(self.f_mid),
            "band_source": self.band_source,
            "nyquist_hz": self.nyquist,
            "forces": [c.to_json() for c in self.forces],
            "motions": [c.to_json() for c in self.motions],
            "rule": (
                f"per channel: Welch PSD, floor = median PSD of the upper third, signal = bins above "
                f"{DETECT:g}x floor, f_hi = frequency below which {POWER:.0%} of the above-floor power "
                "lies; band edge = largest f_hi of the forces and of measured accelerations (derived "
                "accelerations are not used: their noise grows like f^2)"
            ),
        }


def _num(v):
    if isinstance(v, (float, np.floating)):
        return float(v) if np.isfinite(v) else None
    return v


def segment_length(T: int, dt: float) -> int:
    """Welch segment: about 4 s, at most a quarter of the record, at least 64 samples."""
    return int(max(min(64, T), min(T // 4, int(round(4.0 / dt)))))


def psd(x: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Welch PSD (Hann, :func:`segment_length`, linear detrend per segment) of the
    columns of ``x``: frequencies [Hz] and (F, ...) one-sided PSD [unit^2/Hz]."""
    from scipy.signal import welch

    x = np.asarray(x, dtype=float)
    return welch(x, fs=1.0 / dt, nperseg=segment_length(x.shape[0], dt), axis=0, detrend="linear")


def encoder_quantum(x: np.ndarray) -> float:
    """Largest ``q`` with every reading a whole multiple of ``q`` (3 counts at least), or 0."""
    x = np.asarray(x, dtype=float)
    steps = np.abs(np.diff(np.unique(x)))
    steps = steps[steps > 0]
    if steps.size < 2:
        return 0.0
    q = float(np.min(steps))
    scale = max(float(np.max(np.abs(x))), q)
    if q < 1e-12 * scale:  # steps at rounding level: analogue readings
        return 0.0
    whole = np.round(x / q)
    if np.any(whole != 0):  # the least-squares step of the grid (float32 storage blurs the smallest step)
        q = float(np.dot(x, whole) / np.dot(whole, whole))
    counts = x / q
    if np.max(np.abs(counts - np.round(counts))) > 1e-3:  # off the grid: analogue readings
        return 0.0
    if np.unique(np.round(counts)).size < 3:
        return 0.0
    return q


def quantisation_psd(x: np.ndarray, dt: float) -> float:
    """One-sided PSD [unit^2/Hz] of the quantisation noise of readings ``x`` in encoder counts,
    ``q^2 / 12 / (fs / 2)`` with ``q`` their :func:`encoder_quantum` (0 when not quantised).

    Quantisation error is uniform on ``[-q/2, q/2]`` (variance ``q^2 / 12``) and white up to
    the Nyquist rate while the motion crosses many counts per sample; a slower motion leaves
    an error correlated with the signal whose spectrum need not reach the upper third where
    :func:`white_floor` reads the floor, so the floor of a quantised channel is at least this.
    """
    q = encoder_quantum(x)
    return float(q * q / 12.0 * 2.0 * dt)


#: A tenth of the spectrum this many times below the tenth under it is an anti-alias roll-off.
ROLL_OFF = 2.0


def white_floor(f: np.ndarray, S: np.ndarray) -> np.ndarray:
    """The white noise floor of one-sided PSDs ``S`` (F,) or (F, c) [unit^2/Hz]: the median
    over the upper third of the spectrum; where the spectrum falls off towards Nyquist
    (an anti-alias filter: the top tenth :data:`ROLL_OFF` times below the tenth under it),
    the median of the highest tenth of the upper half below the roll-off (each tenth
    walked past is more than :data:`ROLL_OFF` times below the one under it), provided the
    spectrum is flat there (the next tenth down within :data:`ROLL_OFF`) and lies
    ``DETECT^2`` below the spectrum's peak (a spectrum that keeps falling through the upper
    half, or the plateau of an input that stops at a band edge, is signal)."""
    S = np.asarray(S, dtype=float)
    one = S.ndim == 1
    S2 = S[:, None] if one else S
    nyq = f[-1]
    out = np.median(S2[f >= (2.0 / 3.0) * nyq], axis=0)
    masks = [(f >= k * nyq / 10) & (f <= (k + 1) * nyq / 10) for k in range(5, 10)]
    if min(int(m.sum()) for m in masks) < 2:  # too few bins to see a roll-off
        return out[0] if one else out
    tenth = [np.median(S2[m], axis=0) for m in masks]
    for c in range(S2.shape[1]):
        k = 4
        while k > 0 and tenth[k - 1][c] > ROLL_OFF * tenth[k][c]:
            k -= 1
        # a flat stretch under the roll-off, far below the spectrum's peak (a spectrum still
        # falling at mid-band, or the plateau of a band-limited input, is signal)
        if 0 < k < 4 and tenth[k][c] < np.max(S2[:, c]) / DETECT**2:
            out[c] = tenth[k][c]
    return out[0] if one else out


def channel(name: str, x: np.ndarray, dt: float, quantised: bool = False, incoherent=None) -> Channel:
    """Spectral summary of one signal (module docstring); ``incoherent`` (F,): the share of
    each PSD bin that the other channels do not explain (:func:`coherent_share`), when the
    floor is to be read from that share rather than from the whole spectrum."""
    x = np.asarray(x, dtype=float)
    f, S = psd(x, dt)
    floor = float(white_floor(f, S if incoherent is None else S * incoherent))
    q = encoder_quantum(x) if quantised else 0.0
    floor = max(floor, q * q / 12.0 * 2.0 * dt)  # encoder counts: at least their quantisation noise
    above = np.where(S > DETECT * floor, S - floor, 0.0)
    total = float(above.sum())
    if total > 0:
        c = np.cumsum(above) / total
        f_hi = float(f[min(int(np.searchsorted(c, POWER)), f.size - 1)])
        f_mid = float(f[min(int(np.searchsorted(c, 0.5)), f.size - 1)])
        f_low = float(f[min(int(np.searchsorted(c, 0.1)), f.size - 1)])
        noise = floor * max(f_hi, f[1])
        snr = 10 * np.log10(total * (f[1] - f[0]) / noise) if noise > 0 else np.inf
    else:
        f_hi = f_mid = f_low = snr = float("nan")
    return Channel(
        name=name,
        floor_psd=floor,
        sigma=float(np.sqrt(floor * 0.5 / dt)),
        f_hi=f_hi,
        f_mid=f_mid,
        snr_db=float(snr),
        quantum=q,
        rms=float(np.std(x)),
        f_low=f_low,
    )


def analyse(u: np.ndarray, motion: np.ndarray, dt: float, kind: str = "acceleration") -> NoiseModel:
    """Noise model of a recording: forces ``u`` (T, n) and the measured motion (T, n),
    accelerations (``kind="acceleration"``), velocities (``"velocity"``) or displacements
    (``"displacement"``)."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    u = np.asarray(u, dtype=float).reshape(u.shape[0], -1)
    motion = np.asarray(motion, dtype=float).reshape(motion.shape[0], -1)
    sym = MOTION_FIELDS[kind]
    forces = [channel(f"u{i + 1}", u[:, i], dt) for i in range(u.shape[1])]
    motions = [
        channel(f"{sym}{i + 1}", motion[:, i], dt, quantised=kind == "displacement") for i in range(motion.shape[1])
    ]
    setting = [c for c in forces if np.any(u[:, int(c.name[1:]) - 1] != 0.0)]
    incoherent = coherent_share(u, motion, dt) if any(not np.isfinite(c.f_hi) for c in setting) else None
    if incoherent is not None:  # broadband forcing: the flat top of the spectra is signal
        forces = [channel(f"u{i + 1}", u[:, i], dt, incoherent=incoherent) for i in range(u.shape[1])]
        motions = [
            channel(f"{sym}{i + 1}", motion[:, i], dt, kind == "displacement", incoherent)
            for i in range(motion.shape[1])
        ]
        setting = [c for c in forces if np.any(u[:, int(c.name[1:]) - 1] != 0.0)]
    if kind == "acceleration":
        setting += motions
    found = [c for c in setting if np.isfinite(c.f_hi)]
    if found:
        top = max(found, key=lambda c: c.f_hi)
        f_hi, source = top.f_hi, top.name
    else:
        f_hi, source = 0.5 / dt, ""
    mids = [c.f_mid for c in forces if np.isfinite(c.f_mid)]
    f_mid = float(np.median(mids)) if mids else float("nan")
    return NoiseModel(
        dt=float(dt), motion=kind, forces=forces, motions=motions, f_hi=float(f_hi), f_mid=f_mid, band_source=source
    )


#: Median multiple coherence over the upper third of the spectrum above which its flat top is
#: signal (broadband forcing), not noise.
COHERENT = 0.9


def coherent_share(u: np.ndarray, motion: np.ndarray, dt: float):
    """For a force that stands nowhere above its own floor (white, or broadband up to the
    Nyquist rate: its spectrum is all "floor"): ``1 - gamma^2`` (F,), the share of each PSD bin
    the forces do not explain, with ``gamma^2`` the mean over the motion channels of their
    multiple coherence with every forced channel; None when the upper third of the spectrum
    is not coherent (median below :data:`COHERENT`), i.e. when that flat top is noise after all.
    Noise is what no other channel explains, so the floor is read from this share."""
    from ..model.frf import h1_estimate

    if not np.any(u != 0.0):
        return None
    est = h1_estimate(u, motion, dt, nperseg=segment_length(u.shape[0], dt))
    gamma2 = np.clip(np.nan_to_num(np.mean(est.coherence, axis=1)), 0.0, 1.0)
    top = est.f_hz >= (2.0 / 3.0) * est.f_hz[-1]
    if not np.median(gamma2[top]) >= COHERENT:
        return None
    return np.maximum(1.0 - gamma2, 1e-12)


#: Mains frequencies [Hz] whose lines (and harmonics) are looked for.
MAINS_HZ = (50.0, 60.0)
#: A spectral line stands this many times above the median PSD of its neighbourhood.
LINE_RATIO = 20.0


def mains_lines(signals: np.ndarray, dt: float, harmonics: int = 6) -> list[float]:
    """Mains hum in a recording: the harmonics ``k f0`` (``f0`` 50 or 60 Hz, k up to
    ``harmonics``, below Nyquist) at which some channel's PSD (segments of about 4 s) has a
    narrow line, :data:`LINE_RATIO` times above the median of the bins within 5 Hz but
    more than 1 Hz away. A mains frequency counts when its fundamental or two harmonics
    show; then all its harmonics that show are returned."""
    f, S = psd(np.asarray(signals, dtype=float).reshape(len(signals), -1), dt)
    df = f[1] - f[0]
    out: list[float] = []
    if df > 0.5:  # segments under 2 s cannot tell a line from its neighbourhood
        return out
    for f0 in MAINS_HZ:
        found = []
        for k in range(1, harmonics + 1):
            fk = k * f0
            if fk >= f[-1] - 5.0:
                break
            i = int(round(fk / df))
            near = (np.abs(f - fk) <= 5.0) & (np.abs(f - fk) > 1.0)
            peak = S[max(i - 1, 0) : i + 2].max(axis=0)
            if np.any(peak > LINE_RATIO * np.median(S[near], axis=0)):
                found.append(fk)
        if f0 in found or len(found) >= 2:
            out += found
    return out


def notch(x: np.ndarray, dt: float, lines_hz: list[float], width_hz: float = 0.5) -> np.ndarray:
    """The columns of ``x`` without the bins within ``width_hz`` of each line (one FFT of the
    whole record: the same linear filter on every channel, so eq. 1 still holds)."""
    if not lines_hz:
        return x
    T = x.shape[0]
    X = np.fft.rfft(x, axis=0)
    f = np.fft.rfftfreq(T, dt)
    for fl in lines_hz:
        X[np.abs(f - fl) <= width_hz] = 0.0
    return np.fft.irfft(X, T, axis=0)


def without_hum(rec):
    """The recording (:class:`algid.recording.Recording`) with mains hum notched out of
    every channel alike (:func:`mains_lines`, :func:`notch`), and the lines removed [Hz]."""
    from . import Recording, motion

    kind, y = motion(rec)
    lines = mains_lines(np.column_stack([rec.u, y]), rec.dt)
    if not lines:
        return rec, []
    key = MOTION_FIELDS[kind]
    clean = {"t": rec.t, "u": notch(rec.u, rec.dt, lines), key: notch(y, rec.dt, lines)}
    return Recording(**clean, path=rec.path, units=rec.units, notes=rec.notes, missing=rec.missing), lines
