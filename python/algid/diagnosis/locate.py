"""Where the linear model fails: per DOF equation, in time, in frequency, against amplitude.

All indicators use the equation errors of the linear fit in acceleration units (see
:mod:`.core` for the metric; the per-DOF and per-window gaps are in-band like the metric,
the per-DOF ones also full-band). They locate the gap; the decision between candidate effects
is taken by cross-validation in :mod:`.engine`, not here.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import welch

from ..recording.noise import white_floor
from .linear import LinearFit, per_window_fits
from .windows import Prepared

#: Quantile bins of the amplitude scatter (restoring-force / damping-force curves).
N_BINS = 24
#: A first difference of an equation error this many robust sigmas from their median is a
#: jump, not noise (:func:`without_jumps`)...
JUMP_SIGMAS = 5.0
#: ... and so are its neighbours this many samples either side (a jump over a few samples).
JUMP_REACH = 1


def noise_floor(P: Prepared, resid: np.ndarray) -> np.ndarray:
    """Per-DOF RMS of the white part of the equation error (its target units), from its
    white PSD floor (:func:`algid.recording.noise.white_floor`: the upper third of the band, above the
    forcing and the modes in a well-sampled record, or below an anti-alias roll-off) times
    the bandwidth, read on the error :func:`without_jumps`."""
    f, S = welch(without_jumps(resid), fs=1.0 / P.dt, nperseg=min(P.L, 1024), axis=0)
    return np.sqrt(white_floor(f, S) * f[-1])


def without_jumps(resid: np.ndarray) -> np.ndarray:
    """The equation errors (N, n) with their jumps taken out: first differences further than
    :data:`JUMP_SIGMAS` robust sigmas (1.4826 times their median absolute deviation) from their
    median, and their neighbours within :data:`JUMP_REACH` samples, set to that median and
    summed back. A jump (a friction force reversing, an impact) spreads a ``1/f^2`` spectrum
    over the upper band where the white floor is read, far above a quiet sensor's noise; white
    noise has a difference that far out once in about two million samples. A column whose
    differences are all equal (no noise) is left as it is."""
    from scipy.ndimage import binary_dilation

    d = np.diff(resid, axis=0)
    mid = np.median(d, axis=0)
    spread = 1.4826 * np.median(np.abs(d - mid), axis=0)
    jump = (np.abs(d - mid) > JUMP_SIGMAS * spread) & (spread > 0)
    jump = binary_dilation(jump, structure=np.ones((2 * JUMP_REACH + 1, 1), bool))
    d = np.where(jump, mid, d)
    return np.concatenate([resid[:1], resid[:1] + np.cumsum(d, axis=0)])


def binned_r2(z: np.ndarray, r: np.ndarray, bins: int = N_BINS) -> float:
    """Share of the variance of ``r`` explained by a piecewise-constant function of ``z``
    (quantile bins), minus the share a random function with as many bins explains by
    chance (``bins / N``)."""
    edges = np.quantile(z, np.linspace(0, 1, bins + 1))
    idx = np.clip(np.searchsorted(edges, z, side="right") - 1, 0, bins - 1)
    cnt = np.bincount(idx, minlength=bins)
    mean = np.bincount(idx, weights=r, minlength=bins) / np.maximum(cnt, 1)
    tot = float(np.sum((r - r.mean()) ** 2))
    if tot <= 0:
        return 0.0
    expl = float(np.sum(cnt * (mean - r.mean()) ** 2))
    return max(expl / tot - bins / r.size, 0.0)


def locate(P: Prepared, lin: LinearFit, natural_hz: np.ndarray, floor: np.ndarray | None = None) -> dict:
    """Location indicators (JSON-ready) of the linear model's gap."""
    n = P.n
    resid = lin.resid  # (N, n) each equation's target units
    a_rms = np.sqrt(np.mean(P.y**2, axis=0))
    eq_sse = lin.cv.test_sse_eq.sum(axis=0)  # withheld, in-band, acceleration units^2
    eq_full = lin.cv.test_sse_eq_full.sum(axis=0)  # withheld, full band
    floor = noise_floor(P, resid) if floor is None else floor
    per_dof = []
    for i in range(n):
        per_dof.append(
            {
                "dof": i + 1,
                "gap": float(np.sqrt(eq_sse[i] / (P.nw * P.L)) / a_rms[i]),
                "share_of_gap": float(eq_sse[i] / eq_sse.sum()),
                # White noise on the band bins: its band fraction of the full-band floor.
                "noise_floor": float(floor[i] * np.sqrt(P.band_fraction) / a_rms[i]),
                "gap_fullband": float(np.sqrt(eq_full[i] / (P.nw * P.L)) / a_rms[i]),
                "noise_floor_fullband": float(floor[i] / a_rms[i]),
            }
        )
    # Time: withheld gap per window.
    a_w = (P.windows(P.y) ** 2).sum(axis=(1, 2))
    gap_w = np.sqrt(lin.cv.test_sse / a_w)
    t_mid = P.t[0] + P.dt * P.L * (np.arange(P.nw) + 0.5)
    slope = np.polyfit(t_mid - t_mid.mean(), gap_w, 1)[0] if P.nw > 2 else 0.0
    time_info = {
        "window_s": P.L * P.dt,
        "t_mid_s": t_mid.tolist(),
        "gap_per_window": gap_w.tolist(),
        "max_over_min": float(gap_w.max() / max(gap_w.min(), 1e-300)),
        "relative_trend": float(slope * (t_mid[-1] - t_mid[0]) / max(gap_w.mean(), 1e-300)),
    }
    # Frequency: where the residual exceeds its white floor.
    f, S = welch(resid, fs=1.0 / P.dt, nperseg=min(4 * P.L, 4096, P.nw * P.L), axis=0)
    Ssum = S.sum(axis=1)
    excess = np.clip(Ssum - white_floor(f, Ssum), 0.0, None)
    if excess.max() > 0:
        k = int(np.argmax(excess))
        half = np.nonzero(excess >= 0.5 * excess[k])[0]
        c = np.cumsum(excess) / excess.sum()
        band = [float(f[np.searchsorted(c, 0.1)]), float(f[min(np.searchsorted(c, 0.9), f.size - 1)])]
        freq_info = {
            "peak_hz": float(f[k]),
            "half_power_hz": [float(f[half.min()]), float(f[half.max()])],
            "band_80pct_hz": band,
        }
    else:
        freq_info = {"peak_hz": None, "half_power_hz": None, "band_80pct_hz": None}
    freq_info["excess_share"] = float(excess.sum() / max(Ssum.sum(), 1e-300))
    freq_info["natural_frequencies_hz"] = [float(x) for x in natural_hz]
    # Amplitude: restoring-force curves per spring, damping-force curves per mass.
    force_resid = lin.resid_force
    amp_springs = []
    for j in P.network.identifiable_springs():
        d = P.deformation(lin.x, j)
        z = np.concatenate([d for _ in P.sides(j)])
        r = np.concatenate([s * force_resid[:, e] for e, s in P.sides(j)])
        amp_springs.append({"spring": j, "explained": binned_r2(z, r)})
    amp_masses = []
    for i in range(n):
        amp_masses.append({"dof": i + 1, "explained": binned_r2(lin.v[:, i], force_resid[:, i])})
    return {
        "per_dof": per_dof,
        "time": time_info,
        "frequency": freq_info,
        "amplitude": {"springs": amp_springs, "masses": amp_masses},
    }


def window_parameters(P: Prepared, lin: LinearFit) -> dict:
    """Linear parameters fitted on every window alone (least squares) and, when the C++
    estimator is available, the on-line estimator reseeded at every window start (its
    eq. 7 estimate at the window end). Returns JSON-ready lists."""
    fits = per_window_fits(P, lin)
    t_mid = (P.t[0] + P.dt * P.L * (np.arange(P.nw) + 0.5)).tolist()
    out = {
        "t_mid_s": t_mid,
        "least_squares": [{"dof": e + 1, "names": lin.names[e], "values": fits[e].tolist()} for e in range(P.n)],
    }
    if not P.chain:  # the on-line estimator is the chain's
        return out
    try:
        from ..estimator import ChainEstimator
    except ImportError:
        return out
    rows = []
    for w in range(P.nw):
        sl = slice(w * P.L, (w + 1) * P.L)
        est = ChainEstimator(P.n, P.dt, P.boundary)
        res = est.run(P.a[sl], P.u[sl])
        rows.append(
            {
                "mass": res["mass"][-1].tolist(),
                "damping": res["damping"][-1].tolist(),
                "stiffness": res["stiffness"][-1].tolist(),
            }
        )
    out["online"] = rows
    return out
