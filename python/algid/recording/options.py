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


#: The help of the RECORDING argument of ``algid identify`` and ``algid diagnose``.
RECORDING_HELP = (
    "CSV/TSV/TXT (optionally .gz, .bz2, .xz, .zip), .npz, HDF5 or UFF 58 with time, forces u1..un and "
    "accelerations a1..an (or velocities v1..vn, displacements x1..xn)"
)


def known_units() -> str:
    """``"force N, kN, mN, lbf; acceleration m/s^2, ..., g; ...; raw V, mV, uV, counts"``."""
    from .units import LABELS, TO_SI

    roles = "; ".join(f"{role} {', '.join(units)}" for role, units in TO_SI.items())
    return f"{roles}; raw (kept as labels) {', '.join(LABELS)}"


def add_recording_options(parser) -> None:
    """Register the recording options on an ``argparse`` (sub)parser."""
    g = parser.add_argument_group(
        "reading the recording",
        "Columns are found by their names (t or time, u1..un, a1..an, v1..vn, x1..xn, each with an "
        "optional unit: 'Time [s]', 'a1 (m/s^2)'); these options name them otherwise. A column without "
        f"a unit is taken as SI (with a note). Known units: {known_units()}.",
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
        help="units of the signals, overriding the header, e.g. acceleration=g,force=kN; the known units "
        "are converted to SI, raw units (V, counts) kept as labels, any other name is an error unless "
        "declared a label (force=lbs:label)",
    )
    rate = g.add_mutually_exclusive_group()
    rate.add_argument(
        "--rate", type=float, metavar="HZ", help="sampling rate, for a file without a time column or to replace it"
    )
    rate.add_argument(
        "--dt", type=float, metavar="S", help="sampling interval, for a file without a time column or to replace it"
    )
    g.add_argument("--group", metavar="NAME", help="HDF5 group holding the datasets (default: the root)")


def mapping_file(path: Path) -> dict:
    """The role -> column names mapping a ``--columns`` JSON file holds."""
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


def _interval(rate: float | None, dt: float | None) -> float | None:
    if rate is not None and dt is not None:
        raise RecordingError("give the sampling rate or the interval, not both (--rate HZ or --dt S)")
    value, flag = (rate, "--rate") if rate is not None else (dt, "--dt")
    if value is None:
        return None
    value = float(value)
    if not math.isfinite(value) or value <= 0:
        raise RecordingError(f"{flag} must be a positive number, got {value}")
    return 1.0 / value if flag == "--rate" else value


def _names(value) -> list[str]:
    """``"F1,F2"`` or ``["F1", "F2"]`` -> ``["F1", "F2"]``."""
    items = value.split(",") if isinstance(value, str) else list(value)
    return [str(name).strip() for name in items]


#: The keywords :func:`reading_options` takes (the options of :func:`add_recording_options`).
READING = ("time", *list(_ROLE_OPTIONS)[1:], "columns", "units", "rate", "dt", "group")


def reading_options(
    time=None,
    force=None,
    accel=None,
    velocity=None,
    displacement=None,
    columns=None,
    units=None,
    rate=None,
    dt=None,
    group=None,
) -> dict:
    """The keyword arguments of :func:`algid.recording.load_recording` that the command line's
    options give, as the options are written: ``force="F1,F2"`` (or a list), ``accel``,
    ``velocity``, ``displacement``, ``time`` column names; ``columns`` a role -> names mapping
    or the path of a JSON file holding one; ``units`` ``"acceleration=g,force=kN"`` or a dict;
    ``rate`` [Hz] or ``dt`` [s]; ``group`` the HDF5 group."""
    mapping = dict(columns) if isinstance(columns, dict) else mapping_file(Path(columns)) if columns else {}
    named = {"time": time, "force": force, "accel": accel, "velocity": velocity, "displacement": displacement}
    for option, value in named.items():
        if value is not None:
            mapping[_ROLE_OPTIONS[option]] = _names(value)
    return {
        "columns": mapping or None,
        "units": (_units(units) if isinstance(units, str) else dict(units)) if units else None,
        "dt": _interval(rate, dt),
        "group": group,
    }


def given_options(args) -> dict:
    """The reading options given on the command line, by keyword of :func:`reading_options`."""
    return {name: getattr(args, name) for name in READING if getattr(args, name, None) is not None}


def recording_options(args) -> dict:
    """The keyword arguments of :func:`algid.recording.load_recording` the parsed options give."""
    return reading_options(**given_options(args))


def print_notes(rec, command: str, quiet: bool = False) -> None:
    """The recording's notes (ignored columns, conversions) on stderr, one line each."""
    if not quiet:
        for note in rec.notes:
            print(f"algid {command}: note: {note}", file=sys.stderr)
