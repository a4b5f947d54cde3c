"""Recordings: loading, validating and saving the measured signals of a chain.

A recording holds, on a uniform time grid ``t`` [s], the forces ``u1..un`` applied to the n
masses and their accelerations ``a1..an``, optionally their velocities ``v1..vn`` and
displacements ``x1..xn``; in SI units (N, m/s^2, m/s, m) unless its ``units`` say otherwise.
Rigs that record velocity only (a laser vibrometer) or displacement only (an encoder) may
omit ``a``: the acceleration the estimator needs is then derived by :func:`accelerations`.

File formats (:func:`load_recording`), columns named the same way in all of them:

* delimited text ``.csv``, ``.tsv``, ``.txt``, also compressed (``.gz``, ``.bz2``, ``.xz``,
  a one-file ``.zip``): one header line, one sample per line; the delimiter (comma,
  semicolon, tab, ``|`` or blanks) and a decimal comma are detected; blank lines and lines
  starting with ``#`` are ignored (:mod:`algid.recording.text`);
* ``.npz``: one 1-D array per column (``numpy.savez``);
* ``.h5`` / ``.hdf5`` with ``pip install 'algid[hdf5]'``: one 1-D dataset per column
  (:mod:`algid.recording.hdf5`);
* ``.uff`` / ``.unv`` with ``pip install 'algid[uff]'``: UFF 58 time responses
  (:mod:`algid.recording.uff`);
* a :class:`pandas.DataFrame` (:meth:`Recording.from_frame`, :meth:`Recording.to_frame`).

Columns (:mod:`algid.recording.columns`): ``t`` or ``time``, ``u1..un``, ``a1..an``,
``v1..vn``, ``x1..xn`` in any order and case, each with an optional unit in brackets or
parentheses (``Time [s]``, ``a1 (m/s^2)``, ``x1[mm]``); or any names mapped to roles by
``columns``. pandas' index column and every other column are ignored and listed in
:attr:`Recording.notes`. Without a time column the sampling interval ``dt`` must be given.

Units (:mod:`algid.recording.units`): from the header or from ``units`` (``{"force": "V",
"displacement": "V"}``). Convertible units (mm, um, in, g, kN, lbf, ms, ...) are converted to
SI, with a note; a column without a unit is taken as SI, with a note; raw units (V, mV, counts)
and names declared ``UNIT:label`` are kept and carried as labels, and :func:`parameter_units`
gives the units the identified m, c, k are then in; any other unit name is an error naming the
nearest known ones.

Validation (every failure raises :class:`RecordingError` with a one-line message naming
the problem and, where it has one, the offending line / column):

* a known extension; the file exists and is not empty;
* a time column (or ``dt``) and ``u1..un`` present, plus ``a1..an``, ``v1..vn`` and/or
  ``x1..xn`` for the *same* n, numbered 1..n without holes; a base-excited record (a shake
  table) has its support's motion ``a0`` (or ``v0``, ``x0``) and forces on any DOFs, or none
  (:attr:`Recording.base`); no signal named twice; a DOF
  number beyond the number of columns is refused before anything is allocated;
* every row has as many fields as the header and every field read parses as a number;
* no NaN or inf in the time column; in a signal, gaps of up to
  :data:`~.gaps.MAX_GAP_SAMPLES` missing samples (NaN, inf) are bridged and noted
  (:mod:`algid.recording.gaps`), a longer gap or more than :data:`~.gaps.MAX_MISSING_SHARE` of
  the instants missing is an error;
* at least :data:`MIN_SAMPLES` samples; time strictly increasing and uniform:
  ``max |t[k+1] - t[k] - dt| <= UNIFORM_RTOL * dt`` with ``dt = (t[-1] - t[0]) / (T - 1)``
  (0.1 %). A file's time column whose steps vary by up to
  :data:`~.core.TIMESTAMP_JITTER` of a step (timestamps rounded to microseconds at 2048 Hz,
  a logger's jitter) is replaced by the straight line through it, with a note giving the
  rate; ``--rate``/``--dt`` replace any time column (:func:`.core.file_time`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..messages import quote_path
from .core import DT_RANGE_S, MIN_SAMPLES, MOTIONS, UNIFORM_RTOL, Recording, RecordingError
from .derivatives import (
    DEFAULT_DIFF_POINTS,
    accelerations,
    base_acceleration,
    derivative,
    derivative_weights,
    motion,
    second_derivative,
)
from .text import COMPRESSIONS, CSV_CHUNK_LINES, TEXT_SUFFIXES
from .units import SI_UNITS, parameter_unit_labels

__all__ = [
    "as_recording",
    "readable",
    "CSV_CHUNK_LINES",
    "DEFAULT_DIFF_POINTS",
    "DT_RANGE_S",
    "MIN_SAMPLES",
    "MOTIONS",
    "UNIFORM_RTOL",
    "Recording",
    "RecordingError",
    "accelerations",
    "base_acceleration",
    "derivative",
    "derivative_weights",
    "load_recording",
    "motion",
    "parameter_units",
    "save_recording",
    "second_derivative",
]

_OTHER_SUFFIXES = {".npz": "npz", ".h5": "hdf5", ".hdf5": "hdf5", ".uff": "uff", ".unv": "uff"}
EXTENSIONS = ", ".join([*TEXT_SUFFIXES, *_OTHER_SUFFIXES, *(f"{TEXT_SUFFIXES[0]}{c}" for c in COMPRESSIONS)])


def _format(path: Path) -> tuple[str, str | None]:
    """(format, compression) from the file's extensions."""
    suffixes = [s.lower() for s in path.suffixes[-2:]]
    compression = suffixes[-1] if suffixes and suffixes[-1] in COMPRESSIONS else None
    ext = (suffixes[-2] if len(suffixes) == 2 else "") if compression else (suffixes[-1] if suffixes else "")
    if ext in TEXT_SUFFIXES:
        return "text", compression
    if ext in _OTHER_SUFFIXES and compression is None:
        return _OTHER_SUFFIXES[ext], None
    raise RecordingError(f"{path.name}: unknown extension {''.join(path.suffixes[-2:])!r} (expected {EXTENSIONS})")


def readable(path) -> bool:
    """Whether :func:`load_recording` reads files named like ``path`` (by extension only)."""
    try:
        _format(Path(path))
    except RecordingError:
        return False
    return True


def as_recording(source, **reading) -> Recording:
    """``source`` itself when it is a :class:`Recording`, else :func:`load_recording` of it (a
    path or a DataFrame) read as the command line's options say: ``force="F1"``,
    ``accel="acc1"``, ``units="acceleration=g"``, ``rate=2048``... (the keywords of
    :func:`.options.reading_options`); a clear ``TypeError`` for anything else."""
    from .options import reading_options

    if isinstance(source, Recording):
        if any(value is not None for value in reading.values()):
            raise TypeError(f"{', '.join(reading)}: options for reading a file or a DataFrame, not a Recording")
        return source
    if isinstance(source, (str, os.PathLike)) or hasattr(source, "columns"):
        return load_recording(source, **reading_options(**reading))
    raise TypeError(f"expected a Recording, a path or a pandas DataFrame, got {type(source).__name__}")


def load_recording(
    source,
    columns: dict | None = None,
    units: dict | None = None,
    dt: float | None = None,
    group: str | None = None,
) -> Recording:
    """Read and validate a recording.

    Parameters
    ----------
    source : file to read (see the module docstring for the formats), or a DataFrame.
    columns : role -> column name(s), e.g. ``{"t": "Time", "u": ["F_shaker"], "a": ["acc1", "acc2"]}``;
        roles not named are found by their header names.
    units : role -> unit, overriding the header's, e.g. ``{"force": "V", "displacement": "V"}``.
    dt : sampling interval [s]: the time when the file has no time column (checked
        against it when it has one).
    group : HDF5 group holding the datasets (default the root).

    Returns
    -------
    Recording with ``path`` set, its ``units`` and its ``notes`` (ignored columns, conversions).

    Raises
    ------
    RecordingError
        With a one-line message naming the problem (see the module docstring).
    """
    if not isinstance(source, (str, Path)):
        return Recording.from_frame(source, columns=columns, units=units, dt=dt)
    path = Path(source)
    kind, compression = _format(path)
    if not path.exists():
        raise RecordingError(f"no such file: {quote_path(path)}")
    if path.is_dir():
        raise RecordingError(f"is a directory, not a recording: {quote_path(path)}")
    if path.stat().st_size == 0:
        raise RecordingError(f"{path.name}: empty file")
    if kind == "text":
        from .text import read_text

        return read_text(path, compression, columns=columns, units=units, dt=dt)
    if kind == "npz":
        from .npz import read_npz

        return read_npz(path, columns=columns, units=units, dt=dt)
    if kind == "hdf5":
        from .hdf5 import read_hdf5

        return read_hdf5(path, columns=columns, units=units, dt=dt, group=group)
    from .uff import read_uff

    return read_uff(path, columns=columns, units=units, dt=dt)


def _header_names(rec: Recording) -> list[str]:
    """Column names with the unit of every signal (``t [s]``, ``u1 [N]``, ``x1 [V]``)."""
    roles = {"u": "force", "a": "acceleration", "v": "velocity", "x": "displacement"}
    names = []
    for name in rec.columns():
        role = roles.get(name[0], "time")
        names.append(f"{name} [{rec.units.get(role, SI_UNITS[role])}]")  # a support motion of another kind: SI
    return names


def save_recording(path: str | Path, rec: Recording) -> Path:
    """Write ``rec`` to ``path`` (``.csv`` with 17 significant digits, or ``.npz``); the
    columns are named ``t, u1.., a1..`` with the unit of every signal (``t [s]``, ``u1 [V]``).

    Returns the path written. ``load_recording(save_recording(p, rec))`` reproduces
    ``rec`` exactly for ``.npz`` and to the last bit for ``.csv`` (``%.17g``), units included.
    """
    path = Path(path)
    ext = path.suffix.lower()
    cols = dict(zip(_header_names(rec), rec.columns().values()))
    if ext == ".npz":
        with open(path, "wb") as fh:  # np.savez would append .npz to other spellings
            np.savez(fh, **cols)
    elif ext == ".csv":
        table = np.column_stack(list(cols.values()))
        np.savetxt(path, table, delimiter=",", header=",".join(cols), comments="", fmt="%.17g")
    else:
        raise RecordingError(f"{path.name}: unknown extension {path.suffix!r} (expected .csv or .npz)")
    return path


def parameter_units(rec: Recording) -> dict[str, str]:
    """Unit labels ``{"m": .., "c": .., "k": ..}`` of the chain identified from ``rec``: kg,
    N s/m, N/m for SI data; ``V s^2/V``, ``V s/V``, ``V/V`` for forces and displacements in volts."""
    return parameter_unit_labels(rec.units, motion(rec)[0])
