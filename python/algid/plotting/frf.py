"""Figure ``frf.png``: the model's FRF against the H1 estimate from the recording.

Three panels over frequency [Hz] (log scale): magnitude (log), phase [deg] and the multiple coherence of
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
