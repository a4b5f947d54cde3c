"""Figures ``frf.png`` (the model's FRF against the H1 estimate from a recording) and
``frf_fit.png`` (:func:`frf_fit_figure`: the model fitted to measured FRFs against them).

``frf.png``: three panels over frequency [Hz] (log scale): magnitude (log), phase [deg] and the multiple coherence of
every drive-point FRF ``H[e, e]`` (the response of mass e to its own force) of a forced mass;
measured where the forces excite it (:func:`algid.model.frf.h1_estimate`: a multisine's lines are
points at their frequencies, a broadband band a curve), model dashed in the same colour on a
fine grid. The frequency axis spans :data:`SPAN` times the chain's highest natural frequency
(or the excited band without a chain), not the Nyquist rate. Units are the estimate's
(:attr:`algid.model.frf.FrfEstimate.unit`: the recording's declared units, else SI) unless
``units`` names others.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import subplots

#: The frequency axis ends at this multiple of the highest natural frequency.
SPAN = 3.0
#: Points of the model curve.
MODEL_POINTS = 1500


def frequency_range(estimate, chain=None) -> tuple[float, float]:
    """``(lo, hi)`` [Hz] of the axis: from half the lowest of the natural frequencies and the
    excited frequencies to :data:`SPAN` times the highest natural frequency, or with no chain
    (or no mode) to 1.2 times the highest excited frequency; within ``(0, Nyquist]``."""
    at = estimate.at_hz[np.isfinite(estimate.at_hz)]
    natural = chain.natural_frequencies_hz() if chain is not None else np.array([])
    natural = natural[natural > 0]
    lows = np.concatenate([at, natural])
    nyquist = float(estimate.f_hz[-1])
    lo = 0.5 * float(lows.min()) if lows.size else float(estimate.f_hz[1])
    hi = SPAN * float(natural.max()) if natural.size else 1.2 * float(at.max()) if at.size else nyquist
    return max(lo, float(estimate.f_hz[1]) / 2), min(max(hi, 2 * lo), nyquist)


def measured(estimate, e: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(f, H, coherence)`` of the drive point ``e`` over all bins: ``f`` the frequency each
    bin stands for (a line's own where force ``e`` excites a line), ``H`` and the coherence
    NaN where force ``e`` does not excite (the line is broken there; a lone line is a point)."""
    on = estimate.excited[:, e]
    f = np.where(on, estimate.at_hz[:, e], estimate.f_hz)
    return f, np.where(on, estimate.H[:, e, e], np.nan), np.where(on, estimate.coherence[:, e], np.nan)


def frf_figure(estimate, chain=None, units: str | None = None, title: str = ""):
    """The figure (a ``matplotlib.figure.Figure``) of an :class:`algid.model.frf.FrfEstimate` and,
    if given, the model of ``chain``."""
    unit = units or estimate.unit
    lo, hi = frequency_range(estimate, chain)
    f_model = np.geomspace(lo, hi, MODEL_POINTS)
    model = chain.frf(f_model, estimate.output) if chain is not None else None
    fig, (mag, pha, coh) = subplots(3, 1, figsize=(9, 8), sharex=True, gridspec_kw={"height_ratios": [3, 2, 1.3]})
    drawn = []
    for e in range(estimate.H.shape[1]):
        if not estimate.excited[:, e].any():
            continue  # an unforced mass (or forces not separable anywhere) has no drive-point FRF
        f, H, gamma2 = measured(estimate, e)
        drawn.append(e + 1)
        (line,) = mag.semilogy(f, np.abs(H), ".-", ms=5, lw=1.0, label=f"H{e + 1}{e + 1} measured (H1)")
        colour = line.get_color()
        pha.plot(f, np.degrees(np.angle(H)), ".-", ms=5, lw=1.0, color=colour)
        coh.plot(f, np.clip(gamma2, 0.0, 1.0), ".-", ms=5, lw=1.0, color=colour, label=f"output {e + 1}")
        if model is not None:
            mag.semilogy(f_model, np.abs(model[:, e, e]), "--", lw=1.2, color=colour, label=f"H{e + 1}{e + 1} model")
            pha.plot(f_model, np.degrees(np.angle(model[:, e, e])), "--", lw=1.2, color=colour)
    mag.set_ylabel(f"|H| [{unit}]")
    pha.set_ylabel("phase [deg]")
    pha.set_ylim(-185, 185)
    pha.set_yticks([-180, -90, 0, 90, 180])
    coh.set_ylabel("coherence [-]")
    coh.set_ylim(0, 1.05)
    coh.set_xlabel("frequency [Hz]  (measured only where the forces excite)")
    coh.set_xscale("log")  # shared: every panel
    coh.set_xlim(lo, hi)
    for ax in (mag, pha, coh):
        ax.grid(alpha=0.3, which="both")
    if mag.get_legend_handles_labels()[0]:
        mag.legend(loc="best", fontsize=8, ncol=2)
    fig.suptitle(title or _title(estimate, chain, drawn), fontsize=10)
    fig.tight_layout()
    return fig


def _title(estimate, chain, drawn: list[int]) -> str:
    from ..model.frf import resolution_hz

    text = (
        f"drive-point FRFs: H1 ({estimate.segments} Welch segments of {estimate.nperseg} samples, "
        f"bins of {estimate.resolution_hz:.3g} Hz)"
    )
    if chain is not None:
        text += " vs identified model"
        wanted = resolution_hz(chain)
        if np.isfinite(wanted):
            text += f"\nnarrowest mode {2 * wanted:.3g} Hz wide at half power"
    if not drawn:
        text += "\nno measured FRF: where the forces excite, they are not separable (the same lines on every force)"
    return text


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
