"""Recordings to and from :class:`pandas.DataFrame` (``pip install 'algid[pandas]'``)."""

from __future__ import annotations

import numpy as np

from ..messages import quote
from .columns import resolve
from .core import Recording, RecordingError, require
from .table import assemble

SOURCE = "DataFrame"


def from_frame(frame, columns=None, units=None, dt: float | None = None) -> Recording:
    """A recording from the columns of ``frame`` (named as in a CSV header, or mapped by
    ``columns``); a named index (``frame.set_index("time")``) counts as a column. ``units``
    defaults to ``frame.attrs["units"]`` (what :func:`to_frame` writes)."""
    if frame.index.name is not None:
        frame = frame.reset_index()
    names = [str(c) for c in frame.columns]
    layout = resolve(names, SOURCE, columns, need_time=dt is None)
    used = layout.positions()
    data = np.empty((len(frame), len(used)))
    for col, pos in enumerate(used):
        try:
            data[:, col] = frame.iloc[:, pos].to_numpy(dtype=float)
        except (TypeError, ValueError):
            raise RecordingError(f"{SOURCE}: column {quote(names[pos])} is not numeric") from None
    if units is None:
        units = {role: label for role, label in frame.attrs.get("units", {}).items() if role != "time"}
    return assemble(None, SOURCE, data, layout, None, dt=dt, units=units)


def to_frame(rec: Recording):
    """``rec`` as a DataFrame with columns ``t, u1.., a1..`` and ``attrs["units"]``."""
    pd = require("pandas", "pandas", "DataFrames")
    frame = pd.DataFrame(rec.columns())
    frame.attrs["units"] = {"time": "s", **rec.units}
    return frame
