"""Figure of ``algid identify --plots DIR`` on an impact record: ``transient.png``.

Top: the hit(s), the force as the identification used it (baseline drift removed, band-passed).
Bottom: the measured response over the decay, band-passed alike, and the identified chain's
response to that force (the chain driven from rest by the cleaned force and band-passed alike, as
identify's fit check computes it: :mod:`algid.identification.impact_fit`). The numbers drawn are
those of :func:`transient_lines`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import subplots


def transient_lines(res, rec) -> dict:
    """``t_s``, ``force``, ``measured`` and ``model`` (T,) at the hammer's DOF of the record ``rec``
    as :func:`algid.identify` saw it (:func:`algid.recording.transient.transient_record` with the
    result's band); ``model`` is NaN when there is no admissible chain."""
    from ..identification.impact_fit import chain_of, predicted_motion
    from ..recording import motion
    from ..recording.transient import band_pass, clean_force, transient_record

    filtered, tr = transient_record(rec, res.transient.band_hz)
    kind, y = motion(filtered)
    drive = int(np.argmax(np.max(np.abs(filtered.u), axis=0)))
    model = np.full(filtered.t.size, np.nan)
    chain = chain_of(res.theta, res.n, res.boundary)
    if chain is not None:  # driven by the cleaned force from rest, then band-passed as the record
        out = predicted_motion(chain, kind, clean_force(rec.u, list(tr.hits), tr.dt), tr.dt)
        model = band_pass(out, tr.dt, tr.band_hz)[:, drive]
    return {"t_s": filtered.t, "force": filtered.u[:, drive], "measured": y[:, drive], "model": model, "kind": kind}


def transient_figure(res, rec):
    """The figure (``matplotlib.figure.Figure``) of :func:`transient_lines`."""
    d = transient_lines(res, rec)
    fig, (top, bottom) = subplots(2, 1, figsize=(9, 6), sharex=True)
    top.plot(d["t_s"], d["force"], lw=0.8, label="force (drift removed, band-passed)")
    bottom.plot(d["t_s"], d["measured"], lw=0.6, label=f"measured {d['kind']} (band-passed)")
    bottom.plot(d["t_s"], d["model"], lw=0.6, ls="--", label="identified chain, same force")
    lo, hi = res.transient.band_hz
    top.set_title(res.transient.line(), fontsize=7)
    bottom.set_xlabel("time [s]")
    top.set_ylabel(f"force [{res.units.get('force', 'N') if isinstance(res.units, dict) else 'N'}]")
    bottom.set_ylabel(d["kind"])
    for ax in (top, bottom):
        ax.legend(loc="upper right", fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle(f"impact record, band {lo:.4g}-{hi:.4g} Hz", fontsize=10)
    return fig


def save_transient(res, rec, folder) -> Path:
    """Write ``transient.png`` into ``folder`` (created)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "transient.png"
    transient_figure(res, rec).savefig(path)
    return path
