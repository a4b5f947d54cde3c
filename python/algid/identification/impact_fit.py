"""The fit check of an impact record: does the chain identify estimated explain the hits?

An equation-error fit of windows (the diagnosis's withheld-window test) does not fit a decay, so
on an impact record the check is an *output error*: the estimated chain, driven from rest by
the measured force (cleaned of its baseline drift, :func:`algid.recording.transient.clean_force`),
predicts the motion; the prediction and the measured motion are band-passed alike
(:func:`algid.recording.transient.band_pass`) and compared over every hit's decay (from the
hit's end to the next hit's pre-trigger, the filter's unsettled end left out). The band-pass
commutes with the chain, so filtering the prediction is filtering the force; filtering it
*after* the simulation keeps the start from rest exact when the pre-trigger is shorter than the
zero-phase filter's reach (the whole record starts at rest, its band-passed force does not).

The yardstick is the noise: the RMS of the motion in the band over the record's quietest quiet
part (:func:`quietest`, per channel; a later hit's pre-trigger may still ring). Rule: the chain
explains the hits when the RMS of its prediction error over their decays is at most
:data:`OUTPUT_ERROR_RATIO` times that noise (each hit's own ratio is reported too). A right
chain with the right parameters leaves the noise alone (ratio 1); an estimate within a few of its
standard deviations adds a prediction error of the order of the noise (a frequency error drifts
the phase over the hundreds of periods of a light decay, which is why the factor is not 1); a
chain that misses a mode in the band or a nonlinearity leaves an error that is a share of the
response, tens of times the noise on a decay standing 40 dB above it. The modes outside the band
are filtered out of both sides and reported apart (residual modes).
"""

from __future__ import annotations

import math

import numpy as np

from ..model.chain import Chain
from ..recording import motion
from ..recording.transient import band_pass, clean_force, quiet_parts

#: The chain explains the hits when its output error over their decays is at most this many times
#: the RMS noise of the quiet part in the band (module docstring).
OUTPUT_ERROR_RATIO = 5.0


def chain_of(theta: np.ndarray, n: int, boundary: str) -> Chain | None:
    """The chain of the packed estimate ``theta``, None when it has none (a mass, damping or
    stiffness missing or below zero: the verdicts say why)."""
    if not np.all(np.isfinite(theta[: 2 * n])):
        return None
    try:
        return Chain.from_packed(np.nan_to_num(theta), n, boundary)
    except ValueError:
        return None


def predicted_motion(chain: Chain, kind: str, u: np.ndarray, dt: float) -> np.ndarray:
    """Motion ``kind`` (T, n) of ``chain`` driven from rest by the forces ``u`` (T, n) [N]
    sampled every ``dt`` [s] (first-order hold between the samples)."""
    from scipy.signal import lsim

    _, y, _ = lsim(chain.state_space(kind), u, np.arange(u.shape[0]) * dt)
    return np.asarray(y, float).reshape(u.shape[0], -1)


def quietest(y: np.ndarray, tr) -> float:
    """RMS of the motion ``y`` (T,) in the band over the quietest of the record's quiet parts
    (:func:`algid.recording.transient.quiet_parts`): a later hit's pre-trigger may still ring
    with the decay of the one before."""
    return min((float(np.sqrt(np.mean(q**2))) for q in quiet_parts(y, tr) if q.size), default=math.nan)


def _decays(tr) -> list[np.ndarray]:
    """Per hit, the samples of its decay: from the hit's end to its segment's end, the
    band-pass's unsettled end left out."""
    settled = np.flatnonzero(~tr.missing)
    end = int(settled[-1]) + 1 if settled.size else 0
    return [np.arange(h.stop, min(stop, end)) for h, (_, stop) in zip(tr.hits, tr.segments)]


def impact_fit(sig, theta: np.ndarray, boundary: str) -> dict:
    """The fit check (module docstring) of the chain ``theta`` on the impact record of ``sig``
    (:class:`.screen.Signals` with its ``transient``): the ``model_fit`` fields ``check``,
    ``output_error`` and ``noise`` (RMS over the decays and over the quiet part, the motion's
    unit), ``ratio``, ``hit_ratios``, ``ratio_limit``, ``explains_record``, and ``misfit``: why
    the estimates are ``model_misfit`` ("" when the chain explains the hits)."""
    tr, raw = sig.transient, sig.raw
    y = motion(raw)[1]
    chain = chain_of(theta, raw.n, boundary)
    if chain is None:
        return {"check": "output error", "explains_record": False, "misfit": ""}  # the verdicts say why
    u = clean_force(raw.u, list(tr.hits), tr.dt)
    error = band_pass(predicted_motion(chain, sig.kind, u, tr.dt) - y, tr.dt, tr.band_hz)
    noise = float(np.sqrt(np.mean([quietest(y[:, c], tr) ** 2 for c in range(y.shape[1])])))
    hits = [float(np.sqrt(np.mean(error[d] ** 2))) if d.size else math.nan for d in _decays(tr)]
    every = np.concatenate(_decays(tr))
    rms = float(np.sqrt(np.mean(error[every] ** 2))) if every.size else math.nan
    ratios = [e / noise for e in hits]
    explains = bool(rms / noise <= OUTPUT_ERROR_RATIO)  # False when NaN: no decay to judge
    out = {
        "check": "output error",
        "output_error": rms,
        "noise": noise,
        "ratio": rms / noise,
        "hit_ratios": ratios,
        "ratio_limit": OUTPUT_ERROR_RATIO,
        "explains_record": explains,
    }
    over = f"the decays of {len(hits)} hits" if len(hits) > 1 else "the hit's decay"
    why = (
        f"driven by the measured force, the chain's prediction leaves an output error of {rms:.3g} over {over}, "
        f"{rms / noise:.3g}x the noise of the quiet part in the band ({noise:.3g}; at most "
        f"{OUTPUT_ERROR_RATIO:g}x explains the hits)"
    )
    return {**out, "misfit": "" if explains else why}


def fit_line(fit: dict) -> str:
    """The summary's line of :func:`impact_fit`'s ``model_fit``."""
    if "ratio" not in fit:
        return "fit check (output error): no admissible chain to simulate"
    hits = ", ".join(f"{r:.3g}" for r in fit["hit_ratios"])
    say = "explains the hits" if fit["explains_record"] else "does not explain the hits"
    return (
        f"fit check (output error over the decays): {fit['output_error']:.3g}, {fit['ratio']:.3g}x the quiet "
        f"part's noise {fit['noise']:.3g} (per hit: {hits}; limit {fit['ratio_limit']:g}x): the chain {say}"
    )
