"""Figures ``frf.png`` (the model's FRF against the H1 estimate from a recording) and
``frf_fit.png`` (:func:`frf_fit_figure`: the model fitted to measured FRFs against them).

``frf.png``: three panels over frequency [Hz] (log scale): magnitude (log), phase [deg] and the multiple coherence of
every drive-point FRF ``H[e, e]`` (the response of mass e to its own force) of a forced mass;
measured solid, model dashed in the same colour. Units are the estimate's
(:attr:`algid.frf.FrfEstimate.unit`: the recording's declared units, else SI) unless
``units`` names others.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import subplots


def frf_figure(estimate, chain=None, units: str | None = None, title: str = ""):
    """The figure of an :class:`algid.frf.FrfEstimate` and, if given, the model of ``chain``."""
    unit = units or estimate.unit
    f, H = estimate.f_hz, estimate.H
    keep = f > 0
    model = chain.frf(f[keep], estimate.output) if chain is not None else None
    fig, (mag, pha, coh) = subplots(3, 1, figsize=(9, 8), sharex=True, gridspec_kw={"height_ratios": [3, 2, 1.3]})
    for e in range(H.shape[1]):
        if not np.all(np.isfinite(H[:, e, e])):
            continue  # an unforced mass has no drive-point FRF
        (line,) = mag.semilogy(f[keep], np.abs(H[keep, e, e]), lw=1.0, label=f"H{e + 1}{e + 1} measured (H1)")
        colour = line.get_color()
        pha.plot(f[keep], np.degrees(np.angle(H[keep, e, e])), lw=1.0, color=colour)
        coh.plot(f[keep], np.clip(estimate.coherence[keep, e], 0.0, 1.0), lw=1.0, color=colour, label=f"output {e + 1}")
        if model is not None:
            mag.semilogy(f[keep], np.abs(model[:, e, e]), "--", lw=1.2, color=colour, label=f"H{e + 1}{e + 1} model")
            pha.plot(f[keep], np.degrees(np.angle(model[:, e, e])), "--", lw=1.2, color=colour)
    mag.set_ylabel(f"|H| [{unit}]")
    pha.set_ylabel("phase [deg]")
    pha.set_ylim(-185, 185)
    pha.set_yticks([-180, -90, 0, 90, 180])
    coh.set_ylabel("coherence [-]")
    coh.set_ylim(0, 1.05)
    coh.set_xlabel("frequency [Hz]")
    coh.set_xscale("log")  # shared: every panel
    for ax in (mag, pha, coh):
        ax.grid(alpha=0.3)
    if mag.get_legend_handles_labels()[0]:
        mag.legend(loc="best", fontsize=8, ncol=2)
    fig.suptitle(
        title
        or f"drive-point FRFs: H1 ({estimate.segments} Welch segments of {estimate.nperseg} samples)"
        + (" vs identified model" if chain is not None else "")
    )
    return fig


def save_frf(estimate, folder, chain=None, units: str | None = None) -> Path:
    """Write ``frf.png`` into ``folder`` (created); returns its path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "frf.png"
    frf_figure(estimate, chain, units).savefig(path)
    return path


def frf_fit_figure(result):
    """``frf_fit.png`` of an FRF fit (:class:`~algid.identification.frf_result.FrfIdentification`):
    one column of panels per measured force, magnitude (log) over phase [deg] against
    frequency [Hz] (log), every response measured solid and the fitted model dashed in the
    same colour, in the FRFs' own quantity and units."""
    from ..identification.frf_fit import model_frf

    data = result.data
    f, keep = data.frequency_hz, data.frequency_hz > 0
    model = model_frf(result.theta, data, result.boundary)
    Q = data.force_dof.size
    fig, axes = subplots(2, Q, figsize=(4.5 * Q + 1.5, 6.5), sharex=True, squeeze=False)
    for q, j in enumerate(data.force_dof):
        mag, pha = axes[0, q], axes[1, q]
        for r, e in enumerate(data.response_dof):
            (line,) = mag.semilogy(f[keep], np.abs(data.H[r, q, keep]), lw=1.0, label=f"H{e}{j} measured")
            colour = line.get_color()
            mag.semilogy(f[keep], np.abs(model[r, q, keep]), "--", lw=1.2, color=colour, label=f"H{e}{j} model")
            pha.plot(f[keep], np.degrees(np.angle(data.H[r, q, keep])), lw=1.0, color=colour)
            pha.plot(f[keep], np.degrees(np.angle(model[r, q, keep])), "--", lw=1.2, color=colour)
        mag.set_title(f"force at DOF {j}")
        mag.set_ylabel(f"|H| [{data.unit}]")
        mag.legend(loc="best", fontsize=7, ncol=2)
        pha.set_ylabel("phase [deg]")
        pha.set_ylim(-185, 185)
        pha.set_yticks([-180, -90, 0, 90, 180])
        pha.set_xlabel("frequency [Hz]")
        pha.set_xscale("log")  # shared: both panels
        for ax in (mag, pha):
            ax.grid(alpha=0.3)
    fig.suptitle(f"measured {data.quantity} (solid) vs identified model (dashed)")
    return fig


def save_frf_fit(result, folder) -> Path:
    """Write ``frf_fit.png`` (:func:`frf_fit_figure`) into ``folder`` (created); returns its path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "frf_fit.png"
    frf_fit_figure(result).savefig(path)
    return path
