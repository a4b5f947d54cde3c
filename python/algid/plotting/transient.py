"""Figure of ``algid identify --plots DIR`` on an impact record: ``transient.png``.

Top: the hit(s), the force as the identification used it (baseline drift removed, band-passed).
Bottom: the measured response over the decay, band-passed alike, and the identified chain's
response to that force (the chain's state space, :func:`algid.model.frf.state_space`, simulated with
the measured force). The numbers drawn are those of :func:`transient_lines`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import subplots


def transient_lines(res, rec) -> dict:
    """``t_s``, ``force``, ``measured`` and ``model`` (T,) at the hammer's DOF of the record ``rec``
    as :func:`algid.identify` saw it (:func:`algid.recording.transient.transient_record` with the
    result's band); ``model`` is NaN when the chain has no estimate."""
    from scipy.signal import lsim

    from ..model.chain import Chain
    from ..model.frf import state_space
    from ..recording.transient import transient_record

    filtered, _ = transient_record(rec, res.transient.band_hz)
    kind = "acceleration" if filtered.a is not None else ("velocity" if filtered.v is not None else "displacement")
    y = {"acceleration": filtered.a, "velocity": filtered.v, "displacement": filtered.x}[kind]
    drive = int(np.argmax(np.max(np.abs(filtered.u), axis=0)))
    model = np.full(filtered.t.size, np.nan)
    if np.all(np.isfinite(res.theta[: 2 * res.n])) and np.isfinite(res.theta[2 * res.n]):
        chain = Chain.from_packed(np.nan_to_num(res.theta), res.n, res.boundary)
        _, out, _ = lsim(state_space(chain, kind), filtered.u, filtered.t - filtered.t[0])
        model = np.asarray(out).reshape(filtered.t.size, -1)[:, drive]
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
