"""Is the linear chain a model of the record at all? The ``model`` verdict of ``algid diagnose``.

An effect ranking only means something when eq. 1 is the right skeleton: before asking
which unmodelled effect closes the gap, the diagnosis asks three questions of the
recording and of the linear fit, and reports the first that fails with its evidence:

0. ``no_force_response``: the accelerations do not respond to the recorded forces: no
   force or no motion in the band, or, for every forced DOF, the multiple coherence of its
   acceleration with all the forces, averaged over the band weighted by the force power, is below
   :data:`MIN_RESPONSE_COHERENCE` (independent noise in both channels, a force sensor wired
   to another rig). The record carries no identifiable system, whatever the fit says. An impact
   record (:mod:`algid.recording.transient`) is one decay per hit, over which a Welch coherence
   measures nothing: with two hits or more, the coherence across hits (one FFT per hit),
   averaged over the band weighted by the force power, against the same bound; with one hit,
   its band-passed decay standing :data:`MIN_DECAY_DB` above the record's quiet level.
1. ``inertia_not_identifiable``: a forced DOF whose inertia the record does not determine:
   the inertia force ``|m| rms(a)`` is below :data:`INERTIA_SHARE` of the force in the
   signal band (a quasi-static, displacement-driven device), or the mass is not above zero
   by three jackknife sigma.
2. ``more_modes_than_dof``: a drive-point frequency response (force to acceleration,
   Welch H1) with more resonances in the signal band than the chain has DOF: peaks of
   ``|H|`` standing :data:`PEAK_PROMINENCE` times above their surroundings, with coherence
   above :data:`PEAK_COHERENCE` (a structure measured at fewer points than it has modes).
3. ``not_a_chain``: the linear fit is not physical: a mass, a damping or a spring below
   zero by more than three jackknife sigma (a mass that is not positive within that is
   question 1's), unless its force is under :data:`NEGLIGIBLE` of the force, or unless the
   record does not need it: refitted with its negative dampings and springs at zero (their
   bound), the chain explains the record to its noise (withheld in-band gap within the gap
   noise explains, the bound ``none`` itself uses). The jackknife sigma measures the spread
   of an estimate, not its bias: noise in the regressors biases a fit (the encoder's counts
   of a closed-loop axis enter its force through the controller, and its fit trades mass
   for a negative spring), and a parameter the noise can trade is no evidence of a
   structure the chain lacks.

Otherwise ``chain``. ``admissible`` (question 3 alone) is reported too; the diagnosis
never says ``none`` (nothing to explain) unless the fit is admissible and the record has
no more modes than the chain.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .equations import linear_design, target, to_physical
from .gram import EqSpec, cross_validate, jackknife_std, window_stats
from .linear import LinearFit
from .windows import Prepared

MODEL_VERDICTS = ("chain", "no_force_response", "inertia_not_identifiable", "more_modes_than_dof", "not_a_chain")
#: Band-mean multiple coherence (acceleration with every force) below which a DOF does not
#: respond to the forces. Independent noise gives about q / K (q forces, K Welch averages,
#: kept below a tenth by the segment length); a chain at 0 dB SNR gives about 0.5.
MIN_RESPONSE_COHERENCE = 0.25
#: A single hit's band-passed decay stands this far above the quiet level [dB] when the
#: structure responds to it.
MIN_DECAY_DB = 20.0
#: Inertia force over force, in the band, below which a DOF's mass is not determined.
INERTIA_SHARE = 0.02
#: A resonance peak stands this many times above the lower of its two flanking minima.
PEAK_PROMINENCE = 2.0
#: A negative damping or spring whose force is below this share of the force in the band
#: does not make the fit inadmissible (the windowed fit of a closed-loop axis without a
#: spring puts a few percent of its force into a small negative spring).
NEGLIGIBLE = 0.05
#: Coherence of force and acceleration at a resonance peak that is counted.
PEAK_COHERENCE = 0.8
#: Share of the force's band edge searched for peaks (at the edge the force's PSD falls
#: steeply and H1 turns to noise).
FORCE_EDGE = 0.9
#: A peak this many times above its flanks counts down to this coherence.
PEAK_STRONG = 10.0
PEAK_COHERENCE_STRONG = 0.15


@dataclass
class ModelVerdict:
    """``verdict`` (one of :data:`MODEL_VERDICTS`), one line per finding in ``reasons``,
    and the ``evidence`` behind each question."""

    verdict: str
    reasons: list = field(default_factory=list)
    admissible: bool = True
    evidence: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        return {
            "verdict": self.verdict,
            "admissible": self.admissible,
            "reasons": self.reasons,
            "evidence": self.evidence,
        }


def physical_uncertainty(P: Prepared, lin: LinearFit) -> list[np.ndarray]:
    """Jackknife standard deviation of every equation's physical ``[m, c, k_j ...]`` over
    the cross-validation folds."""
    out = []
    for e, sl in enumerate(lin.cv.stats.slices):
        folds = np.array([to_physical(P, e, th[sl]) for th in lin.cv.theta_folds])
        out.append(jackknife_std(folds))
    return out


def band_rms(x: np.ndarray, dt: float, f_hi: float) -> np.ndarray:
    """RMS of the columns of ``x`` in ``(0, f_hi]`` (FFT, the mean removed)."""
    X = np.fft.rfft(x - x.mean(axis=0), axis=0)
    f = np.fft.rfftfreq(x.shape[0], dt)
    X[f > f_hi] = 0.0
    return np.sqrt(np.mean(np.fft.irfft(X, x.shape[0], axis=0) ** 2, axis=0))


def inertia(P: Prepared, lin: LinearFit, sd: list[np.ndarray], f_hi: float) -> dict:
    """Inertia share and mass significance of every forced DOF (question 1)."""
    a_rms = band_rms(P.a, P.dt, f_hi)
    u_rms = band_rms(P.u, P.dt, f_hi)
    out = {}
    for e in np.nonzero(P.forced)[0]:
        m, s = float(lin.theta[e][0]), float(sd[e][0])
        share = abs(m) * a_rms[e] / u_rms[e] if u_rms[e] > 0 else float("inf")
        out[int(e) + 1] = {
            "mass": m,
            "mass_sigma": s,
            "inertia_share": float(share),
            "determined": bool(share >= INERTIA_SHARE and m > 3 * s),
        }
    return out


def cross_spectra(X: np.ndarray, dt: float, nper: int, chunk: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Welch cross-spectral matrices of the columns of ``X`` (T, c): frequencies [Hz] and
    ``S[f, i, j] = E[conj(X_i) X_j]`` (one-sided density, Hann windows of ``nper`` samples
    overlapping by half, each segment's mean removed: :func:`scipy.signal.csd` of every
    pair). Every channel's segment spectra are taken once and multiplied pairwise,
    ``chunk`` segments at a time: memory of a chunk, time of ``c`` transforms and ``c^2``
    products per segment (``csd`` of all pairs transforms every channel ``2 c`` times)."""
    from scipy.signal import get_window

    T, c = X.shape
    win = get_window("hann", nper)
    starts = np.arange(0, T - nper + 1, nper - nper // 2)
    S = np.zeros((nper // 2 + 1, c, c), dtype=complex)
    for lo in range(0, starts.size, chunk):
        seg = X[starts[lo : lo + chunk, None] + np.arange(nper)]  # (s, nper, c)
        F = np.fft.rfft((seg - seg.mean(axis=1, keepdims=True)) * win[None, :, None], axis=1)
        S += np.einsum("sfi,sfj->fij", F.conj(), F)
    S *= 1.0 / (np.sum(win**2) / dt * starts.size)
    S[1 : -1 if nper % 2 == 0 else None] *= 2.0
    return np.fft.rfftfreq(nper, dt), S


def force_response(P: Prepared, f_hi: float) -> dict:
    """Question 0: the band-mean multiple coherence of every forced DOF's acceleration with
    all the forces (the share of its power the forces explain linearly, per bin), over the
    samples the windows analyse."""
    forced = np.nonzero(P.forced)[0]
    u, a = P.u[:, forced], P.a  # the analysed samples: not a filter's start-up before them
    if forced.size == 0 or not np.any(band_rms(u, P.dt, f_hi) > 0) or not np.any(band_rms(a, P.dt, f_hi) > 0):
        return {"related": False, "coherence": {}, "reason": "no force or no motion in the signal band"}
    q, T = forced.size, u.shape[0]
    nper = int(2 ** np.floor(np.log2(max(T // (20 * q), 32))))  # K >= about 40 q averages
    X = np.column_stack([u, a])
    f, S = cross_spectra(X, P.dt, nper)
    band = (f > 0) & (f <= f_hi)
    Sb = S[band]
    Suu, Sua, Saa = Sb[:, :q, :q], Sb[:, :q, q:], np.einsum("fii->fi", Sb[:, q:, q:]).real
    # per bin and DOF: Sua^H Suu^+ Sua / Saa, the share of the acceleration's power the forces explain
    with np.errstate(divide="ignore", invalid="ignore"):
        coh = np.einsum("fie,fij,fje->fe", Sua.conj(), np.linalg.pinv(Suu), Sua).real / Saa
    # weighted by the force power: where the forces act (a quasi-static device moves slowly,
    # and its acceleration, differentiated from an encoder, is noise above that)
    weight = np.einsum("fii->f", Suu).real
    out = {}
    for e in forced:
        ok = np.isfinite(coh[:, e]) & (weight > 0)
        share = np.sum(np.clip(coh[ok, e], 0.0, 1.0) * weight[ok]) / np.sum(weight[ok]) if ok.any() else 0.0
        out[int(e) + 1] = float(share)
    related = any(c >= MIN_RESPONSE_COHERENCE for c in out.values())
    listed = ", ".join(f"DOF {d}: {c:.2f}" for d, c in out.items())
    reason = (
        ""
        if related
        else f"the forces explain almost none of the accelerations in the band (multiple coherence {listed})"
    )
    return {"related": related, "coherence": out, "reason": reason}


def transient_response(u: np.ndarray, y: np.ndarray, tr) -> dict:
    """Question 0 for an impact record ``tr`` with its cleaned, band-passed force ``u`` (T,) and
    response ``y`` (T,): the coherence across hits, or a single hit's decay over the quiet
    level (module docstring)."""
    from ..recording.transient import across_hits

    if len(tr.hits) >= 2:
        x = across_hits(u, y, tr)
        band = (x["f_hz"] >= tr.band_hz[0]) & (x["f_hz"] <= tr.band_hz[1]) & np.isfinite(x["coherence"])
        w = x["force_power"][band]
        share = float(np.sum(np.clip(x["coherence"][band], 0, 1) * w) / np.sum(w)) if np.sum(w) > 0 else 0.0
        related = share >= MIN_RESPONSE_COHERENCE
        what = f"coherence across {x['hits']} hits {share:.2f}"
        out = {"related": related, "coherence": {1: share}, "hits": x["hits"]}
    else:
        db = tr.to_json()["decay_over_quiet_db"]
        related = db is not None and db >= MIN_DECAY_DB
        what = "decay over quiet level " + (f"{db:.1f} dB" if db is not None else "not measurable")
        out = {"related": related, "decay_over_quiet_db": db, "hits": 1}
    return {**out, "reason": "" if related else f"the response does not rise with the hits ({what})", "what": what}


def resonances(P: Prepared, f_hi: float) -> dict:
    """Resonance peaks of every forced DOF's drive-point H1 (question 2), in the signal band,
    below :data:`FORCE_EDGE` of the force's own band edge (:func:`algid.recording.noise.channel`) and
    where it carries power (PSD above :data:`algid.recording.noise.DETECT` times its white floor and
    within ``DETECT^2`` of its peak: a band-passed record has no floor to speak of);
    segments of an eighth of the record (fine resolution, 8 averages). A peak
    counts with coherence of at least :data:`PEAK_COHERENCE`, or, standing
    :data:`PEAK_STRONG` times above its flanks, of at least :data:`PEAK_COHERENCE_STRONG`
    (a struck, lightly damped structure rings on into segments the hammer did not touch,
    which lowers the coherence of its sharpest resonances)."""
    from scipy.ndimage import maximum_filter1d
    from scipy.signal import csd, find_peaks, welch

    from ..recording.noise import DETECT, channel, white_floor

    fs = 1.0 / P.dt
    T = P.u_full.shape[0]
    nper = int(2 ** np.floor(np.log2(max(T // 8, 64))))
    out = {}
    for e in np.nonzero(P.forced)[0]:
        u, a = P.u_full[:, e], P.a_full[:, e]
        f, Puu = welch(u, fs=fs, nperseg=nper)
        _, Paa = welch(a, fs=fs, nperseg=nper)
        _, Pua = csd(u, a, fs=fs, nperseg=nper)
        with np.errstate(divide="ignore", invalid="ignore"):
            H = np.abs(Pua) / Puu
            coh = np.abs(Pua) ** 2 / (Puu * Paa)
        f_top = min(f_hi, FORCE_EDGE * channel("u", u, P.dt).f_hi)
        # where the force has power: above its floor, within DETECT^2 of its peak, and not
        # in a valley between the lines of a sparse multisine (within DETECT of the largest
        # force PSD within 3 bins: H1 there is leakage, not a response)
        local = maximum_filter1d(Puu, size=7, mode="nearest")
        powered = (Puu > DETECT * white_floor(f, Puu)) & (Puu > Puu.max() / DETECT**2) & (Puu > local / DETECT)
        keep = (f > 2 * f[1]) & (f <= f_top) & powered & np.isfinite(H) & (H > 0)
        at = np.nonzero(keep)[0]  # the kept bins as one sequence: a line spectrum's lines are neighbours
        idx, props = find_peaks(np.log(H[at]), prominence=np.log(PEAK_PROMINENCE)) if at.size > 2 else ([], {})
        peaks = [
            float(f[at[i]])
            for i, pr in zip(idx, props.get("prominences", []))
            if (coh[at[i]] >= PEAK_COHERENCE or (pr >= np.log(PEAK_STRONG) and coh[at[i]] >= PEAK_COHERENCE_STRONG))
        ]
        out[int(e) + 1] = {"peaks_hz": peaks, "count": len(peaks)}
    return out


def admissibility(
    P: Prepared,
    lin: LinearFit,
    sd: list[np.ndarray],
    f_hi: float,
    states: tuple[np.ndarray, np.ndarray],
    noise_gap: float | None = None,
    denom: float | None = None,
) -> tuple[list[str], dict]:
    """Physically impossible parameters of the linear fit (question 3), one line each: below
    zero by three sigma and standing for at least :data:`NEGLIGIBLE` of the force in the
    band (a spring of -0.4 N/m on an axis that moves 50 mm under tens of newtons is no
    evidence against the chain); ``states = (x, v)`` on the analysed samples. With
    ``noise_gap`` (the largest relative withheld gap the noise explains) and ``denom`` (the
    targets' squared sum, the gap's scale), negative dampings and springs the record does not
    need are dropped too (:func:`bound_gap`), and the second value says what was tried."""
    u_rms = band_rms(P.u, P.dt, f_hi)
    x, v = states
    v_rms, a_rms = band_rms(v, P.dt, f_hi), band_rms(P.a, P.dt, f_hi)
    bad: list[tuple[int, int | None, str]] = []  # (equation, column at its bound or None, line)
    for e in range(P.n):
        th, s = lin.theta[e], sd[e]
        force = u_rms[e] if P.forced[e] else np.nan
        if P.forced[e] and th[0] < -3 * s[0] and not abs(th[0]) * a_rms[e] < NEGLIGIBLE * force:
            bad.append((e, None, f"DOF {e + 1}: mass {th[0]:.4g} +- {s[0]:.2g} is negative"))
        for q, (name, val, sg) in enumerate(zip(lin.names[e][1:], th[1:], s[1:])):
            if not val < -3 * sg:
                continue
            if name == "c":
                reg = v_rms[e]
            else:
                j, other = P.columns[e][q - 1]
                d = x[:, e] - (x[:, other] if other >= 0 else 0.0)
                reg = band_rms(d[:, None], P.dt, f_hi)[0]
            if np.isfinite(force) and abs(val) * reg < NEGLIGIBLE * force:
                continue
            what = "damping" if name == "c" else f"spring {name[1:]}"
            col = q + 1 if P.forced[e] else q  # the unforced equation has no mass column
            bad.append((e, col, f"DOF {e + 1}: {what} {val:.4g} +- {sg:.2g} is negative"))
    bound: dict = {}
    at_bound = {}
    for e, col, _ in bad:
        if col is not None:
            at_bound.setdefault(e, []).append(col)
    if at_bound and noise_gap is not None and denom:
        gap = bound_gap(P, lin, at_bound, denom)
        bound = {"gap_at_bound": gap, "noise_gap": float(noise_gap), "needed": bool(gap > noise_gap)}
        if not bound["needed"]:
            bad = [b for b in bad if b[1] is None]
    return [line for _, _, line in bad], bound


def bound_gap(P: Prepared, lin: LinearFit, at_bound: dict[int, list[int]], denom: float) -> float:
    """Relative withheld in-band gap of the linear chain with the columns ``at_bound[e]`` of
    equation ``e`` (negative dampings and springs) held at zero, the other equations as
    fitted: cross-validated as the linear fit is."""
    sse_eq = lin.cv.test_sse_eq.sum(axis=0).copy()
    for e, cols in at_bound.items():
        X = linear_design(P, e)
        keep = [i for i in range(X.shape[1]) if i not in cols]
        if not keep:
            continue
        spec = EqSpec(e=e, X=np.ascontiguousarray(X[:, keep]), y=target(P, e), E=None)
        sse_eq[e] = float(cross_validate(P, window_stats(P, [spec])).test_sse.sum())
    return float(np.sqrt(sse_eq.sum() / denom))


def model_verdict(
    P: Prepared,
    lin: LinearFit,
    f_hi: float,
    states: tuple | None = None,
    noise_gap: float | None = None,
    denom: float | None = None,
    response: dict | None = None,
) -> ModelVerdict:
    """The three questions of the module docstring, in order; ``states = (x, v)`` measured
    or reconstructed on the analysed samples (default: the linear fit's reconstruction);
    ``noise_gap`` and ``denom`` as :func:`admissibility` takes them (without them every
    significant negative damping or spring counts); ``response`` question 0's answer when the
    caller has it (an impact record's, :func:`transient_response`)."""
    response = force_response(P, f_hi) if response is None else response
    if not response["related"]:
        evidence = {"force_response": response}
        reason = f"no force response: {response['reason']}; the record carries no identifiable system"
        return ModelVerdict(verdict="no_force_response", reasons=[reason], admissible=False, evidence=evidence)
    sd = physical_uncertainty(P, lin)
    ine = inertia(P, lin, sd, f_hi)
    res = resonances(P, f_hi)
    bad, bound = admissibility(
        P, lin, sd, f_hi, states if states is not None else (lin.x, lin.v), noise_gap=noise_gap, denom=denom
    )
    reasons = []
    for dof, d in ine.items():
        if not d["determined"]:
            reasons.append(
                f"DOF {dof}: inertia not identifiable (inertia force {100 * d['inertia_share']:.2g} % of "
                f"the force in the band, mass {d['mass']:.4g} +- {d['mass_sigma']:.2g})"
            )
    many = {dof: r for dof, r in res.items() if r["count"] > P.n}
    for dof, r in many.items():
        reasons.append(
            f"DOF {dof}: {r['count']} resonances in the band ("
            + ", ".join(f"{f:.3g}" for f in r["peaks_hz"])
            + f" Hz) for a chain of {P.n} DOF"
        )
    reasons += bad
    if any(not d["determined"] for d in ine.values()):
        verdict = "inertia_not_identifiable"
    elif many:
        verdict = "more_modes_than_dof"
    elif bad:
        verdict = "not_a_chain"
    else:
        verdict = "chain"
    evidence = {
        "force_response": response,
        "inertia": ine,
        "resonances": res,
        "inadmissible": bad,
        "at_bound": bound,
        "parameters_sigma": [s.tolist() for s in sd],
    }
    return ModelVerdict(verdict=verdict, reasons=reasons, admissible=not bad, evidence=evidence)
