"""Figures of ``algid diagnose`` (matplotlib figures without pyplot; PNG files).

Each figure answers one question a vibration engineer asks of the gap between the
recording and the linear chain:

* ``residuals_time.png`` — when: the equation error of every DOF over time, before and
  after the reported effect, with its withheld RMS per window;
* ``residuals_spectrum.png`` — at which frequencies: spectra of the measured acceleration
  and of the equation errors against the sensor noise's spectrum in the same units and
  scaling (:func:`noise_spectrum`), natural frequencies marked, the signal band on which the
  gap is scored shaded;
* ``restoring_force.png`` — against deformation: for every spring, the force the linear
  spring carries plus the unexplained force of the adjacent equations, against the
  spring's deformation (a straight line when the spring is linear);
* ``damping_force.png`` — against velocity: for every mass, damper force plus unexplained
  force against its velocity (a straight line when damping is viscous);
* ``window_parameters.png`` — drift: the linear parameters fitted on every window alone
  (least squares, and the on-line estimator reseeded per window when available), relative
  to the whole-record fit;
* ``ranking.png`` — which: withheld gap of every candidate against the linear model and
  the noise floor;
* ``prediction.png`` — how well: the measured acceleration (or force, in the force form) of
  every DOF against what the linear chain and the chain with the reported effect predict
  from the same record, on the stretch where the linear model fails most.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.ticker import FormatStrFormatter, LogLocator, MaxNLocator, NullFormatter
from scipy.signal import welch

from ..diagnosis.equations import force_form
from ..diagnosis.locate import window_parameters
from ..diagnosis.windows import detrend
from . import subplots

DPI = 90
C_BEFORE = "#c0392b"
C_AFTER = "#2471a3"
C_MEAS = "#999999"
#: Units of the parameters of a DOF without force (its equation is per unit mass).
PER_UNIT_MASS = {"m": "-", "c": "1/s", "k": "1/s^2"}


def _subsample(*columns: np.ndarray, max_points: int = 6000, seed: int = 0) -> np.ndarray:
    """Indices of at most ``max_points`` random samples and the extremes of every column
    (so the axes drawn cover the data)."""
    N = columns[0].size
    if N <= max_points:
        return np.arange(N)
    extremes = [g(c) for c in columns for g in (np.argmin, np.argmax)]
    return np.unique(np.concatenate([np.random.default_rng(seed).choice(N, max_points, replace=False), extremes]))


def _label(d) -> str:
    if d.best is None:
        return d.effect
    ((k, v),) = d.location.items()
    return f"with {d.effect} ({'DOF' if k == 'dof' else 'spring'} {v})"


def _target_unit(d, e: int) -> str:
    """Unit of equation ``e``'s error: the force in the force form, else the acceleration."""
    return d.units["force"] if force_form(d.P, e) else d.units["acceleration"]


def _time_panels(d, draw, xlabel: str, title: str):
    """One panel per DOF equation over time, ``draw(ax, i)`` filling panel ``i``, in the
    equation's target unit, the legend on the first panel."""
    n = d.P.n
    fig, axes = subplots(n, 1, figsize=(9, 1.9 * n + 0.9), sharex=True, squeeze=False)
    for i, ax in enumerate(axes[:, 0]):
        draw(ax, i)
        ax.set_ylabel(f"DOF {i + 1}\n[{_target_unit(d, i)}]")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(loc="upper right", fontsize=7, ncol=3)
    axes[-1, 0].set_xlabel(xlabel)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def fig_residuals_time(d):
    P = d.P
    before, after = d.residuals()
    tw = P.t[0] + P.dt * P.L * (np.arange(P.nw) + 0.5)

    def draw(ax, i):
        ax.plot(P.t, before[:, i], color=C_BEFORE, lw=0.4, alpha=0.8, label="linear model")
        if d.best is not None:
            ax.plot(P.t, after[:, i], color=C_AFTER, lw=0.4, alpha=0.8, label=_label(d))
        rms_w = np.sqrt((P.windows(before[:, i]) ** 2).mean(axis=1))
        ax.step(tw, rms_w, where="mid", color="k", lw=1.0, label="RMS per window (linear)")

    return _time_panels(
        d,
        draw,
        "time [s]",
        f"Acceleration equation error over time (in-band gap {d.gap_before:.3g} -> {d.gap_after:.3g}; "
        f"full band {d.gap_before_full:.3g} -> {d.gap_after_full:.3g})",
    )


def fig_residuals_spectrum(d):
    P = d.P
    before, after = d.residuals()
    fs = 1.0 / P.dt
    nper = spectrum_segment(d)
    f, Sa = welch(P.y, fs=fs, nperseg=nper, axis=0)
    _, Sb = welch(before, fs=fs, nperseg=nper, axis=0)
    _, Sf = welch(after, fs=fs, nperseg=nper, axis=0)
    noise = noise_spectrum(d, nper)
    n = P.n
    fig, axes = subplots(n, 1, figsize=(9, 1.9 * n + 0.9), sharex=True, squeeze=False)
    for i, ax in enumerate(axes[:, 0]):
        ax.loglog(
            f[1:],
            Sa[1:, i],
            color=C_MEAS,
            lw=0.8,
            label="measured force" if P.form == "force" and P.forced[i] else "measured acceleration",
        )
        ax.loglog(f[1:], Sb[1:, i], color=C_BEFORE, lw=0.8, label="error, linear model")
        if d.best is not None:
            ax.loglog(f[1:], Sf[1:, i], color=C_AFTER, lw=0.8, label="error, " + _label(d))
        ax.loglog(f[1:], noise[1:, i], color="k", ls="--", lw=0.8, label="sensor noise (noise model)")
        ax.axvspan(
            f[1],
            d.band.f_hi,
            color="#f4d03f",
            alpha=0.18,
            lw=0,
            label=f"signal band 0-{d.band.f_hi:.3g} Hz (gap scored here)" if i == 0 else None,
        )
        for fn in d.extra.get("natural_hz", []):
            ax.axvline(fn, color="k", ls=":", lw=0.6)
        ax.set_ylabel(f"DOF {i + 1}\n[({_target_unit(d, i)})^2/Hz]")
        ax.grid(alpha=0.3, which="both")
    axes[0, 0].legend(loc="lower left", fontsize=7, ncol=2)
    axes[-1, 0].set_xlabel("frequency [Hz]  (dotted: natural frequencies of the fitted chain)")
    fig.suptitle(f"Spectrum of the equation error (in-band gap {d.gap_before:.3g} -> {d.gap_after:.3g})", fontsize=10)
    fig.tight_layout()
    return fig


def spectrum_segment(d) -> int:
    """Welch segment [samples] of the residual spectra: four windows (at most 4096 samples),
    or longer for bins narrower than the fitted chain's modes (:func:`algid.model.frf.resolution_hz`),
    at most a quarter of the record."""
    from ..diagnosis.engine import fitted_chain
    from ..model.frf import resolution_hz, segment_samples

    N = d.P.y.shape[0]
    chain = fitted_chain(d.lin, d.P.boundary)
    wanted = segment_samples(N, d.P.dt, resolution_hz(chain)) if chain is not None else 0
    return int(min(max(min(4 * d.P.L, 4096), wanted), N // 4))


def noise_spectrum(d, nperseg: int) -> np.ndarray:
    """(F, n) one-sided PSD of the sensor noise in every equation error [target unit^2/Hz],
    Welch with ``nperseg`` like the residual spectra: for derived accelerations the noise
    model's white motion noise carried through the analysis
    (:func:`algid.diagnosis.engine.equation_noise`) plus the force sensor's floor; for
    measured accelerations the white floor the diagnosis reads off the equation errors."""
    from ..diagnosis.engine import equation_noise

    P, levels = d.P, d.extra.get("noise_levels")
    fs = 1.0 / P.dt
    F = nperseg // 2 + 1
    if levels is None or levels.motion_sigma is None:
        floor = np.array([row["noise_floor_fullband"] for row in d.where["per_dof"]]) * np.sqrt(np.mean(P.y**2, axis=0))
        return np.broadcast_to(floor**2 / (fs / 2), (F, P.n)).copy()
    E = equation_noise(P, d.lin, levels.motion_sigma, levels.order, np.random.default_rng(0))
    _, S = welch(E, fs=fs, nperseg=nperseg, axis=0)
    for e in np.nonzero(P.forced)[0]:
        theta_u = 1.0 if force_form(P, e) else float(d.lin.theta_a[e][0])
        S[:, e] += theta_u**2 * levels.force_psd[e]
    return S


def _binned(z, r, bins=30):
    edges = np.quantile(z, np.linspace(0, 1, bins + 1))
    idx = np.clip(np.searchsorted(edges, z, side="right") - 1, 0, bins - 1)
    cnt = np.maximum(np.bincount(idx, minlength=bins), 1)
    return np.bincount(idx, weights=z, minlength=bins) / cnt, np.bincount(idx, weights=r, minlength=bins) / cnt


def _force_panels(title: str, items: list, xlabel: str, xscale: float, ylabel: str, force_unit: str):
    """Two rows per item: the total force against the amplitude variable with the linear
    law, and below it the unexplained force alone (scatter and binned mean), which is
    where a nonlinearity shows. ``items``: (label, z, linear_force, unexplained, coef_txt)."""
    cols = len(items)
    fig, axes = subplots(2, cols, figsize=(max(3.6 * cols, 6.0), 5.4), squeeze=False, sharex="col")
    for c, (label, z, lin_f, r, coef_txt) in enumerate(items):
        idx = _subsample(z, lin_f + r, r)
        top, bot = axes[0, c], axes[1, c]
        top.plot(z[idx] * xscale, (lin_f + r)[idx], ".", ms=1.2, color=C_MEAS, alpha=0.5)
        zz = np.array([z.min(), z.max()])
        k = np.polyfit(z, lin_f, 1)[0]
        top.plot(zz * xscale, k * zz, "k--", lw=0.8, label=coef_txt)
        top.set_title(label, fontsize=9)
        top.legend(fontsize=7, loc="upper left")
        bot.plot(z[idx] * xscale, r[idx], ".", ms=1.2, color=C_MEAS, alpha=0.5)
        zb, rb = _binned(z, r)
        bot.plot(zb * xscale, rb, "-", color=C_BEFORE, lw=1.6, label="binned mean")
        bot.axhline(0.0, color="k", lw=0.6)
        bot.legend(fontsize=7, loc="upper left")
        bot.set_xlabel(xlabel)
        for ax in (top, bot):
            ax.grid(alpha=0.3)
            ax.xaxis.set_major_locator(MaxNLocator(nbins=5 if cols < 3 else 4))
    axes[0, 0].set_ylabel(f"{ylabel} [{force_unit}]")
    axes[1, 0].set_ylabel(f"unexplained force [{force_unit}]")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def _states(d) -> tuple[np.ndarray, np.ndarray]:
    """Displacements and velocities (N, n) the candidates were fitted against: measured
    when the record has positions, else reconstructed by the linear fit."""
    ctx = d.extra.get("ctx")
    return (ctx.x, ctx.v) if ctx is not None else (d.lin.x, d.lin.v)


def fig_restoring_force(d):
    P, lin = d.P, d.lin
    x, _ = _states(d)
    force_resid = lin.resid_force
    expl = {s["spring"]: s["explained"] for s in d.where["amplitude"]["springs"]}
    kfit = lin.stiffness()
    items = []
    for j in P.network.identifiable_springs():
        dj = P.deformation(x, j)
        k = kfit[0] if P.n == 1 else kfit[j - 1]
        # Unexplained force attributed to the spring: + in eq. j, - in eq. j-1 (mean of sides).
        r = np.mean([-s * force_resid[:, e] for e, s in P.sides(j)], axis=0)
        name = f"spring {j}" + (" (k1+k2)" if P.n == 1 else "")
        items.append(
            (f"{name}: binned law explains {expl.get(j, 0):.0%}", dj, k * dj, r, f"linear k = {k:.4g} {d.units['k']}")
        )
    unit, scale = ("mm", 1e3) if d.units["displacement"] == "m" else (d.units["displacement"], 1.0)
    return _force_panels(
        "Restoring force per spring against its deformation",
        items,
        f"deformation [{unit}]",
        scale,
        "restoring force",
        d.units["force"],
    )


def fig_damping_force(d):
    P, lin = d.P, d.lin
    force_resid = lin.resid_force
    expl = {s["dof"]: s["explained"] for s in d.where["amplitude"]["masses"]}
    c = lin.damping()
    _, velocity = _states(d)
    items = []
    for i in range(P.n):
        v = velocity[:, i]
        items.append(
            (
                f"DOF {i + 1}: binned law explains {expl.get(i + 1, 0):.0%}",
                v,
                c[i] * v,
                -force_resid[:, i],
                f"linear c = {c[i]:.3g} {d.units['c']}",
            )
        )
    velocity = f"velocity [{d.units['velocity']}]"
    return _force_panels(
        "Damping force per mass against its velocity", items, velocity, 1.0, "damping force", d.units["force"]
    )


def fig_window_parameters(d):
    P, lin = d.P, d.lin
    wp = window_parameters(P, lin)
    t = np.array(wp["t_mid_s"])
    n = P.n
    fig, axes = subplots(n, 1, figsize=(9, 1.8 * n + 0.9), sharex=True, squeeze=False)
    for e, ax in enumerate(axes[:, 0]):
        vals = np.array(wp["least_squares"][e]["values"])
        names = wp["least_squares"][e]["names"]
        ref = lin.theta[e]
        for k, nm in enumerate(names):
            unit = d.units[nm[0]] if lin.forced[e] else PER_UNIT_MASS[nm[0]]
            ax.plot(t, vals[:, k] / ref[k], "o-", ms=3, lw=1, label=f"{nm} ({ref[k]:.4g} {unit})")
        if "online" in wp:
            on = wp["online"]
            m = np.array([r["mass"][e] for r in on])
            ax.plot(t, m / ref[0], "x", color="k", ms=5, label="m, on-line estimator")
        ax.axhline(1.0, color="k", lw=0.6)
        ax.set_ylabel(f"DOF {e + 1}\nrelative")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=5, loc="upper left")
        lo, hi = np.nanpercentile(vals / ref, [2, 98])
        ax.set_ylim(min(lo, 0.9) - 0.02, max(hi, 1.1) + 0.02)
    axes[-1, 0].set_xlabel("window centre [s]")
    fig.suptitle("Linear parameters fitted per window / whole-record fit", fontsize=10)
    fig.tight_layout()
    return fig


def fig_ranking(d, top: int = 12):
    rk = d.ranking[:top]
    fig, ax = subplots(figsize=(8, 0.32 * len(rk) + 1.4))
    labels = []
    for s in rk:
        ((k, v),) = s.fit.location.items()
        labels.append(f"{s.fit.effect} {'DOF' if k == 'dof' else 'spring'} {v}")
    y = np.arange(len(rk))[::-1]
    ax.barh(y, [s.gap_after for s in rk], color=[C_AFTER if s.significant else C_MEAS for s in rk])
    ax.axvline(d.gap_before, color=C_BEFORE, lw=1.5, label=f"linear model {d.gap_before:.3g}")
    nf = d.extra.get("noise_floor")
    if nf:
        ax.axvline(nf, color="k", ls="--", lw=1, label=f"sensor-noise floor (in band) {nf:.3g}")
    ax.set_yticks(y, labels, fontsize=8)
    ax.set_xscale("log")
    ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel(f"withheld gap (NRMS acceleration equation error, 0-{d.band.f_hi:.3g} Hz); blue = beyond noise")
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title(f"Candidates ranked - diagnosis: {d.effect}", fontsize=10)
    fig.tight_layout()
    return fig


def fig_prediction(d, windows: int = 2):
    """The target of every equation (window-detrended, as the fits see it) and the two
    models' predictions of it, target minus equation error, over ``windows`` windows centred
    on the one where the linear model's error is largest."""
    P = d.P
    before, after = d.residuals()
    y = detrend(P, P.y).reshape(before.shape)
    worst = int(np.argmax((P.windows(before) ** 2).sum(axis=(1, 2))))
    lo = max(0, min(worst - windows // 2, P.nw - windows))
    span = slice(lo * P.L, min(P.nw, lo + windows) * P.L)
    t = P.t[span]

    def draw(ax, i):
        ax.plot(t, y[span, i], color=C_MEAS, lw=1.6, label="measured")
        ax.plot(t, (y - before)[span, i], color=C_BEFORE, lw=0.8, ls="--", label="linear model")
        if d.best is not None:
            ax.plot(t, (y - after)[span, i], color=C_AFTER, lw=0.8, label=_label(d))

    return _time_panels(
        d,
        draw,
        "time [s]  (each window's straight line removed, as the fits see it)",
        f"Measured against predicted, where the linear model fails most (in-band gap {d.gap_before:.3g} -> "
        f"{d.gap_after:.3g})",
    )


FIGURES = {
    "residuals_time.png": fig_residuals_time,
    "residuals_spectrum.png": fig_residuals_spectrum,
    "restoring_force.png": fig_restoring_force,
    "damping_force.png": fig_damping_force,
    "window_parameters.png": fig_window_parameters,
    "ranking.png": fig_ranking,
    "prediction.png": fig_prediction,
}


def save_figures(d, folder, which: tuple[str, ...] | None = None) -> list[Path]:
    """Write the diagnosis figures of ``d`` into ``folder`` (created); returns the paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name, make in FIGURES.items():
        if which is not None and name not in which:
            continue
        fig = make(d)
        path = folder / name
        fig.savefig(path, dpi=DPI)
        out.append(path)
    return out
