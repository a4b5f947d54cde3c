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


#: UFF 58 function types of a frequency response function and of an (ordinary) coherence.
FRF, COHERENCE = 4, 6
#: UFF ordinate specific data type of an FRF's numerator -> FRF quantity.
UFF_QUANTITIES = {8: "receptance", 11: "mobility", 12: "accelerance"}


def _sets(path: Path, header_only: bool = False) -> list[dict]:
    pyuff = require("pyuff", "uff", "UFF files")
    try:
        sets = pyuff.UFF(str(path)).read_sets(header_only=header_only)
    except Exception as err:  # noqa: BLE001 - pyuff raises bare Exceptions on malformed files
        raise RecordingError(f"{path.name}: not a readable UFF file ({type(err).__name__})") from None
    return [sets] if isinstance(sets, dict) else list(sets)


def holds_frf(path: Path) -> bool:
    """True when ``path`` holds a UFF 58 frequency response function (read from the
    records' headers; False without pyuff or for a file pyuff cannot read)."""
    try:
        return any(s.get("type") == 58 and s.get("func_type") == FRF for s in _sets(path, header_only=True))
    except RecordingError:
        return False


def _frequency_axis(s: dict) -> np.ndarray:
    """The record's frequencies [Hz]: ``abscissa_min + k abscissa_inc`` when evenly spaced,
    else its abscissa array."""
    if s.get("abscissa_spacing", 1) == 1 and s.get("abscissa_inc", 0) > 0:
        return s["abscissa_min"] + s["abscissa_inc"] * np.arange(s["num_pts"])
    return np.asarray(s["x"], dtype=float)


def _frf_records(path: Path) -> tuple[list[dict], list[dict]]:
    """The FRF records (function type 4) and the coherence records (type 6), checked."""
    sets = [s for s in _sets(path) if s.get("type") == 58]
    frfs = [s for s in sets if s.get("func_type") == FRF]
    if not frfs:
        raise RecordingError(f"{path.name}: no frequency response functions (UFF 58 records of function type 4)")
    f0 = _frequency_axis(frfs[0])
    for s in frfs + [s for s in sets if s.get("func_type") == COHERENCE]:
        if np.size(s["data"]) != s["num_pts"]:
            raise RecordingError(
                f"{path.name}: record {quote(s['id1'])} holds {np.size(s['data'])} values "
                f"but declares {s['num_pts']} (truncated or corrupt)"
            )
        f = _frequency_axis(s)
        if f.size != f0.size or not np.allclose(f, f0, rtol=1e-9, atol=0):
            raise RecordingError(f"{path.name}: record {quote(s['id1'])} is not on the frequency lines of the first")
    return frfs, [s for s in sets if s.get("func_type") == COHERENCE]


def _frf_units(s: dict, quantity: str) -> tuple[float, dict, list[str]]:
    """(factor to SI, unit labels by role, notes) of an FRF record's numerator and denominator."""
    from .units import conversion_note, to_si

    motion = {"receptance": "displacement", "mobility": "velocity", "accelerance": "acceleration"}[quantity]
    factor, units, notes = 1.0, {}, []
    for role, key in ((motion, "ordinate_axis_units_lab"), ("force", "orddenom_axis_units_lab")):
        label = _label(s.get(key))
        scale, unit = to_si(role, label)
        units[role] = unit
        if scale is not None and scale != 1.0:
            factor *= scale if role == motion else 1.0 / scale
            notes.append(conversion_note(role, label, scale))
    return factor, units, notes


def read_uff_frf(path: Path):
    """The FRFs of a UFF 58 file (:func:`algid.recording.frf_file.load_frf`): one record of
    function type 4 per response and reference pair; response and reference nodes in
    increasing order are DOF 1..n; the quantity from the numerator's ordinate data type (8
    displacement, 11 velocity, 12 acceleration); a negative direction flips the sign;
    coherences from records of function type 6 of the same pair, if every pair has one."""
    from .frf_file import FrfData

    frfs, cohs = _frf_records(path)
    types = {s["ordinate_spec_data_type"] for s in frfs}
    if len(types) != 1 or next(iter(types)) not in UFF_QUANTITIES:
        raise RecordingError(
            f"{path.name}: FRF ordinate data types {sorted(types)}: expected one of 8 (receptance), "
            "11 (mobility), 12 (accelerance) for every record"
        )
    quantity = UFF_QUANTITIES[types.pop()]
    nodes = sorted({s["rsp_node"] for s in frfs} | {s["ref_node"] for s in frfs})
    responses = sorted({nodes.index(s["rsp_node"]) + 1 for s in frfs})
    forces = sorted({nodes.index(s["ref_node"]) + 1 for s in frfs})
    F = frfs[0]["num_pts"]
    H = np.full((len(responses), len(forces), F), np.nan + 0j)
    coherence = np.full(H.shape, np.nan)
    factor, units, notes = _frf_units(frfs[0], quantity)
    for records, out in ((frfs, H), (cohs, coherence)):
        for s in records:
            dof = {node: i + 1 for i, node in enumerate(nodes)}
            if dof.get(s["rsp_node"]) not in responses or dof.get(s["ref_node"]) not in forces:
                continue  # a coherence of a pair without an FRF
            r, q = responses.index(dof[s["rsp_node"]]), forces.index(dof[s["ref_node"]])
            sign = np.sign(s.get("rsp_dir", 1) or 1) * np.sign(s.get("ref_dir", 1) or 1)
            out[r, q] = sign * factor * np.asarray(s["data"]) if out is H else np.asarray(s["data"], float).real
    if np.any(np.isnan(H)):
        raise RecordingError(
            f"{path.name}: not every response has an FRF for every reference "
            f"(responses at nodes {[nodes[d - 1] for d in responses]}, references at {[nodes[d - 1] for d in forces]})"
        )
    return FrfData(
        frequency_hz=_frequency_axis(frfs[0]),
        H=H,
        quantity=quantity,
        response_dof=np.array(responses),
        force_dof=np.array(forces),
        coherence=None if np.any(np.isnan(coherence)) else coherence,
        units=units,
        notes=tuple(notes) + tuple(f"node {node} is DOF {i + 1}" for i, node in enumerate(nodes)),
        path=path,
    )
