"""Robust-range screen of a recording: finite samples so far outside the channel's own range
that no sensor could have measured them (a bit flip, a logger's overflow marker, a
glitch of 1e3-1e100 times the signal).

Rule, per channel (every force and motion column): the deviations ``d = |y - median(y)|``
sorted from the largest; the channel's *robust range* ``R`` is the (:data:`RANGE_RANK` + 1)-th
largest, so that up to :data:`RANGE_RANK` absurd samples cannot set it; a sample with
``d > OUTLIER_RANGE * R`` is screened. The margin of that threshold on the clean records of
every suite (the identify and blind-diagnosis benchmarks, the realistic rigs, impact-hammer
tests with one to four hits, Silverbox and every F-16 record; the worst a single short hammer
hit) is measured by ``bench/outlier_screen.py`` (``docs/reliability.md``). A channel with
``R = 0`` (constant but for at most :data:`RANGE_RANK` samples, an unforced DOF with a glitch)
has every sample off its constant screened. More than
:data:`RANGE_RANK` absurd samples in one channel set its range and are not screened.

A screened sample is treated like a NaN: in the record handed to the noise model, the hum
notch, the derivatives and the surrogates it is replaced by the straight line between its
channel's nearest unscreened neighbours (so that it spreads nowhere), and the estimators
see its instant (and, for accelerations derived from velocities or displacements, the
instants whose derivative stencil reaches it) as not a number in every channel: the single
window reseeds there, the continuous estimator drops the windows in flight. The
bootstrap's surrogates see the same instants as not a number, so the uncertainty includes
what the lost samples cost.

:func:`screened_signals` is identify's first stage: the screen, then the mains hum notched out
of every channel alike (:func:`algid.recording.noise.without_hum`), an impact record's hits
found, its force cleaned and force and motion band-passed alike around the modes the chain is
to hold (:mod:`algid.recording.transient`), and the accelerations the estimators read
(measured, or the derivatives of the velocities or displacements): the record as every later
stage sees it (:class:`Signals`). When the fit check finds a multiplexed converter's channel
skew (:mod:`algid.diagnosis.timing`), the stages after it read the signals realigned
(:func:`on_time_signals`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..diagnosis.timing import channel_names, realign
from ..recording import DEFAULT_DIFF_POINTS, Recording, accelerations
from ..recording import motion as recording_motion
from ..recording.noise import without_hum
from ..recording.transient import Transient, transient_record

#: Deviations from the median that the robust range ignores (the largest ones).
RANGE_RANK = 4
#: A sample beyond this many robust ranges from its channel's median is screened.
OUTLIER_RANGE = 30.0
#: Screened samples listed one by one in the report (the count is always complete).
LISTED = 10


@dataclass(frozen=True)
class Screened:
    """Samples the screen took out of a recording.

    samples : (S,) sample indices (0-based rows of the recording), channels : (S,) column
    names (``u2``, ``a1`` ...), values : (S,) the recorded values, times_s : (S,) their
    instants [s]; rows : (T,) bool, the instants the estimators see as not a number.
    """

    samples: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    channels: tuple = ()
    values: np.ndarray = field(default_factory=lambda: np.zeros(0))
    times_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    rows: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    @property
    def count(self) -> int:
        """Number of screened samples (channel by channel)."""
        return int(self.samples.size)

    def to_json(self) -> dict:
        """``{"count", "rows_excluded", "rule", "samples": [{"channel", "sample", "t_s", "value"}, ...]}``
        (the first :data:`LISTED`)."""
        listed = [
            {"channel": c, "sample": int(s), "t_s": float(t), "value": float(v)}
            for c, s, t, v in zip(self.channels, self.samples, self.times_s, self.values)
        ][:LISTED]
        return {
            "count": self.count,
            "rows_excluded": int(np.count_nonzero(self.rows)),
            "rule": f"|y - median| > {OUTLIER_RANGE:g} x the channel's {RANGE_RANK + 1}th largest deviation",
            "samples": listed,
        }

    def line(self) -> str:
        """One line for the text report ('' when nothing was screened)."""
        if not self.count:
            return ""
        where = ", ".join(f"{c} at {t:.6g} s" for c, t in zip(self.channels[:3], self.times_s[:3]))
        more = f" and {self.count - 3} more" if self.count > 3 else ""
        return (
            f"screened {self.count} sample{'s' if self.count > 1 else ''} far outside the recording's range "
            f"({where}{more}); treated as missing"
        )


def outliers(y: np.ndarray) -> np.ndarray:
    """(T,) bool: the samples of one channel ``y`` beyond :data:`OUTLIER_RANGE` robust
    ranges from its median (module docstring)."""
    y = np.asarray(y, dtype=float)
    if y.size <= RANGE_RANK + 1:
        return np.zeros(y.shape, bool)
    d = np.abs(y - np.median(y))
    R = np.partition(d, d.size - 1 - RANGE_RANK)[d.size - 1 - RANGE_RANK]  # the (RANGE_RANK+1)-th largest
    with np.errstate(over="ignore"):
        return d > OUTLIER_RANGE * R


def _bridged(y: np.ndarray, bad: np.ndarray) -> np.ndarray:
    """``y`` with the ``bad`` samples on the straight line between their nearest good
    neighbours (held flat beyond the first or last good one)."""
    idx = np.arange(y.size)
    out = y.copy()
    out[bad] = np.interp(idx[bad], idx[~bad], y[~bad])
    return out


def screen(rec, reach: int = 0):
    """``(recording, Screened)``: the recording with its screened samples bridged, and what
    was screened; the rows the estimators must not see include the samples the reader bridged
    (:attr:`Recording.missing`). ``reach``: samples on either side of a screened instant that the
    estimators must not see either (the half-width of a derivative stencil)."""
    T = rec.t.size
    fields = {}
    samples, channels, values = [], [], []
    for role, arr in (("u", rec.u), ("a", rec.a), ("v", rec.v), ("x", rec.x)):
        if arr is None:
            continue
        out = None
        for j in range(arr.shape[1]):
            bad = outliers(arr[:, j])
            if not bad.any():
                continue
            out = arr.copy() if out is None else out
            out[:, j] = _bridged(arr[:, j], bad)
            at = np.flatnonzero(bad)
            samples.extend(at.tolist())
            channels.extend([f"{role}{j + 1}"] * at.size)
            values.extend(arr[at, j].tolist())
        if out is not None:
            fields[role] = out
    gaps = np.zeros(T, bool) if getattr(rec, "missing", None) is None else rec.missing
    rows = np.zeros(T, bool)
    order = np.argsort(samples, kind="stable")
    samples = np.asarray(samples, dtype=int)[order]
    for s in np.union1d(np.unique(samples), np.flatnonzero(gaps)):
        rows[max(0, s - reach) : s + reach + 1] = True
    if not samples.size:
        return rec, Screened(rows=rows)
    found = Screened(
        samples=samples,
        channels=tuple(np.asarray(channels)[order].tolist()),
        values=np.asarray(values)[order],
        times_s=np.asarray(rec.t, dtype=float)[samples],
        rows=rows,
    )
    return replace(rec, **fields), found


@dataclass(frozen=True)
class Signals:
    """The record as identify's stages after the screen see it (:func:`screened_signals`).

    rec : the recording screened, notched and, for an impact record, band-passed; raw : the
    same before the band-pass (the fit check reads it); a : (T, n) accelerations [m/s^2] the
    estimators read; kind, motion : the recorded motion's kind and (T, n) values; missing : (T,)
    bool, the instants the estimators see as not a number; hum_hz : the mains lines notched out
    [Hz]; screened : what the screen took out; transient : an impact record's hits, band and
    modes (None otherwise); dt [s], duration_s [s] (samples times dt); forced : (n,) bool, the
    DOFs that carry a force; timing : a multiplexed converter's channel skew the fit check found
    (:meth:`algid.diagnosis.timing.Timing.to_json`; the signals are realigned when its
    ``realigned``: :func:`on_time_signals`), None when it did not look.
    """

    rec: Recording
    raw: Recording
    a: np.ndarray
    kind: str
    motion: np.ndarray
    missing: np.ndarray
    hum_hz: tuple
    screened: Screened
    transient: Transient | None
    dt: float
    duration_s: float
    forced: np.ndarray
    timing: dict | None = None


def screened_signals(rec: Recording, band_hz: tuple | None = None) -> Signals:
    """Identify's first stage (module docstring); ``band_hz``: an impact record's band
    (:func:`algid.recording.transient.transient_record`)."""
    # a derived acceleration's stencil reaches half its width past a screened sample
    rec, found = screen(rec, reach=0 if rec.a is not None else DEFAULT_DIFF_POINTS // 2)
    missing = found.rows
    rec, hum = without_hum(rec)
    raw, (rec, transient) = rec, transient_record(rec, band_hz)
    if transient is not None:
        missing = missing | transient.missing
    kind, motion = recording_motion(rec)
    return Signals(
        rec=rec,
        raw=raw,
        a=accelerations(rec, DEFAULT_DIFF_POINTS),
        kind=kind,
        motion=motion,
        missing=missing,
        hum_hz=tuple(hum),
        screened=found,
        transient=transient,
        dt=float(rec.dt),
        duration_s=rec.t.size * rec.dt,
        forced=np.any(rec.u != 0.0, axis=0),
    )


def on_time_signals(sig: Signals, timing: dict | None) -> Signals:
    """``sig`` with the channel skew ``timing`` (:meth:`algid.diagnosis.timing.Timing.to_json`)
    recorded and, when it was found to be a converter's, undone."""
    if timing is None or not timing["realigned"]:
        return replace(sig, timing=timing)
    rec = realign(sig.rec, np.array([timing["late_samples"][c] for c in channel_names(sig.rec)]))
    _, motion = recording_motion(rec)
    return replace(sig, rec=rec, raw=rec, a=accelerations(rec, DEFAULT_DIFF_POINTS), motion=motion, timing=timing)
