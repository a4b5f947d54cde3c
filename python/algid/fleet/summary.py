"""The summary of a batch: one row per machine (the folder a recording lies in).

Per machine: recordings, ok, failed, valid identifications, the span of recording times, the
diagnosis verdicts counted (``effect: count``), and the largest stiffness shift between the
first and the last valid identification, in standard deviations of the difference,

    z_j = |k_j(last) - k_j(first)| / sqrt(sigma_j(first)^2 + sigma_j(last)^2),

with ``moved`` when the largest ``z_j`` exceeds :data:`MOVED_Z` (the machines to look at).
"""

from __future__ import annotations

import math
import re

#: A stiffness shift of more than this many standard deviations flags the machine.
MOVED_Z = 3.0

_SPRING = re.compile(r"^k[0-9]+$")


def springs(table) -> list[str]:
    """Spring columns ``k1, k2, ...`` of a results table, in DOF order."""
    return sorted((c for c in table.columns if _SPRING.match(c)), key=lambda c: int(c[1:]))


def valid_mask(table):
    """Boolean Series: the rows identified with every DOF valid (False where failed)."""
    import pandas as pd

    if "valid" not in table.columns:
        return pd.Series(False, index=table.index)
    return (table["status"] == "ok") & table["valid"].eq(True)


def stiffness_shift_z(rows) -> float:
    """Largest ``z_j`` between the first and the last row (sorted by time); NaN if undefined."""
    if len(rows) < 2:
        return math.nan
    first, last = rows.iloc[0], rows.iloc[-1]
    z = [
        abs(last[k] - first[k]) / math.hypot(first[f"sigma_{k}"], last[f"sigma_{k}"])
        for k in springs(rows)
        if all(math.isfinite(v) for v in (first[k], last[k], first[f"sigma_{k}"], last[f"sigma_{k}"]))
        and math.hypot(first[f"sigma_{k}"], last[f"sigma_{k}"]) > 0
    ]
    return max(z) if z else math.nan


def _verdicts(rows) -> str:
    if "effect" not in rows.columns:
        return ""
    counts = rows["effect"].dropna().value_counts()
    return ", ".join(f"{effect}: {count}" for effect, count in counts.items())


def summary(table):
    """The per-machine summary (a pandas DataFrame, one row per machine, sorted by name)."""
    import pandas as pd

    out = []
    for machine, rows in table.groupby("machine", sort=True):
        ok = rows[rows["status"] == "ok"]
        valid = rows[valid_mask(rows)]
        z = stiffness_shift_z(valid.sort_values("recorded_at")) if len(valid) else math.nan
        out.append(
            {
                "machine": machine,
                "recordings": len(rows),
                "ok": len(ok),
                "failed": int((rows["status"] == "failed").sum()),
                "valid": len(valid),
                "first": rows["recorded_at"].min() if "recorded_at" in rows.columns else None,
                "last": rows["recorded_at"].max() if "recorded_at" in rows.columns else None,
                "verdicts": _verdicts(ok),
                "stiffness_shift_z": z,
                "moved": bool(z > MOVED_Z),
            }
        )
    return pd.DataFrame(out)
