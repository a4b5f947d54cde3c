"""Channel timing: the sub-sample skew of a multiplexed converter, found and undone.

A multiplexed ADC samples its channels one after the other: channel ``c`` of a scan holds
its signal ``delta_c`` samples late (``0 <= delta_c < 1``, one value per channel, the same
for the whole record). To first order a late force is an input delay and a late sensor a
sensor low-pass, so left in the record it would be diagnosed as one of them, or as nothing
the vocabulary knows. What tells the converter apart is its pattern: *several* channels, each
with its own sub-sample lateness, where an input delay or a sensor's low-pass makes one
channel late and leaves the rest on time.

The estimate (Gauss-Newton on the delays, variable projection on the chain): every channel
``c`` but a reference is shifted by ``-delta_c`` (cubic spline), the linear chain is refitted
on the shifted record (:class:`ChainFit`: the diagnosis's windows and signal band, with an
effect's force columns when the diagnosis asks), and the
Jacobian of its in-sample equation errors with respect to each delay is taken by finite
differences of :data:`STEP` samples. The record is realigned only when

* at least :data:`MIN_CHANNELS` channels sit apart from the median lateness by more than
  :data:`Z_DELAY` of their standard deviations (the converter's pattern, not one late
  channel),
* every lateness lies within :data:`MAX_SPREAD` samples of the others (a scan lasts at most
  one sample period), and
* the realigned linear chain leaves a withheld gap at most :data:`GAIN` times the record's,
  and at most :data:`GAIN` times what the best lateness of one channel alone leaves (the
  channel whose lateness alone buys most to first order; one late channel, however many
  others its bias moves, is an input delay or a sensor's low-pass: the candidates' business).

A record with one force and one response channel has a single relative lateness: a late
force there *is* an input delay in every respect the record can show, and it is left to the
candidates.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.interpolate import CubicSpline

from ..recording import Recording, accelerations
from ..recording import motion as recording_motion
from ..recording.derivatives import MOTION_FIELDS
from .candidates import lead_in
from .equations import linear_design, target
from .gram import EqSpec, cross_validate, window_stats
from .integrals import integrals
from .linear import linear_specs
from .windows import band_filter, detrend, prepare

#: Windows of the record the latenesses are estimated on.
WINDOWS = 16
#: Finite-difference step of the Jacobian [samples].
STEP = 0.05
#: Gauss-Newton passes at most, the largest step of one [samples], and the step that ends them.
PASSES = 6
MAX_STEP = 0.5
TOLERANCE = 0.005
#: A pass that leaves more than this share of the chain's squared in-sample errors ends the search.
FIRST_GAIN = 0.8
#: Channels apart from the median lateness that make a converter's pattern.
MIN_CHANNELS = 2
#: How far apart, in standard deviations of the estimate, a channel must sit.
Z_DELAY = 6.0
#: Largest spread of the latenesses [samples] a scan can have (with the estimate's slack).
MAX_SPREAD = 1.1
#: The realigned chain's withheld gap must be at most this fraction of the record's.
GAIN = 0.7


@dataclass
class Timing:
    """Channel latenesses found in a record.

    channels : names of the channels, ``u<i>`` (forces) and ``y<i>`` (the recorded motion).
    late : (C,) lateness of each channel relative to the median one [samples].
    late_std : (C,) standard deviation of each [samples].
    gap_before, gap_after : withheld gaps of the linear chain on the record's first windows
        (:data:`WINDOWS`), as recorded and realigned.
    realigned : whether the record was realigned (the pattern and the gain held).
    pattern : whether the latenesses form a converter's pattern (module docstring, the first
        two tests), whatever the gain.
    """

    channels: list[str]
    late: np.ndarray
    late_std: np.ndarray
    gap_before: float
    gap_after: float
    realigned: bool
    pattern: bool = False

    def to_json(self) -> dict:
        return {
            "realigned": self.realigned,
            "late_samples": {c: float(d) for c, d in zip(self.channels, self.late)},
            "late_std_samples": {c: float(s) for c, s in zip(self.channels, self.late_std)},
            "gap_before": self.gap_before,
            "gap_after": self.gap_after,
        }


def timing_lines(doc: dict | None, indent: str = "  ") -> list[str]:
    """What the report says of a record realigned (``doc``: :meth:`Timing.to_json`)."""
    if not doc or not doc["realigned"]:
        return []
    late = ", ".join(f"{c} {d:+.3f} +- {doc['late_std_samples'][c]:.3f}" for c, d in doc["late_samples"].items())
    return [
        f"{indent}channel skew (a multiplexed converter), undone before the fit [samples late]: {late}",
        f"{indent}  linear-chain gap {doc['gap_before']:.4g} -> {doc['gap_after']:.4g} once realigned",
    ]


def shifted(x: np.ndarray, late: float) -> np.ndarray:
    """The column ``x`` taken ``late`` samples earlier: a channel recorded that late, on time."""
    k = np.arange(x.shape[0], dtype=float)
    return CubicSpline(k, x, extrapolate=True)(k - late)


def _channels(rec: Recording) -> list[tuple[str, int]]:
    """The channels a converter sampled (every forced DOF's force, every motion column)."""
    forced = np.nonzero(np.any(np.asarray(rec.u) != 0.0, axis=0))[0]
    return [("u", int(i)) for i in forced] + [("y", i) for i in range(recording_motion(rec)[1].shape[1])]


def channel_names(rec: Recording) -> list[str]:
    """``u<i>`` (forces) and ``y<i>`` (the recorded motion) of :func:`_channels`, in its order."""
    return [f"{w}{i + 1}" for w, i in _channels(rec)]


def realign(rec: Recording, late: np.ndarray) -> Recording:
    """The record with every channel moved ``late[c]`` samples earlier (:func:`_channels` order)."""
    kind, y = recording_motion(rec)
    u, y = np.array(rec.u, dtype=float), np.array(y, dtype=float)
    for (which, i), d in zip(_channels(rec), late):
        if d != 0.0:
            x = u if which == "u" else y
            x[:, i] = shifted(x[:, i], float(d))
    return replace(rec, u=u, **{MOTION_FIELDS[kind]: y})


@dataclass(frozen=True)
class ChainFit:
    """How the timing fits the chain to a record: windows of ``L`` samples from ``skip`` on,
    fitted and scored on ``[0, band_hz]`` (the diagnosis's signal band; the whole spectrum when
    None), with ``effect`` (equation -> (N, q) force columns on the samples from ``skip`` on)
    beside the chain's columns, each equation's with coefficients of its own, when given."""

    boundary: object
    L: int
    skip: int
    band_hz: float | None = None
    effect: dict | None = None

    def __call__(self, rec: Recording, late: np.ndarray) -> tuple[np.ndarray, float]:
        """The chain on ``rec`` realigned by ``late``: (in-band in-sample errors, withheld gap)."""
        r = realign(rec, late)
        a = accelerations(r)
        u, dt = np.asarray(r.u, dtype=float), float(r.dt)
        P = prepare(a, u, dt, self.L, self.boundary, self.skip, A=integrals(a, dt), band_hz=self.band_hz, fit_band=True)
        specs = linear_specs(P) if self.effect is None else self._specs(P)
        cv = cross_validate(P, window_stats(P, specs))
        gam = cv.theta[cv.stats.shared] if self.effect is not None else None
        raw = np.stack(
            [
                sp.y - sp.X @ cv.theta[sl] - (0.0 if gam is None else sp.E @ gam)
                for sp, sl in zip(specs, cv.stats.slices)
            ],
            axis=1,
        )
        return band_filter(P, detrend(P, raw)).ravel(), float(np.sqrt(cv.test_sse.sum() / np.sum(P.y**2)))

    def _specs(self, P) -> list[EqSpec]:
        """The chain's equations on ``P`` with the effect's columns, a block of shared columns
        per equation (zero in the others)."""
        N = P.nw * P.L
        total = sum(cols.shape[1] for cols in self.effect.values())
        specs, at = [], 0
        for e in range(P.n):
            E = np.zeros((N, total))
            if e in self.effect:
                E[:, at : at + self.effect[e].shape[1]] = self.effect[e][:N]
                at += self.effect[e].shape[1]
            specs.append(EqSpec(e=e, X=linear_design(P, e), y=target(P, e), E=E, key=("base", e)))
        return specs


def _head(rec: Recording, samples: int) -> Recording:
    """The first ``samples`` samples of ``rec`` (every per-sample array cut alike)."""
    cut = {
        k: getattr(rec, k)[:samples]
        for k in ("t", "u", "a", "v", "x", "base", "missing")
        if getattr(rec, k) is not None
    }
    return replace(rec, dt=float(rec.dt), **cut)


def _gauss_newton(rec, late, which, r, fit: ChainFit, stop_above=np.inf):
    """Gauss-Newton in the latenesses of the channels ``which`` (the others held) from ``late``,
    whose errors are ``r``: steps of at most :data:`MAX_STEP`, until one is below
    :data:`TOLERANCE` or leaves more than ``stop_above`` of the starting squared errors. Returns
    the latenesses, their errors and the Jacobians of the first and the last pass."""
    late, start, first, J = late.copy(), float(r @ r), None, None
    for _ in range(PASSES):
        nudged = [late + STEP * np.eye(late.size)[c] for c in which]
        J = np.stack([(fit(rec, x)[0] - r) / STEP for x in nudged], 1)
        first = J if first is None else first
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        step *= min(1.0, MAX_STEP / max(float(np.max(np.abs(step))), 1e-300))
        late[which] += step
        r = fit(rec, late)[0]
        if float(r @ r) > stop_above * start or np.max(np.abs(step)) < TOLERANCE:
            break
    return late, r, first, J


def channel_timing(rec: Recording, fit: ChainFit) -> Timing | None:
    """The latenesses of ``rec``'s channels (module docstring), estimated on its first
    :data:`WINDOWS` windows of ``fit`` (the latenesses are the converter's, the same all
    along); None with fewer than three channels (one relative lateness is an input delay or a
    sensor's, not a pattern)."""
    C = len(_channels(rec))
    if C < 3:
        return None
    rec = _head(rec, fit.skip + WINDOWS * fit.L)
    free = np.arange(1, C)  # the first channel is the reference: only differences are seen
    r0, gap_before = fit(rec, np.zeros(C))
    # a pass that does not buy what a converter's skew would ends the search: no pattern to look for
    late, r, J0, J = _gauss_newton(rec, np.zeros(C), free, r0, fit, stop_above=FIRST_GAIN)
    cov = np.linalg.pinv(J.T @ J) * float(r @ r) / max(r.size - free.size, 1)
    std = np.zeros(C)
    std[free] = np.sqrt(np.maximum(np.diag(cov), 0.0))
    _, gap_after = fit(rec, late)
    late = late - np.median(late)
    apart = np.abs(late) > Z_DELAY * np.maximum(std, np.max(std[free]))
    # the reference channel late by d is every other channel early by d
    gap_one = _one_channel_gap(rec, np.column_stack([-J0.sum(axis=1), J0]), r0, fit)
    pattern = int(np.sum(apart)) >= MIN_CHANNELS and float(np.ptp(late)) <= MAX_SPREAD
    gain = gap_after <= GAIN * gap_before and gap_after <= GAIN * gap_one
    return Timing(channel_names(rec), late, std, gap_before, gap_after, pattern and gain, pattern)


def _one_channel_gap(rec: Recording, J0: np.ndarray, r0: np.ndarray, fit: ChainFit) -> float:
    """The withheld gap left by the best lateness of one channel alone (:func:`_gauss_newton`
    in that one lateness): what an input delay or a sensor's low-pass, which make one channel
    late, would explain. The channel is the one whose lateness alone, to first order (``J0``:
    the errors' Jacobian at no lateness, a column per channel; ``r0``: the errors there), buys
    the most."""
    g = J0.T @ r0
    c = int(np.argmax(g**2 / np.maximum(np.sum(J0**2, axis=0), 1e-300)))
    one = np.zeros(J0.shape[1])
    one[c] = float(np.clip(-g[c] / max(float(J0[:, c] @ J0[:, c]), 1e-300), -MAX_STEP, MAX_STEP))
    one = _gauss_newton(rec, one, [c], fit(rec, one)[0], fit)[0]
    return fit(rec, one)[1]


def on_time(
    rec: Recording, boundary, L: int, band_hz: float | None = None, effect: dict | None = None
) -> tuple[Recording, Timing | None]:
    """``rec`` realigned when its channels show a converter's skew, and what was found: on the
    diagnosis's first :data:`WINDOWS` windows of ``L`` samples after its lead-in, in its signal
    band ``band_hz`` (the chain judged as the diagnosis judges it); ``effect``: an effect's
    force columns the chain is fitted with (:class:`ChainFit`)."""
    fit = ChainFit(boundary, int(L), lead_in(rec.u.shape[0], float(rec.dt)), band_hz, effect)
    timing = channel_timing(rec, fit)
    if timing is None or not timing.realigned:
        return rec, timing
    return realign(rec, timing.late), timing
