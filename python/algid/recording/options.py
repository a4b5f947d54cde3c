"""The command-line options that say how to read a recording, shared by ``algid identify``
and ``algid diagnose``: which column is which signal, their units, the sampling rate of a
file without a time column, the HDF5 group."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from ..messages import quote, quote_path
from .core import RecordingError

#: CLI option -> role of the columns it names.
_ROLE_OPTIONS = {"time": "t", "force": "u", "accel": "a", "velocity": "v", "displacement": "x"}


def add_recording_options(parser) -> None:
    """Register the recording options on an ``argparse`` (sub)parser."""
    g = parser.add_argument_group(
        "reading the recording",
        "Columns are found by their names (t or time, u1..un, a1..an, v1..vn, x1..xn, each with an "
        "optional unit: 'Time [s]', 'a1 (m/s^2)'); these options name them otherwise.",
    )
    g.add_argument("--time", metavar="COL", help="the time column")
    g.add_argument("--force", metavar="COLS", help="the force columns of DOF 1..n, comma-separated")
    g.add_argument("--accel", metavar="COLS", help="the acceleration columns, comma-separated")
    g.add_argument("--velocity", metavar="COLS", help="the velocity columns, comma-separated")
    g.add_argument("--displacement", metavar="COLS", help="the displacement columns, comma-separated")
    g.add_argument(
        "--columns",
        type=Path,
        metavar="JSON",
        help='a JSON file mapping roles to columns, e.g. {"t": "Time", "u": ["F"], "a": ["acc1", "acc2"]}',
    )
    g.add_argument(
        "--units",
        metavar="ROLE=UNIT[,ROLE=UNIT]",
        help="units of the signals, overriding the header, e.g. force=V,displacement=V; "
        "mm, um, g, kN, ms and the like are converted to SI, other units (V, counts) kept as labels",
    )
    rate = g.add_mutually_exclusive_group()
    rate.add_argument(
        "--rate", type=float, metavar="HZ", help="sampling rate, for a file without a time column or to replace it"
    )
    rate.add_argument(
        "--dt", type=float, metavar="S", help="sampling interval, for a file without a time column or to replace it"
    )
    g.add_argument("--group", metavar="NAME", help="HDF5 group holding the datasets (default: the root)")


def _mapping_file(path: Path) -> dict:
    try:
        mapping = json.loads(path.read_text(encoding="utf-8"))
    except OSError as err:
        raise RecordingError(f"--columns: cannot read {quote_path(path)} ({err.strerror or err})") from None
    except (ValueError, UnicodeDecodeError) as err:
        raise RecordingError(f"--columns: {quote_path(path)} is not JSON ({err})") from None
    if not isinstance(mapping, dict):
        raise RecordingError(f"--columns: {quote_path(path)} must hold a JSON object (role -> column names)")
    return mapping


def _units(text: str) -> dict[str, str]:
    out = {}
    for item in text.split(","):
        role, sep, unit = item.partition("=")
        if not sep or not role.strip() or not unit.strip():
            raise RecordingError(f"--units: expected ROLE=UNIT, got {quote(item)}")
        out[role.strip()] = unit.strip()
    return out


def _interval(args) -> float | None:
    value, flag = (args.rate, "--rate") if args.rate is not None else (args.dt, "--dt")
    if value is None:
        return None
    if not math.isfinite(value) or value <= 0:
        raise RecordingError(f"{flag} must be a positive number, got {value}")
    return 1.0 / value if flag == "--rate" else value


def recording_options(args) -> dict:
    """The keyword arguments of :func:`algid.recording.load_recording` the options give."""
    columns = _mapping_file(args.columns) if args.columns is not None else {}
    for option, role in _ROLE_OPTIONS.items():
        value = getattr(args, option)
        if value is not None:
            columns[role] = [name.strip() for name in value.split(",")]
    return {
        "columns": columns or None,
        "units": _units(args.units) if args.units else None,
        "dt": _interval(args),
        "group": args.group,
    }


def print_notes(rec, command: str, quiet: bool = False) -> None:
    """The recording's notes (ignored columns, conversions) on stderr, one line each."""
    if not quiet:
        for note in rec.notes:
            print(f"algid {command}: note: {note}", file=sys.stderr)
