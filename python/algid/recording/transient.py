"""Transient (impact hammer) records: the hits, the band of the modes, and the record made ready
for eq. 1.

A hammer test is a few short pulses of force and the structure's decay after each. Its time and
frequency scales are in the *response*; the force's spectrum is flat up to the pulse's cut-off,
and its sensor's baseline drift after a hit (an AC-coupled amplifier's undershoot) puts most of
the force's "signal" at a few hertz. So, decided once from the record (:func:`analyse_transient`):

* **Hits** (:func:`find_hits`): the force with its slow baseline taken out (a running median of
  :data:`BASELINE_S`, which keeps steps and removes pulses shorter than half of it) stands
  above ``max(`` :data:`HIT_NOISE` ``sigma,`` :data:`HIT_SHARE` ``of its peak)`` (``sigma`` the
  force's white noise from its first differences) in short runs; runs closer than
  :data:`DOUBLE_HIT_S` are one hit (a double hit: the hammer bounced). The record is a transient
  when the hits hold at least :data:`ENERGY_SHARE` of that force's energy in at most
  :data:`SPAN_SHARE` of the record, and its baseline swings by at most :data:`BASELINE_SWING`
  of the highest hit (not the steps of a bang-bang drive).
* **Force** (:func:`clean_force`): inside every hit (widened by :data:`HIT_MARGIN_S`) the force
  less its baseline, which goes from the level just before the hit to the level just after as
  the hit's charge passes (an AC-coupled amplifier's undershoot follows the force's running
  integral); zero outside.
* **Segments**: each hit with what follows it up to the next hit's pre-trigger; its pre-trigger
  is the quiet before the hit (at most :data:`PRETRIGGER_S`).
* **Modes** (:func:`response_modes`): peaks of the response's power spectrum averaged over the
  segments (one FFT per segment, from its hit on), standing :data:`PEAK_PROMINENCE` times above
  their surroundings and :data:`PEAK_FLOOR` times above the spectrum's median, between
  :data:`MIN_CYCLES` cycles of the longest segment and :data:`TOP_SHARE` of the sampling rate
  (a hit soon followed by another still leaves the slow modes to the long decays).
* **Band**: given (``--band LO:HI``), or chosen from the modes' *kinetic energy* in the decays
  (:func:`mode_energies`: the velocity's power spectrum, whatever the sensor measures, summed
  over each mode's own band), not from their order: the modes holding at least
  :data:`SHOWN_SHARE` of the strongest one's energy are the ones the response shows; of them, the
  ``n`` adjacent ones (a chain of ``n`` DOF) holding the most energy are held, in a band
  symmetric in log frequency around them and as wide as the modes allow: its edges stay at the
  geometric mean with the nearest shown mode on either side (whichever is closer); with no shown
  mode outside, with the nearest peak; with no peak outside, an octave. A weak first mode next to
  a strong one thus neither takes the chain nor pulls the band's edge onto the strong one. The modes
  outside are *residual modes*: they are filtered out, not blamed on the chain.
* **Filter** (:func:`band_pass`): a Butterworth band-pass of order :data:`FILTER_ORDER`, zero phase,
  the same on the force and on every motion channel over the whole record: a linear
  time-invariant filter applied alike to both sides leaves eq. 1 unchanged. The record's end,
  where the backward pass has not settled (:func:`settling`), is marked missing. The hits of one
  record are one continuous signal: files of separate hits joined end to end have a jump at every
  join that no filter or window explains (identify such hits one by one).
* **Noise**: the white-noise RMS of the raw motion and force (:func:`algid.recording.noise.channel`'s
  floor), read before the band-pass.
* **Quiet level**: the response's RMS in the band over the pre-triggers (each band-passed alone:
  the whole record's zero-phase filter smears a hit backwards), or over the last tenth of the
  segments when no pre-trigger lasts :data:`QUIET_PERIODS` periods of the band's lower edge.
* **Across hits** (:func:`across_hits`): with two hits or more, one FFT per segment (the shortest
  segment's length), averaged across hits: H1 and the coherence of force and response. A Welch
  estimate inside one decaying hit measures nothing.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

#: Running-median length that separates a hit from the force's baseline [s].
BASELINE_S = 0.02
#: A hit stands this many white-noise sigmas above the baseline...
HIT_NOISE = 10.0
#: ... and this share of the highest pulse.
HIT_SHARE = 0.1
#: Pulses closer than this are one hit (a double hit) [s].
DOUBLE_HIT_S = 0.02
#: A transient's hits hold at least this share of the force's energy (baseline removed)...
ENERGY_SHARE = 0.9
#: ... in at most this share of the record.
SPAN_SHARE = 0.05
#: The force's baseline swings by at most this share of the highest hit (a hammer's sensor
#: drifts by a few percent of the hit; the steps of a bang-bang drive, which the running median
#: keeps, are as high as its force).
BASELINE_SWING = 0.25
#: A hit's extent is widened by this on each side [s].
HIT_MARGIN_S = 2e-3
#: Longest quiet before a hit counted as its pre-trigger [s].
PRETRIGGER_S = 0.1
#: A mode's peak stands this many times above its flanks (power)...
PEAK_PROMINENCE = 10.0
#: ... and above the median of the response's power spectrum.
PEAK_FLOOR = 30.0
#: A peak holding less than this share of the strongest mode's kinetic energy is not one of the
#: modes the band is chosen from: neither held nor keeping the band's edges off (it stays a
#: residual mode).
SHOWN_SHARE = 0.01
#: Modes below this many cycles per segment are not resolved.
MIN_CYCLES = 10
#: Highest mode searched, as a share of the sampling rate (an anti-alias filter's band).
TOP_SHARE = 0.4
#: Order of the Butterworth band-pass (run forwards and backwards).
FILTER_ORDER = 4
#: Shortest pre-trigger that gives the quiet level, in periods of the band's lower edge.
QUIET_PERIODS = 2.0
#: The band-pass has settled once its impulse response stays below this share of its peak.
SETTLE = 1e-3


@dataclass(frozen=True)
class Hit:
    """One hit: samples ``[start, stop)`` of its pulses, its peak force, how many pulses."""

    start: int
    stop: int
    peak: float
    pulses: int = 1


@dataclass(frozen=True)
class Transient:
    """What :func:`analyse_transient` found in a hammer test (module docstring)."""

    dt: float
    hits: tuple
    segments: tuple  #: per hit, ``(first, stop)`` samples: its pre-trigger, the hit and its decay
    pretrigger: tuple  #: per hit, samples of quiet before it
    modes_hz: tuple  #: response spectral peaks over the decays [Hz]
    band_hz: tuple  #: (low, high) edges of the band-pass [Hz]
    band_source: str  #: "given" or what set the band
    quiet_rms: float = float("nan")  #: response RMS in the band over the quiet parts
    decay_rms: float = float("nan")  #: response RMS in the band over the decays
    missing: np.ndarray = None  #: (T,) samples the filter's ends make unusable
    #: white-noise RMS of the raw motion and force channels (before the band-pass, which leaves a
    #: white floor nowhere to read): what the weak form's noise terms are given
    noise_rms: tuple = (float("nan"), float("nan"))

    @property
    def in_band_hz(self) -> tuple:
        return tuple(f for f in self.modes_hz if self.band_hz[0] <= f <= self.band_hz[1])

    @property
    def residual_hz(self) -> tuple:
        """The response's modes outside the band: filtered out, not the chain's."""
        return tuple(f for f in self.modes_hz if not self.band_hz[0] <= f <= self.band_hz[1])

    def to_json(self) -> dict:
        return {
            "hits": [
                {"time_s": h.start * self.dt, "peak": h.peak, "pulses": h.pulses, "double": h.pulses > 1}
                for h in self.hits
            ],
            "pretrigger_s": [p * self.dt for p in self.pretrigger],
            "band_hz": list(self.band_hz),
            "band_source": self.band_source,
            "modes_in_band_hz": list(self.in_band_hz),
            "residual_modes_hz": list(self.residual_hz),
            "decay_over_quiet_db": _db(self.decay_rms / self.quiet_rms),
        }

    def line(self) -> str:
        """One line for the summaries."""
        doubles = sum(h.pulses > 1 for h in self.hits)
        hits = f"{len(self.hits)} hit{'s' if len(self.hits) > 1 else ''}" + (f" ({doubles} double)" if doubles else "")
        lo, hi = self.band_hz
        res = ", ".join(f"{f:.4g}" for f in self.residual_hz) or "none"
        return f"impact record, {hits}; band {lo:.4g}-{hi:.4g} Hz ({self.band_source}); residual modes [Hz]: {res}"


def _db(ratio: float):
    return float(20 * np.log10(ratio)) if np.isfinite(ratio) and ratio > 0 else None


def white_sigma(x: np.ndarray) -> float:
    """White-noise standard deviation of ``x`` from its first differences (robust: 1.4826 MAD)."""
    d = np.diff(x)
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2))


def baseline(u: np.ndarray, dt: float) -> np.ndarray:
    """The force's slow baseline: its running median over :data:`BASELINE_S`."""
    from scipy.ndimage import median_filter

    return median_filter(u, size=max(3, int(round(BASELINE_S / dt)) | 1), mode="nearest")


def find_hits(u: np.ndarray, dt: float, base: np.ndarray | None = None) -> tuple[list[Hit], float]:
    """Hits of the force ``u`` (T,) sampled every ``dt`` [s] and the share of the baseline-free
    force's energy they hold (module docstring); ``base``: its :func:`baseline`, if at hand."""
    r = u - (baseline(u, dt) if base is None else base)
    top = float(np.max(np.abs(r)))
    if top == 0.0:
        return [], 0.0
    above = np.abs(r) > max(HIT_NOISE * white_sigma(u), HIT_SHARE * top)
    edges = np.diff(np.concatenate([[0], above.astype(int), [0]]))
    runs = list(zip(np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]))
    margin = int(round(HIT_MARGIN_S / dt))
    hits: list[Hit] = []
    for lo, hi in runs:
        lo, hi = max(0, lo - margin), min(u.size, hi + margin)
        if hits and lo - hits[-1].stop < DOUBLE_HIT_S / dt:
            last = hits[-1]
            if hi - lo > 0 and np.max(np.abs(r[lo:hi])) > 0:
                hits[-1] = replace(last, stop=hi, pulses=last.pulses + 1, peak=max(last.peak, _peak(r, lo, hi)))
            continue
        hits.append(Hit(int(lo), int(hi), _peak(r, lo, hi)))
    inside = sum(float(np.sum(r[h.start : h.stop] ** 2)) for h in hits)
    return hits, inside / float(np.sum(r**2))


def _peak(r: np.ndarray, lo: int, hi: int) -> float:
    i = lo + int(np.argmax(np.abs(r[lo:hi])))
    return float(r[i])


def is_transient(hits: list[Hit], share: float, T: int, swing: float = 0.0) -> bool:
    """Hits holding most of the force's energy in a small part of the record, above a baseline
    that swings (``swing``: its largest excursion from its median) by at most
    :data:`BASELINE_SWING` of the highest hit."""
    span = sum(h.stop - h.start for h in hits)
    top = max((abs(h.peak) for h in hits), default=0.0)
    return bool(hits) and share >= ENERGY_SHARE and span <= SPAN_SHARE * T and swing <= BASELINE_SWING * top


def clean_force(u: np.ndarray, hits: list[Hit], dt: float) -> np.ndarray:
    """The force (T, q) inside the hits less its baseline, zero outside: the baseline goes from
    the level before a hit to the level after it (each the median over :data:`HIT_MARGIN_S`) as
    the hit's charge passes (its running share of the hit's ``|force - level before|`` beyond the
    two levels' difference): an AC-coupled amplifier's undershoot grows with the force's running
    integral."""
    out = np.zeros_like(u)
    w = max(1, int(round(HIT_MARGIN_S / dt)))
    for h in hits:
        before = np.median(u[max(0, h.start - w) : h.start + 1], axis=0)
        after = np.median(u[h.stop - 1 : h.stop + w], axis=0)
        swing = np.abs(after - before)  # the baseline's own share, left out of the charge
        charge = np.cumsum(np.maximum(np.abs(u[h.start : h.stop] - before) - swing, 0.0), axis=0)
        s = charge / np.where(charge[-1] > 0, charge[-1], 1.0)
        out[h.start : h.stop] = u[h.start : h.stop] - (before + s * (after - before))
    return out


def segments(hits: list[Hit], T: int, dt: float) -> tuple[list[tuple[int, int]], list[int]]:
    """Per hit its segment ``(first, stop)`` (the pre-trigger, the hit, its decay) and its
    pre-trigger length [samples]."""
    pre_max = int(round(PRETRIGGER_S / dt))
    firsts, pres = [], []
    for i, h in enumerate(hits):
        prev = hits[i - 1].stop if i else 0
        first = max(prev + (h.start - prev) // 2 if i else 0, h.start - pre_max)
        firsts.append(first)
        pres.append(h.start - first)
    stops = firsts[1:] + [T]
    return list(zip(firsts, stops)), pres


def decay_spectrum(y: np.ndarray, dt: float, hits: list[Hit], segs: list[tuple[int, int]]):
    """Frequencies [Hz] and power spectrum of the response ``y`` (T,) summed over the decays (one
    FFT per segment from its hit on, all of the longest segment's length), and the mask of the
    frequencies searched for modes (module docstring)."""
    N = max(stop - h.start for h, (_, stop) in zip(hits, segs))
    P = np.zeros(N // 2 + 1)
    for h, (_, stop) in zip(hits, segs):
        z = y[h.start : stop] - np.mean(y[h.start : stop])
        P += np.abs(np.fft.rfft(z, N)) ** 2
    f = np.fft.rfftfreq(N, dt)
    keep = (f >= MIN_CYCLES / (N * dt)) & (f <= TOP_SHARE / dt)  # resolved in the longest decay
    return f, P, keep


def response_modes(f: np.ndarray, P: np.ndarray, keep: np.ndarray) -> tuple[float, ...]:
    """Spectral peaks [Hz] of the decays' power spectrum ``P`` over ``f[keep]`` (module docstring)."""
    from scipy.signal import find_peaks

    if np.count_nonzero(keep) < 3:
        return ()
    idx = np.nonzero(keep)[0]
    peaks, _ = find_peaks(np.log(P[idx] + 1e-300), prominence=np.log(PEAK_PROMINENCE))
    floor = np.median(P[idx])
    return tuple(float(f[idx[i]]) for i in peaks if P[idx[i]] >= PEAK_FLOOR * floor)


def mode_energies(f: np.ndarray, P: np.ndarray, modes: tuple, order: int) -> np.ndarray:
    """Kinetic energy of each mode in the decays (arbitrary unit): the velocity's power spectrum
    (``P`` of a motion of derivative ``order``, 0 displacement, 1 velocity, 2 acceleration, times
    ``(2 pi f)^(2 - 2 order)``) summed over the mode's own band, between the geometric means with
    its neighbouring modes (the first's and the last's mirrored in log frequency; an octave
    either side of a lone mode)."""
    m = np.asarray(modes, float)
    Pv = P * (2 * np.pi * np.maximum(f, f[1])) ** (2.0 - 2.0 * order)
    mid = np.sqrt(m[:-1] * m[1:])
    lo = np.concatenate([[m[0] ** 2 / mid[0] if mid.size else m[0] / 2], mid])
    hi = np.concatenate([mid, [m[-1] ** 2 / mid[-1] if mid.size else m[-1] * 2]])
    return np.array([np.sum(Pv[(f >= a) & (f < b)]) for a, b in zip(lo, hi)])


def choose_band(modes: tuple, energies, n: int, dt: float, given: tuple | None) -> tuple[tuple[float, float], str]:
    """Band-pass edges [Hz] and what set them (module docstring)."""
    if given is not None:
        lo, hi = float(given[0]), float(given[1])
        if not 0 < lo < hi < 0.5 / dt:
            raise ValueError(f"band must satisfy 0 < LO < HI < {0.5 / dt:g} Hz (the Nyquist rate), got {lo:g}:{hi:g}")
        return (lo, hi), "given"
    if not modes:
        raise ValueError("impact record: no mode stands out of the response's spectrum; give the band (--band LO:HI)")
    every, e = np.asarray(modes, float), np.asarray(energies, float)
    shown = e >= SHOWN_SHARE * e.max()
    m, e = every[shown], e[shown]
    k = min(n, m.size)
    i = int(np.argmax(np.convolve(e, np.ones(k), "valid")))  # the k adjacent modes holding the most energy
    first, last = m[i], m[i + k - 1]
    r = min(_edge_ratio(first, last, m) or _edge_ratio(first, last, every) or 2.0, 0.99 * 0.5 / dt / last)
    what = "the strongest mode" if k == 1 else f"the {k} adjacent modes holding the most energy"
    return (float(first / r), float(last * r)), f"around {what} of the response"


def _edge_ratio(first: float, last: float, modes: np.ndarray) -> float | None:
    """How far [ratio] a band symmetric in log frequency may reach beyond ``first`` and ``last``
    [Hz] before the geometric mean with the nearest of ``modes`` outside it; None if none is."""
    below, above = modes[modes < first], modes[modes > last]
    ratios = ([np.sqrt(first / below.max())] if below.size else []) + (
        [np.sqrt(above.min() / last)] if above.size else []
    )
    return min(ratios, default=None)


def _sos(dt: float, band_hz: tuple):
    from scipy.signal import butter

    return butter(FILTER_ORDER, band_hz, btype="bandpass", fs=1.0 / dt, output="sos")


def band_pass(x: np.ndarray, dt: float, band_hz: tuple) -> np.ndarray:
    """``x`` (T, c) band-passed forwards and backwards from rest (no padding: the record starts at
    rest, so the forward pass is exact; the backward pass starts cold at the end, which
    :func:`settling` masks)."""
    from scipy.signal import sosfiltfilt

    return sosfiltfilt(_sos(dt, band_hz), x, axis=0, padtype=None)


def settling(dt: float, band_hz: tuple) -> int:
    """Samples after which the band-pass's impulse response stays below :data:`SETTLE` of its
    peak: the end of a record where the backward pass has not settled."""
    from scipy.signal import sosfilt

    N = int(np.ceil(50.0 / (band_hz[1] - band_hz[0]) / dt)) + 8
    h = np.abs(sosfilt(_sos(dt, band_hz), np.r_[1.0, np.zeros(N - 1)]))
    return int(np.nonzero(h > SETTLE * h.max())[0][-1]) + 1


def analyse_transient(u: np.ndarray, y: np.ndarray, dt: float, n: int, band_hz: tuple | None = None, order: int = 2):
    """The :class:`Transient` of a record with forces ``u`` (T, q) and response ``y`` (T, c) of
    derivative ``order`` (0 displacement, 1 velocity, 2 acceleration), or None when the record is
    not a hammer test (module docstring)."""
    from .noise import channel

    drive = int(np.argmax(np.max(np.abs(u - np.median(u, axis=0)), axis=0)))
    base = baseline(u[:, drive], dt)
    hits, share = find_hits(u[:, drive], dt, base)
    T = u.shape[0]
    if not is_transient(hits, share, T, float(np.max(np.abs(base - np.median(base))))):
        return None
    segs, pres = segments(hits, T, dt)
    resp = y[:, drive] if y.shape[1] > drive else y[:, 0]
    f, P, keep = decay_spectrum(resp, dt, hits, segs)
    modes = response_modes(f, P, keep)
    band, source = choose_band(modes, mode_energies(f, P, modes, order) if modes else (), n, dt, band_hz)
    yb = band_pass(resp[:, None], dt, band)[:, 0]
    settle = settling(dt, band)
    decay = np.concatenate([yb[h.stop : stop] for h, (_, stop) in zip(hits, segs)])
    tr = Transient(
        dt=float(dt),
        hits=tuple(hits),
        segments=tuple(segs),
        pretrigger=tuple(pres),
        modes_hz=modes,
        band_hz=band,
        band_source=source,
        decay_rms=float(np.sqrt(np.mean(decay**2))) if decay.size else float("nan"),
        missing=np.arange(T) >= T - settle,
        noise_rms=(channel("y", resp, dt).sigma, channel("u", u[:, drive], dt).sigma),
    )
    quiet = np.concatenate(quiet_parts(resp, tr))
    return replace(tr, quiet_rms=float(np.sqrt(np.mean(quiet**2))) if quiet.size else float("nan"))


def quiet_parts(y: np.ndarray, tr: Transient) -> list[np.ndarray]:
    """The response ``y`` (T,) in the band over each quiet part of the record (module docstring):
    each pre-trigger band-passed alone (the whole record's zero-phase filter smears the hit back
    into it); without one of :data:`QUIET_PERIODS` of the band's lower edge, the last tenth of
    each segment before the filter's unsettled end."""
    least = QUIET_PERIODS / tr.band_hz[0] / tr.dt
    segs = zip(tr.segments, tr.pretrigger)
    pre = [band_pass(y[f : f + p, None], tr.dt, tr.band_hz)[:, 0] for (f, _), p in segs if p >= least]
    if pre:
        return pre
    yb, settle = band_pass(y[:, None], tr.dt, tr.band_hz)[:, 0], int(np.count_nonzero(tr.missing))
    return [yb[max(f, stop - settle - (stop - f) // 10) : max(f, stop - settle)] for f, stop in tr.segments]


def transient_record(rec, band_hz: tuple | None = None):
    """``(record, transient)``: a hammer test made ready for eq. 1 (its forces cleaned, forces and
    motions band-passed alike, :func:`analyse_transient`), or the record unchanged and None."""
    order, motion = next((o, m) for o, m in ((2, rec.a), (1, rec.v), (0, rec.x)) if m is not None)
    tr = analyse_transient(rec.u, motion, float(rec.dt), rec.n, band_hz, order)
    if tr is None:
        if band_hz is not None:
            raise ValueError("--band applies to impact records, and no hit was found in the force")
        return rec, None
    u = band_pass(clean_force(rec.u, list(tr.hits), tr.dt), tr.dt, tr.band_hz)
    moved = {k: band_pass(getattr(rec, k), tr.dt, tr.band_hz) for k in ("a", "v", "x") if getattr(rec, k) is not None}
    note = f"{tr.line()}; force and motion band-passed alike"
    return replace(rec, u=u, **moved, notes=list(rec.notes) + [note]), tr


def across_hits(u: np.ndarray, y: np.ndarray, tr: Transient) -> dict:
    """H1 and coherence of force ``u`` (T,) and response ``y`` (T,) across the hits: one FFT per
    segment over the shortest segment's length, averaged across hits. Frequencies [Hz], ``h1``,
    ``coherence`` and ``hits``; ``coherence`` is 1 by construction with one hit."""
    N = min(stop - first for first, stop in tr.segments)
    U = np.array([np.fft.rfft(u[first : first + N]) for first, _ in tr.segments])
    Y = np.array([np.fft.rfft(y[first : first + N]) for first, _ in tr.segments])
    Suu, Syy, Suy = np.mean(np.abs(U) ** 2, 0), np.mean(np.abs(Y) ** 2, 0), np.mean(U.conj() * Y, 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        h1, coh = Suy / Suu, np.abs(Suy) ** 2 / (Suu * Syy)
    return {"f_hz": np.fft.rfftfreq(N, tr.dt), "h1": h1, "coherence": coh, "force_power": Suu, "hits": len(tr.segments)}


def band_option(text: str) -> tuple[float, float]:
    """``LO:HI`` [Hz] of ``--band``."""
    import argparse

    try:
        lo, hi = (float(x) for x in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LO:HI in Hz, got {text!r}") from None
    return lo, hi


def add_band_option(p) -> None:
    """``--band LO:HI`` of ``algid identify`` and ``algid diagnose``."""
    p.add_argument(
        "--band",
        type=band_option,
        metavar="LO:HI",
        help="impact records: the band [Hz] whose modes the chain holds (default: around the n adjacent modes "
        "holding the most kinetic energy in the response); force and response are band-passed alike and the "
        "modes outside are reported as residual modes",
    )
