"""Figures of ``algid batch --plots``: ``histories.png`` and ``verdicts.png``.

``histories.png``: one panel per machine (the first :data:`MAX_PANELS`), every spring's
estimate over the recording times with its one-sigma error bar, valid identifications only,
so a stiffness that moved stands out. ``verdicts.png``: how many recordings failed, were
identified but not valid, or valid, and (with ``--diagnose``) how many got each diagnosis.
"""

from __future__ import annotations

from pathlib import Path

from ..fleet.summary import springs, valid_mask
from . import subplots

#: Machines drawn in the histories figure.
MAX_PANELS = 12


def histories_figure(table):
    """Spring estimates over time per machine (valid identifications)."""
    ok = table[valid_mask(table)]
    machines = sorted(ok["machine"].unique())[:MAX_PANELS] if len(ok) else []
    fig, axes = subplots(max(len(machines), 1), 1, figsize=(9, 2.2 * max(len(machines), 1) + 0.8), squeeze=False)
    for ax, machine in zip(axes[:, 0], machines):
        rows = ok[ok["machine"] == machine].sort_values("recorded_at")
        for k in springs(rows):
            ax.errorbar(rows["recorded_at"], rows[k], yerr=rows[f"sigma_{k}"], fmt="o-", ms=3, lw=1, capsize=2, label=k)
        ax.set_title(machine, fontsize=9, loc="left")
        ax.set_ylabel("k [N/m]")
        ax.legend(fontsize=7, ncol=4)
    if not machines:
        axes[0, 0].text(0.5, 0.5, "no valid identification", ha="center", transform=axes[0, 0].transAxes)
    axes[-1, 0].set_xlabel("recorded at (file time, UTC)")
    fig.tight_layout()
    return fig


def verdicts_figure(table):
    """Counts of the outcomes and of the diagnosis verdicts."""
    ok = table["status"] == "ok"
    valid = valid_mask(table)
    outcomes = {"failed": int((~ok).sum()), "not valid": int((ok & ~valid).sum()), "valid": int(valid.sum())}
    panels = [("identification", outcomes)]
    if "effect" in table.columns:
        panels.append(("diagnosis", table.loc[ok, "effect"].value_counts().to_dict()))
    fig, axes = subplots(1, len(panels), figsize=(4.5 * len(panels), 3.5), squeeze=False)
    for ax, (title, counts) in zip(axes[0], panels):
        ax.bar(list(counts), list(counts.values()), color="tab:blue")
        ax.set_title(title)
        ax.set_ylabel("recordings")
        ax.tick_params(axis="x", labelrotation=30, labelsize=8)
    fig.tight_layout()
    return fig


def save_figures(table, folder: str | Path) -> list[Path]:
    """Write ``histories.png`` and ``verdicts.png`` into ``folder``; returns their paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    files = [folder / "histories.png", folder / "verdicts.png"]
    histories_figure(table).savefig(files[0])
    verdicts_figure(table).savefig(files[1])
    return files
