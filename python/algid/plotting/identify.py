"""Figure of ``algid identify --plots DIR``: ``estimates.png``.

One panel per family (masses, dampings, springs): every parameter's estimate history
relative to its final value, with the one-sigma band of the bootstrap, so that a user sees
when the estimates settled and how far they can be trusted. The legend gives every final
estimate in the units of the recording (``res.units``: kg, N s/m, N/m for SI data, V s^2/V,
V s/V, V/V for forces and displacements in volts); parameters that are not valid are drawn
dashed and named with their status. Built on ``matplotlib.figure.Figure`` (no
pyplot, no backend switch): it works headless and inside notebooks alike.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import subplots

FAMILIES = (("m", "masses"), ("c", "dampings"), ("k", "springs"))


def estimates_figure(res):
    """The figure (a ``matplotlib.figure.Figure``) of an :class:`algid.Identification`."""
    fig, axes = subplots(3, 1, figsize=(9, 7.5), sharex=True)
    rows = min(res.history.shape[0], res.history_sigma.shape[0])
    t, H, S = res.time_s[-rows:], res.history[-rows:], res.history_sigma[-rows:]
    for ax, (fam, title) in zip(axes, FAMILIES):
        for p, v in enumerate(res.verdicts):
            final = res.theta[p]
            if v.name[0] != fam or not np.isfinite(final) or final == 0:
                continue
            rel = 100 * (H[:, p] / final - 1)
            band = 100 * S[:, p] / abs(final)
            style = "-" if v.valid else "--"
            label = f"{v.name} = {final:.4g} {res.units[fam]}" + ("" if v.status == "ok" else f" ({v.status})")
            (line,) = ax.plot(t, rel, style, lw=1.2, label=label)
            ax.fill_between(t, rel - band, rel + band, color=line.get_color(), alpha=0.15, lw=0)
        ax.axhline(0.0, color="0.4", lw=0.6)
        ax.set_ylabel(f"{title} [% from final]")
        lim = _limits(ax)
        if lim is not None:
            ax.set_ylim(*lim)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper right", fontsize=8, ncol=4)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("end of the data described [s]")
    fig.suptitle(
        f"{res.plan.estimator} estimator, {res.samples} samples: estimate / final estimate - 1, one-sigma bands"
    )
    return fig


def _limits(ax):
    """Y range from the second half of the curves (start-up transients would hide the end)."""
    ys = []
    for line in ax.get_lines()[:-1] if ax.get_lines() else []:
        y = np.asarray(line.get_ydata(), dtype=float)
        y = y[y.size // 2 :]
        ys.append(y[np.isfinite(y)])
    ys = np.concatenate(ys) if ys else np.array([])
    if ys.size == 0:
        return None
    span = max(float(np.max(np.abs(ys))), 1e-9)
    return -4 * span, 4 * span


def save_figures(res, folder) -> list[Path]:
    """Write ``estimates.png`` into ``folder`` (created); with effects (one estimate, no
    history), the diagnosis's ``prediction.png`` instead: the chain with the effects against
    the linear one and the data. Returns the paths written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if res.diagnosis is not None:
        from .diagnosis import save_figures as save_diagnosis

        return save_diagnosis(res.diagnosis, folder, which=("prediction.png",))
    path = folder / "estimates.png"
    estimates_figure(res).savefig(path)
    return [path]
