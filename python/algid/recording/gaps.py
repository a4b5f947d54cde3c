"""Missing samples in a file's signals (NaN, inf, a logger's dropped reading): short gaps bridged,
a record that is mostly missing refused.

A run of at most :data:`MAX_GAP_SAMPLES` missing samples in a channel is bridged by the straight
line between its channel's neighbours (held flat at the record's ends), and its instants are
marked in :attr:`Recording.missing`: :func:`algid.identify` leaves them out of its estimates as it
does samples its screen takes out (the single window reseeds, the continuous estimator drops the
windows in flight), :func:`algid.diagnose` reads the bridged values. A note counts them. A longer
gap, or more than :data:`MAX_MISSING_SHARE` of the instants missing, is an error that says where.
The time column is never bridged: a missing timestamp is an error.
"""

from __future__ import annotations

import numpy as np

from .core import RecordingError

#: Longest run of missing samples in one channel that is bridged [samples].
MAX_GAP_SAMPLES = 8
#: Largest share of the instants (any channel missing) a record may lack.
MAX_MISSING_SHARE = 0.2


def _runs(bad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(starts, lengths) of the runs of True in the 1-D ``bad``."""
    edges = np.diff(np.concatenate([[0], bad.astype(np.int8), [0]]))
    starts = np.flatnonzero(edges == 1)
    return starts, np.flatnonzero(edges == -1) - starts


def _where(row: int, lines: np.ndarray | None) -> str:
    return f"line {lines[row]}" if lines is not None else f"sample {row}"


def _bridge(y: np.ndarray, bad: np.ndarray) -> np.ndarray:
    """``y`` with its ``bad`` samples on the line between their good neighbours."""
    k = np.arange(y.size)
    out = y.copy()
    out[bad] = np.interp(k[bad], k[~bad], y[~bad])
    return out


def bridge_gaps(
    parts: dict[str, np.ndarray], lines: np.ndarray | None = None, names: dict[str, list[str]] | None = None
) -> tuple[dict[str, np.ndarray], np.ndarray | None, list[str]]:
    """``(parts, missing, notes)``: the (T, n) signals of ``parts`` (``u``, ``a``, ``v``, ``x``)
    with their short gaps bridged, the (T,) instants bridged (None when none) and the note that
    counts them; ``names`` the file's names of the columns (default ``u1``, ``a1``...). Raises
    :class:`RecordingError` on a longer gap or a mostly missing record."""
    T = next(iter(parts.values())).shape[0]
    missing = np.zeros(T, bool)
    runs: list[tuple[int, int, str]] = []  # (start, length, channel)
    for key, arr in parts.items():
        called = (names or {}).get(key) or [f"{key}{j + 1}" for j in range(arr.shape[1])]
        for j in range(arr.shape[1]):
            bad = ~np.isfinite(arr[:, j])
            if bad.all():
                raise RecordingError(f"column {called[j]} holds no number")
            runs += [(int(start), int(length), called[j]) for start, length in zip(*_runs(bad))]
            missing |= bad
    if not runs:
        return parts, None, []
    longest = max(runs, key=lambda r: r[1])
    if longest[1] > MAX_GAP_SAMPLES:
        start, length, channel = longest
        raise RecordingError(
            f"column {channel} misses {length} samples in a row from {_where(start, lines)} (at most "
            f"{MAX_GAP_SAMPLES} are bridged): cut the record there, or fill the gap"
        )
    share = missing.mean()
    if share > MAX_MISSING_SHARE:
        raise RecordingError(
            f"{100 * share:.0f} % of the samples miss a value (NaN or inf; at most {100 * MAX_MISSING_SHARE:.0f} % "
            "may): too little left to identify"
        )
    out = {}
    for key, arr in parts.items():
        bad = ~np.isfinite(arr)
        out[key] = (
            arr if not bad.any() else np.column_stack([_bridge(arr[:, j], bad[:, j]) for j in range(arr.shape[1])])
        )
    runs.sort()
    shown = ", ".join(f"{c} at {_where(s, lines)}" for s, _, c in runs[:3]) + (" ..." if len(runs) > 3 else "")
    count = sum(length for _, length, _ in runs)
    plural = {
        "value": "s" if count > 1 else "",
        "gap": "s" if len(runs) > 1 else "",
        "sample": "s" if longest[1] > 1 else "",
    }
    note = (
        f"{count} missing value{plural['value']} (NaN or inf) in {len(runs)} gap{plural['gap']} of at most "
        f"{longest[1]} sample{plural['sample']} bridged by straight lines ({shown}); identify leaves those instants out"
    )
    return out, missing, [note]
