"""Figures of ``algid demo`` (matplotlib figures without pyplot; PNG files).

* ``estimates.png`` (the paper's fig. 2): the on-line estimates against time with the true
  values, one parameter family (masses, dampings, stiffnesses) per row; left the first
  0.25 s where they converge and the substitution happens, right the whole run;
* ``positions.png`` (fig. 3): reference against actual positions, and the tracking error;
* ``forces.png`` (fig. 4): the control forces, and around the substitution their
  deviation from the force an exact model needs along the reference (the overshoot);
* ``estimation_error.png``: relative error of every estimate on a log scale (the paper
  does not show it; it tells when the estimates reach a given accuracy and how they drift);
  when the demo ran the drift table (``res.drift``), a last panel compares the largest
  error of the single growing window with that of the continuous running estimate, both
  open loop on the recorded samples.

``algid demo --topology`` (a spring network, open loop) writes ``network_estimates.png``
instead: every estimate's relative error against the truth with its one-sigma bar.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..model.chain import parameter_names
from . import subplots

__all__ = [
    "FIGURES",
    "estimates_figure",
    "estimation_error_figure",
    "forces_figure",
    "network_estimates_figure",
    "positions_figure",
    "write_figures",
    "write_network_figures",
]

_FAMILIES = (("mass", "mass [kg]"), ("damping", "damping [N s/m]"), ("stiffness", "stiffness [N/m]"))


def _families(res: Any) -> list[tuple[str, np.ndarray, np.ndarray, list[str]]]:
    """Per family (masses, dampings, stiffnesses): axis label, estimates (T, p), true
    values (p,) and names of the parameters that are estimated."""
    chain = res.chain
    true_all = chain.identifiable()
    n = chain.n
    names_all = parameter_names(n)
    out = []
    sl = {"mass": slice(0, n), "damping": slice(n, 2 * n), "stiffness": slice(2 * n, 3 * n + 1)}
    for key, label in _FAMILIES:
        est = np.asarray(res.estimates[key], dtype=float)
        true = true_all[sl[key]]
        keep = np.isfinite(true)
        if key == "stiffness" and chain.boundary == "free":
            keep[-1] = False  # k_{n+1} = 0 is known
        names = names_all[sl[key]]
        if key == "stiffness" and n == 1 and chain.boundary == "fixed":
            names[0] = "k1+k2"
        out.append((label, est[:, keep], true[keep], [nm for nm, k in zip(names, keep) if k]))
    return out


def _title(res: Any, summary: dict[str, Any]) -> str:
    """What ran: DOF, mode, noise, estimator (and whether the estimates were substituted)."""
    from ..control.demo import CONTROL_WORDS, ESTIMATOR_WORDS

    title = (
        f"n = {res.chain.n}, {CONTROL_WORDS[res.mode]}, "
        + ("noise-free" if summary["noise_db"] is None else f"accel SNR {summary['noise_db']:.0f} dB")
        + (f", {ESTIMATOR_WORDS[summary['estimator']]}" if summary.get("estimator") else "")
    )
    if summary.get("estimates_substituted_s", 0.0) is None:
        title += "; estimates never substituted"
    return title


def estimates_figure(res: Any, summary: dict[str, Any]) -> Any:
    """Fig. 2: the on-line estimates against time with the true values."""
    t, t_sw = res.t, summary["switch_time_s"]
    fig, axes = subplots(3, 2, figsize=(12, 9), sharex="col")
    zoom = t <= min(0.25, t[-1])
    for row, (label, est, true, names) in enumerate(_families(res)):
        for col, mask in enumerate((zoom, np.ones_like(zoom))):
            ax = axes[row, col]
            for q in range(true.size):
                (line,) = ax.plot(t[mask], est[mask, q], lw=1.3, label=f"{names[q]} estimate")
                ax.axhline(true[q], color=line.get_color(), ls="--", lw=0.9)
            ax.axvline(t_sw, color="k", ls=":", lw=1.0)
            spread = 0.5 if col == 0 else 0.1
            ax.set_ylim(true.min() * (1 - spread), true.max() * (1 + spread))
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        axes[row, 1].legend(
            loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, title="dashed: true value", title_fontsize=8
        )
    axes[0, 0].set_title("convergence and substitution (dotted line)")
    axes[0, 1].set_title("whole run (y range: true values +-10 %)")
    axes[-1, 0].set_xlabel("time [s]")
    axes[-1, 1].set_xlabel("time [s]")
    fig.suptitle(f"On-line estimates, eq. 7 ({_title(res, summary)})")
    fig.tight_layout()
    return fig


def positions_figure(res: Any, summary: dict[str, Any]) -> Any:
    """Fig. 3: reference against actual positions, and the tracking error."""
    t, t_sw = res.t, summary["switch_time_s"]
    fig, (ax1, ax2) = subplots(2, 1, figsize=(10, 7), sharex=True)
    for i in range(res.chain.n):
        (line,) = ax1.plot(t, 1e3 * res.x[:, i], lw=1.4, label=f"x{i + 1} actual")
        ax1.plot(t, 1e3 * res.x_ref[:, i], ls="--", color=line.get_color(), lw=1.0, label=f"x{i + 1} reference")
        ax2.plot(t, 1e6 * (res.x[:, i] - res.x_ref[:, i]), lw=1.0, label=f"x{i + 1} - x{i + 1}*")
    for ax in (ax1, ax2):
        ax.axvline(t_sw, color="k", ls=":", lw=1.0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=2, loc="upper right")
    ax1.set_ylabel("position [mm]")
    ax2.set_ylabel("tracking error [um]")
    ax2.set_xlabel("time [s]")
    tr = summary["tracking"]
    ax1.set_title(
        f"Reference tracking ({_title(res, summary)})\npeak error after 1 s "
        f"{1e6 * tr['peak_after_1s_m']:.3g} um = {tr['peak_after_1s_pct_stroke']:.2g} % of stroke"
    )
    fig.tight_layout()
    return fig


def forces_figure(res: Any, summary: dict[str, Any]) -> Any:
    """Fig. 4: the control forces, and around the substitution their deviation from the
    force an exact model needs along the reference."""
    t, t_sw = res.t, summary["switch_time_s"]
    chain = res.chain
    M, C, K = chain.matrices()
    log = res.controller_log
    u_ff = log["xdd_ref"] @ M.T + log["xd_ref"] @ C.T + res.x_ref @ K.T
    fig, (ax1, ax2) = subplots(2, 1, figsize=(10, 7))
    zmask = (t >= max(0.0, t_sw - 0.05)) & (t <= t_sw + 0.2)
    for i in range(chain.n):
        (line,) = ax1.plot(t, res.u_applied[:, i], lw=1.3, label=f"u{i + 1}")
        ax2.plot(
            t[zmask],
            1e3 * (res.u_applied[zmask, i] - u_ff[zmask, i]),
            lw=1.3,
            color=line.get_color(),
            label=f"u{i + 1} - exact-model force",
        )
    for ax in (ax1, ax2):
        ax.axvline(t_sw, color="k", ls=":", lw=1.0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=3, loc="upper right")
    ax1.set_ylabel("force [N]")
    ax1.set_xlabel("time [s]")
    ax1.set_title(f"Control forces ({_title(res, summary)})")
    ax2.set_ylabel("force deviation [mN]")
    ax2.set_xlabel("time [s]")
    ax2.set_title(
        "deviation from the force an exact model needs along the reference, around the substitution (dotted line)",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def estimation_error_figure(res: Any, summary: dict[str, Any]) -> Any:
    """Relative error of every estimate on a log scale, and with the drift table
    (``res.drift``) the largest error of both estimators open loop."""
    t, t_sw = res.t, summary["switch_time_s"]
    drift = getattr(res, "drift", None)
    rows = 4 if drift is not None else 3
    fig, axes = subplots(rows, 1, figsize=(10, 3 * rows), sharex=True)
    tpos = np.maximum(t, t[1])
    y_lo = 1e-10 if summary["noise_db"] is None else 1e-5
    for ax, (label, est, true, names) in zip(axes[:3], _families(res)):
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.abs(est / true - 1.0)
        for q in range(true.size):
            ax.plot(tpos, rel[:, q], lw=1.1, label=names[q])
        ax.axhline(0.01, color="k", ls="--", lw=0.9, label="1 %")
        ax.axvline(t_sw, color="k", ls=":", lw=1.0)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(y_lo, 10)
        ax.set_ylabel(f"|relative error|\n{label.split(' [')[0]}")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, ncol=5, loc="upper right")
    if drift is not None:
        _drift_panel(axes[3], drift, tpos, t_sw, y_lo)
    axes[-1].set_xlabel("time [s] (log scale)")
    axes[0].set_title(f"Estimation error ({_title(res, summary)})")
    fig.tight_layout()
    return fig


def _drift_panel(ax: Any, drift: dict[str, Any], tpos: np.ndarray, t_sw: float, y_lo: float) -> None:
    """Largest relative error of the single growing window and of the continuous running
    estimate, both open loop on the recorded samples."""
    running = f"{drift['running_from_s']:.2f} s)" if drift["running_from_s"] is not None else "-)"
    with np.errstate(invalid="ignore"):
        for key, lab in (
            ("single_history", "single growing window"),
            ("continuous_history", "continuous (running estimate from " + running),
        ):
            h = np.asarray(drift[key], dtype=float)
            worst = np.where(np.all(np.isnan(h), axis=1), np.nan, np.nanmax(np.where(np.isnan(h), np.inf, h), axis=1))
            ax.plot(tpos, worst, lw=1.2, label=lab)
    ax.axhline(0.01, color="k", ls="--", lw=0.9, label="1 %")
    ax.axvline(t_sw, color="k", ls=":", lw=1.0)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(y_lo, 100)
    ax.set_ylabel("largest |relative\nerror|, open loop")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="upper right")


#: The demo's figures: file name -> ``make(res, summary)``.
FIGURES = {
    "estimates.png": estimates_figure,
    "positions.png": positions_figure,
    "forces.png": forces_figure,
    "estimation_error.png": estimation_error_figure,
}


def write_figures(res: Any, summary: dict[str, Any], out: Path) -> list[Path]:
    """Write the demo's PNG figures into ``out``; returns their paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, make in FIGURES.items():
        fig = make(res, summary)
        paths.append(out / name)
        fig.savefig(paths[-1], dpi=110)
    return paths


def network_estimates_figure(res: Any, summary: dict[str, Any]) -> Any:
    """``algid demo --topology``: every estimate's relative error [%] against the truth with its
    one-sigma bar, one row per family (masses, dampings, springs); parameters whose verdict is
    not ``ok`` hollow, without an estimate absent."""
    rows = summary["parameters"]
    fig, axes = subplots(3, 1, figsize=(max(8, 0.3 * len(rows)), 8))
    for ax, (letter, label) in zip(axes, (("m", "masses"), ("c", "dampings"), ("k", "springs"))):
        family = [r for r in rows if r["name"][0] == letter]
        x = np.arange(len(family))
        rel = np.array([100 * r["rel_err"] for r in family])
        bar = np.array([100 * r["sigma"] / r["true"] if r["true"] else np.nan for r in family])
        ok = np.array([r["status"] == "ok" for r in family])
        for mask, face in ((ok, "C0"), (~ok, "none")):
            ax.errorbar(x[mask], rel[mask], bar[mask], fmt="o", mfc=face, mec="C0", ecolor="C0", capsize=3)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xticks(x, [r["name"] for r in family])
        ax.set_ylabel(f"{label}\nrelative error [%]")
        ax.grid(alpha=0.3)
    noise = "noise-free" if summary["noise_db"] is None else f"accel SNR {summary['noise_db']:g} dB"
    axes[0].set_title(
        f"Network of {summary['n']} masses, {len(summary['springs'])} springs, open loop, {noise}\n"
        "estimates against the truth (bars: one sigma; hollow: verdict not ok)"
    )
    fig.tight_layout()
    return fig


def write_network_figures(res: Any, summary: dict[str, Any], out: Path) -> list[Path]:
    """Write ``algid demo --topology``'s ``network_estimates.png`` into ``out``; returns its path."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "network_estimates.png"
    network_estimates_figure(res, summary).savefig(path, dpi=110)
    return [path]
