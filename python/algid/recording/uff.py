"""UFF 58 recordings (``.uff``, ``.unv``; the optional extra ``algid[uff]``, pyuff): the
time responses (function type 1) a test rig's software exports, one record per channel.

The abscissa gives the time (``abscissa_min + k * abscissa_inc``, every record on the same
grid). Without a mapping each record's role comes from its ordinate data type (13 or 9:
force, 12: acceleration, 11: velocity, 8: displacement; others ignored), its DOF from its
response node (nodes in increasing order are DOF 1..n) and its unit from the ordinate's
unit label. With a mapping the columns are named by each record's ``id1``. pyuff reads the
whole file into memory.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..messages import quote
from .columns import resolve
from .core import RecordingError, require
from .table import assemble

#: UFF ordinate specific data type -> signal.
UFF_ROLES = {13: "u", 9: "u", 12: "a", 11: "v", 8: "x"}
#: UFF 58 function type of a time response.
TIME_RESPONSE = 1


def _time_responses(path: Path) -> list[dict]:
    pyuff = require("pyuff", "uff", "UFF recordings")
    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception as err:  # noqa: BLE001 - pyuff raises bare Exceptions on malformed files
        raise RecordingError(f"{path.name}: not a readable UFF file ({type(err).__name__})") from None
    sets = [sets] if isinstance(sets, dict) else list(sets)
    series = [s for s in sets if s.get("type") == 58 and s.get("func_type") == TIME_RESPONSE]
    if not series:
        raise RecordingError(f"{path.name}: no time responses (UFF 58 records of function type 1)")
    first = series[0]
    for s in series:
        same_grid = s["num_pts"] == first["num_pts"] and math.isclose(
            s["abscissa_inc"], first["abscissa_inc"], rel_tol=1e-9
        )
        if not same_grid or s["abscissa_min"] != first["abscissa_min"]:
            raise RecordingError(f"{path.name}: record {quote(s['id1'])} is not on the time grid of the first record")
        if np.iscomplexobj(s["data"]):
            raise RecordingError(f"{path.name}: record {quote(s['id1'])} is complex, not a time response")
        if np.size(s["data"]) != s["num_pts"]:
            raise RecordingError(
                f"{path.name}: record {quote(s['id1'])} holds {np.size(s['data'])} values "
                f"but declares {s['num_pts']} (truncated or corrupt)"
            )
    return series


def _names(series: list[dict], by_id: bool) -> list[str]:
    """``id1`` of every record, or the signal name its data type and node give."""
    if by_id:
        return [str(s["id1"]).strip() for s in series]
    names = []
    for s in series:
        key = UFF_ROLES.get(s["ordinate_spec_data_type"])
        nodes = sorted({r["rsp_node"] for r in series if UFF_ROLES.get(r["ordinate_spec_data_type"]) == key})
        names.append(f"{key}{nodes.index(s['rsp_node']) + 1}" if key else str(s["id1"]).strip())
    return names


def _label(text) -> str | None:
    """A UFF unit label, None when blank, ``NONE`` or a number (``0``: pyuff's default, no unit)."""
    text = str(text or "").strip()
    return None if text.upper() in ("", "NONE") or text.lstrip("+-").replace(".", "", 1).isdigit() else text


def read_uff(path: Path, columns=None, units=None, dt=None):
    """Read and validate the UFF 58 time responses of ``path``."""
    series = _time_responses(path)
    names = ["t"] + _names(series, by_id=bool(columns))
    declared = [_label(series[0]["abscissa_axis_units_lab"])] + [_label(s["ordinate_axis_units_lab"]) for s in series]
    layout = resolve(names, path.name, columns, declared=declared)
    T, step = series[0]["num_pts"], series[0]["abscissa_inc"]
    table = [series[0]["abscissa_min"] + step * np.arange(T)] + [np.asarray(s["data"], float) for s in series]
    data = np.column_stack([table[p] for p in layout.positions()])
    return assemble(path, path.name, data, layout, None, dt=dt, units=units)
