"""Recordings: loading, validating and saving the measured signals of a chain.

A recording holds, on a uniform time grid ``t`` [s], the forces ``u1..un`` [N] applied
to the n masses and their accelerations ``a1..an`` [m/s^2], optionally their velocities
``v1..vn`` [m/s] and displacements ``x1..xn`` [m]. Rigs that record velocity only (a laser
vibrometer) or displacement only (an encoder, a displacement transducer) may omit ``a``:
the acceleration the estimator needs is then derived by :func:`accelerations`.

File formats (the same column / array names in both):

* ``.csv`` — one header line ``t,u1,..,un,a1,..,an[,v1,..,vn][,x1,..,xn]`` (any column order,
  names exact), one sample per line, comma separated, SI units. Blank lines and lines
  starting with ``#`` are ignored.
* ``.npz`` — one 1-D array per name (``numpy.savez``).

Validation (every failure raises :class:`RecordingError` with a one-line message naming
the problem and, where it has one, the offending line / column):

* extension ``.csv`` or ``.npz``; the file exists and is not empty;
* columns ``t`` and ``u1..un`` present, plus ``a1..an``, ``v1..vn`` and/or ``x1..xn`` for
  the *same* n, numbered 1..n without holes; no other columns;
* every row has as many fields as the header and every field parses as a number;
* no NaN or inf anywhere;
* at least :data:`MIN_SAMPLES` samples; time strictly increasing and uniform:
  ``max |t[k+1] - t[k] - dt| <= UNIFORM_RTOL * dt`` with ``dt = (t[-1] - t[0]) / (T - 1)``
  (0.1 %: enough for times printed with 6 significant digits, far below any real
  sampling jitter that would matter to the estimator).
"""

from __future__ import annotations

import math
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .messages import listing, quote, quote_path

__all__ = [
    "MIN_SAMPLES",
    "UNIFORM_RTOL",
    "Recording",
    "RecordingError",
    "accelerations",
    "derivative",
    "derivative_weights",
    "motion",
    "load_recording",
    "save_recording",
]

#: Fewest samples a recording may have (the estimator's quadrature needs a few).
MIN_SAMPLES = 8
#: Tolerated relative deviation of every sample interval from the mean interval.
UNIFORM_RTOL = 1e-3
#: Sampling intervals a recording may have [s]: 1 ns (1 GHz) to 1 h.
DT_RANGE_S = (1e-9, 3600.0)
#: Lines of a CSV file parsed at a time (the reader's memory beyond the data is about this).
CSV_CHUNK_LINES = 8192
#: Points of the interpolating polynomial :func:`accelerations` differentiates.
DEFAULT_DIFF_POINTS = 5
#: File suffixes :func:`load_recording` reads (lower case); folders are searched for these.
SUFFIXES = (".csv", ".npz")

_NAME = re.compile(r"^([uavx])([1-9][0-9]*)$")
_KIND = {"u": "force", "a": "acceleration", "v": "velocity", "x": "displacement"}
#: Motion signals a recording may carry, in the order the estimator prefers them.
MOTIONS = ("a", "v", "x")


class RecordingError(ValueError):
    """A recording that cannot be used; ``str(err)`` is one line naming the problem."""

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


@dataclass
class Recording:
    """Sampled signals of an n-DOF chain on a uniform time grid.

    Parameters
    ----------
    t : (T,) sample times [s], strictly increasing and uniform.
    u : (T, n) forces applied to each mass [N].
    a : (T, n) accelerations of each mass [m/s^2], or None.
    x : (T, n) displacements of each mass [m], or None.
    v : (T, n) velocities of each mass [m/s], or None (at least one of a, v, x).
    dt : sampling interval [s]; computed from ``t`` when None.
    n : number of degrees of freedom; taken from ``u`` when None.
    path : file the recording was read from, if any.

    The constructor validates (see the module docstring) and raises
    :class:`RecordingError`.
    """

    t: np.ndarray
    u: np.ndarray
    a: np.ndarray | None = None
    x: np.ndarray | None = None
    dt: float | None = None
    n: int | None = None
    path: Path | None = None
    v: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1:
            raise RecordingError(f"t must be 1-D, got shape {t.shape}")
        T = t.size
        if T == 0:
            raise RecordingError("empty recording: no samples")
        u = _as_2d("u", self.u, T)
        n = u.shape[1]
        if n < 1:
            raise RecordingError("no force columns u1..un")
        a = None if self.a is None else _as_2d("a", self.a, T)
        x = None if self.x is None else _as_2d("x", self.x, T)
        v = None if self.v is None else _as_2d("v", self.v, T)
        if a is None and x is None and v is None:
            raise RecordingError("need accelerations a1..an, velocities v1..vn or displacements x1..xn")
        for name, arr in (("a", a), ("v", v), ("x", x)):
            if arr is not None and arr.shape[1] != n:
                raise RecordingError(f"mismatched n: {n} force columns but {arr.shape[1]} {_KIND[name]} columns")
        if self.n is not None and int(self.n) != n:
            raise RecordingError(f"mismatched n: n = {self.n} given but u has {n} columns")
        for name, arr in (("t", t[:, None]), ("u", u), ("a", a), ("v", v), ("x", x)):
            if arr is not None:
                _check_finite(name, arr, t)
        dt = _check_time(t)
        if self.dt is not None and not math.isclose(float(self.dt), dt, rel_tol=UNIFORM_RTOL):
            raise RecordingError(f"dt = {self.dt} given but the time column has dt = {dt:.9g} s")
        self.t, self.u, self.a, self.v, self.x = t, u, a, v, x
        self.dt, self.n = dt, n
        self.path = None if self.path is None else Path(self.path)

    @property
    def duration_s(self) -> float:
        """Recorded time span ``t[-1] - t[0]`` [s]."""
        return float(self.t[-1] - self.t[0])

    @property
    def fs_hz(self) -> float:
        """Sampling rate 1/dt [Hz]."""
        return 1.0 / float(self.dt)

    def columns(self) -> dict[str, np.ndarray]:
        """The recording as named 1-D columns ``t, u1..un[, a1..an][, x1..xn]``."""
        out: dict[str, np.ndarray] = {"t": self.t}
        for key, arr in (("u", self.u), ("a", self.a), ("v", self.v), ("x", self.x)):
            if arr is not None:
                for i in range(self.n):
                    out[f"{key}{i + 1}"] = arr[:, i]
        return out


def _as_2d(name: str, value, T: int) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] != T:
        raise RecordingError(f"{name} has shape {arr.shape}, expected ({T}, n) to match t")
    return arr


def _check_finite(name: str, arr: np.ndarray, t: np.ndarray, lines: np.ndarray | None = None) -> None:
    bad = ~np.isfinite(arr)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        what = "NaN" if np.isnan(arr[row, col]) else "inf"
        column = name if name == "t" else f"{name}{col + 1}"
        where = f"line {lines[row]}" if lines is not None else f"sample {row}"
        raise RecordingError(f"column {column} has {what} at {where} ({int(bad.sum())} non-finite values)")


def _check_time(t: np.ndarray, lines: np.ndarray | None = None) -> float:
    T = t.size
    if T < MIN_SAMPLES:
        raise RecordingError(f"too short: {T} samples, need at least {MIN_SAMPLES}")
    d = np.diff(t)
    where = (lambda k: f"line {lines[k + 1]}") if lines is not None else (lambda k: f"sample {k + 1}")
    if np.any(d <= 0):
        k = int(np.argmax(d <= 0))
        raise RecordingError(f"time is not increasing at {where(k)} (t = {t[k + 1]:.9g} s after {t[k]:.9g} s)")
    with np.errstate(over="ignore"):
        dt = float((t[-1] - t[0]) / (T - 1))
    if not DT_RANGE_S[0] <= dt <= DT_RANGE_S[1]:
        raise RecordingError(
            f"sampling interval {dt:.3g} s outside {DT_RANGE_S[0]:g} .. {DT_RANGE_S[1]:g} s "
            "(1 GHz to one sample an hour)"
        )
    dev = np.abs(d - dt)
    if dev.max() > UNIFORM_RTOL * dt:
        k = int(np.argmax(dev))
        raise RecordingError(
            f"non-uniform time: step {d[k]:.9g} s at {where(k)} differs from the mean step {dt:.9g} s "
            f"by more than {UNIFORM_RTOL:.1%}"
        )
    return dt


def _group_columns(names: list[str], source: str) -> tuple[int, dict[str, list[int]]]:
    """Map the column names to their position; return n and {'t': [pos], 'u': [...], ...}.

    Checked before anything is allocated from them: an index above the number of columns
    (``u10000000`` in a header of five) is refused at once."""
    seen: set[str] = set()
    groups: dict[str, dict[int, int]] = {"u": {}, "a": {}, "v": {}, "x": {}}
    tpos = None
    for pos, raw in enumerate(names):
        name = raw.strip()
        if name in seen:
            raise RecordingError(f"{source}: duplicate column {quote(name)}")
        seen.add(name)
        if name == "t":
            tpos = pos
            continue
        m = _NAME.match(name)
        if not m:
            raise RecordingError(
                f"{source}: unexpected column {quote(name)} (expected t, u1..un, a1..an, v1..vn, x1..xn)"
            )
        if len(m.group(2)) > 9 or int(m.group(2)) > len(names):
            raise RecordingError(f"{source}: column {quote(name)} numbers a DOF beyond the file's {len(names)} columns")
        groups[m.group(1)][int(m.group(2))] = pos
    if tpos is None:
        raise RecordingError(f"{source}: missing column 't'")
    if not groups["u"]:
        raise RecordingError(f"{source}: missing force columns u1..un")
    n = max(groups["u"])
    if not groups["a"] and not groups["v"] and not groups["x"]:
        raise RecordingError(f"{source}: missing columns a1..a{n} (or velocities v1..v{n}, or displacements x1..x{n})")
    for key, cols in groups.items():
        if not cols:
            continue
        top = max(cols)
        if top != n and key != "u":
            raise RecordingError(
                f"{source}: mismatched n: force columns u1..u{n} but {_KIND[key]} columns up to {key}{top}"
            )
        missing = [f"{key}{i}" for i in range(1, n + 1) if i not in cols]
        if missing:
            raise RecordingError(f"{source}: missing column{'s' if len(missing) > 1 else ''} {listing(missing)}")
    out = {"t": [tpos]}
    for key, cols in groups.items():
        if cols:
            out[key] = [cols[i] for i in range(1, n + 1)]
    return n, out


def _csv_lines(fh, first_lineno: int):
    """(line number, text) of the data lines from ``first_lineno`` on: blank lines and ``#``
    comments skipped, the file read line by line."""
    for lineno, line in enumerate(fh, start=first_lineno):
        s = line.strip()
        if s and not s.startswith("#"):
            yield lineno, s


def _csv_header(fh, source: str) -> tuple[list[str], int]:
    for lineno, s in _csv_lines(fh, 1):
        return [c.strip() for c in s.split(",")], lineno
    raise RecordingError(f"{source}: empty file")


def _parse_chunk(texts: list[str], linenos: list[int], header: list[str], source: str) -> np.ndarray:
    """One chunk of data lines as a (rows, columns) array; on a bad line, the one-line error
    naming it (found line by line, only then)."""
    try:
        return np.loadtxt(texts, delimiter=",", ndmin=2, dtype=float, comments=None)
    except ValueError:
        pass
    width = len(header)
    for text, lineno in zip(texts, linenos):
        fields = text.split(",")
        if len(fields) != width:
            raise RecordingError(f"{source}: ragged row at line {lineno}: {len(fields)} fields, header has {width}")
        for col, field in enumerate(fields):
            try:
                np.loadtxt([field], delimiter=",", dtype=float, comments=None)
            except ValueError:
                raise RecordingError(
                    f"{source}: line {lineno}, column {quote(header[col])}: "
                    f"cannot parse {quote(field.strip())} as a number"
                ) from None
    raise RecordingError(f"{source}: unreadable data between lines {linenos[0]} and {linenos[-1]}")  # pragma: no cover


def _read_csv(path: Path) -> Recording:
    """Read the CSV chunk by chunk: the memory is the data array (8 bytes a value) plus one
    chunk of lines, never the whole text split into Python strings."""
    chunks: list[np.ndarray] = []
    line_numbers: list[np.ndarray] = []
    try:
        with open(path, encoding="utf-8-sig") as fh:
            header, header_line = _csv_header(fh, path.name)
            n, groups = _group_columns(header, path.name)
            texts: list[str] = []
            linenos: list[int] = []
            for lineno, text in _csv_lines(fh, header_line + 1):
                texts.append(text)
                linenos.append(lineno)
                if len(texts) == CSV_CHUNK_LINES:
                    chunks.append(_parse_chunk(texts, linenos, header, path.name))
                    line_numbers.append(np.asarray(linenos, dtype=np.int64))
                    texts, linenos = [], []
            if texts:
                chunks.append(_parse_chunk(texts, linenos, header, path.name))
                line_numbers.append(np.asarray(linenos, dtype=np.int64))
    except UnicodeDecodeError:
        raise RecordingError(f"{path.name}: not a text CSV file (cannot decode as UTF-8)") from None
    if not chunks:
        raise RecordingError(f"{path.name}: no data rows after the header (line {header_line})")
    data = chunks[0] if len(chunks) == 1 else np.concatenate(chunks)
    del chunks
    return _from_table(path, data, groups, np.concatenate(line_numbers))


def _from_table(path: Path, data: np.ndarray, groups: dict[str, list[int]], lines: np.ndarray | None) -> Recording:
    t = data[:, groups["t"][0]]
    parts = {key: data[:, cols] for key, cols in groups.items() if key != "t"}
    for key, arr in (("t", t[:, None]), *parts.items()):
        try:
            _check_finite(key, arr, t, lines)
        except RecordingError as err:
            raise RecordingError(f"{path.name}: {err}") from None
    try:
        _check_time(t, lines)
        return Recording(t=t, u=parts["u"], a=parts.get("a"), v=parts.get("v"), x=parts.get("x"), path=path)
    except RecordingError as err:
        raise RecordingError(f"{path.name}: {err}") from None


def _npz_members(path: Path) -> dict[str, tuple[tuple[int, ...], np.dtype]]:
    """Name -> (shape, dtype) of every array of an npz, read from the headers only: nothing is
    decompressed before the names, shapes and types are known to be right."""
    if not zipfile.is_zipfile(path):
        raise RecordingError(f"{path.name}: not a readable .npz file (not a zip archive)")
    members = {}
    try:
        with zipfile.ZipFile(path) as z:
            for info in z.infolist():
                if not info.filename.endswith(".npy"):
                    raise RecordingError(f"{path.name}: member {quote(info.filename)} is not an .npy array")
                with z.open(info) as fh:
                    version = np.lib.format.read_magic(fh)
                    read_header = {(1, 0): np.lib.format.read_array_header_1_0}.get(
                        version, np.lib.format.read_array_header_2_0
                    )
                    shape, _, dtype = read_header(fh)
                    declared = math.prod(shape) * dtype.itemsize
                    if declared > info.file_size:
                        raise RecordingError(
                            f"{path.name}: array {quote(info.filename)} declares {declared} bytes "
                            f"but holds at most {info.file_size} (truncated or corrupt)"
                        )
                members[info.filename[: -len(".npy")]] = (shape, dtype)
    except RecordingError:
        raise
    except (zipfile.BadZipFile, ValueError, OSError, EOFError, NotImplementedError) as err:
        raise RecordingError(f"{path.name}: not a readable .npz file ({type(err).__name__})") from None
    return members


def _read_npz(path: Path) -> Recording:
    members = _npz_members(path)
    if not members:
        raise RecordingError(f"{path.name}: empty file (no arrays)")
    names = list(members)
    n, groups = _group_columns(names, path.name)
    for name, (shape, dtype) in members.items():
        if len(shape) != 1:
            raise RecordingError(f"{path.name}: array {quote(name)} has shape {shape}, expected 1-D")
        if dtype.kind not in "fiu":
            raise RecordingError(f"{path.name}: array {quote(name)} is not real numeric (dtype {dtype})")
    T = members["t"][0][0]
    for name, (shape, _) in members.items():
        if shape[0] != T:
            raise RecordingError(f"{path.name}: ragged arrays: {quote(name)} has {shape[0]} samples, t has {T}")
    if T == 0:
        raise RecordingError(f"{path.name}: empty file (no samples)")
    data = np.empty((T, len(names)))
    try:
        with np.load(path, allow_pickle=False) as z:
            for col, name in enumerate(names):
                data[:, col] = z[name]
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as err:
        raise RecordingError(f"{path.name}: not a readable .npz file ({type(err).__name__})") from None
    return _from_table(path, data, groups, None)


def load_recording(path: str | Path) -> Recording:
    """Read and validate a ``.csv`` or ``.npz`` recording.

    Parameters
    ----------
    path : file to read.

    Returns
    -------
    Recording with ``path`` set.

    Raises
    ------
    RecordingError
        With a one-line message naming the problem (see the module docstring).
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in (".csv", ".npz"):
        raise RecordingError(f"{path.name}: unknown extension {path.suffix!r} (expected .csv or .npz)")
    if not path.exists():
        raise RecordingError(f"no such file: {quote_path(path)}")
    if path.is_dir():
        raise RecordingError(f"is a directory, not a recording: {quote_path(path)}")
    if path.stat().st_size == 0:
        raise RecordingError(f"{path.name}: empty file")
    return _read_csv(path) if ext == ".csv" else _read_npz(path)


def save_recording(path: str | Path, rec: Recording) -> Path:
    """Write ``rec`` to ``path`` (``.csv`` with 17 significant digits, or ``.npz``).

    Returns the path written. ``load_recording(save_recording(p, rec))`` reproduces
    ``rec`` exactly for ``.npz`` and to the last bit for ``.csv`` (``%.17g``).
    """
    path = Path(path)
    ext = path.suffix.lower()
    cols = rec.columns()
    if ext == ".npz":
        with open(path, "wb") as fh:  # np.savez would append .npz to other spellings
            np.savez(fh, **cols)
    elif ext == ".csv":
        table = np.column_stack(list(cols.values()))
        np.savetxt(path, table, delimiter=",", header=",".join(cols), comments="", fmt="%.17g")
    else:
        raise RecordingError(f"{path.name}: unknown extension {path.suffix!r} (expected .csv or .npz)")
    return path


def derivative_weights(points: int, order: int, at: int) -> np.ndarray:
    """Weights ``w`` with ``f^(order)(s_at) ~= h^-order * sum_m w[m] f(s_m)``.

    Exact derivative of the degree ``points-1`` polynomial interpolating ``f`` at the
    unit-spaced nodes ``s_m = m`` (m = 0..points-1), evaluated at node ``at``.
    """
    if not 0 <= at < points or order >= points:
        raise ValueError("need 0 <= at < points and order < points")
    s = np.arange(points, dtype=float) - at
    # Row q of V: s^q / q!; the weights solve V w = e_order (moment conditions).
    V = np.array([s**q / math.factorial(q) for q in range(points)])
    rhs = np.zeros(points)
    rhs[order] = 1.0
    return np.linalg.solve(V, rhs)


def derivative(x: np.ndarray, dt: float, order: int = 2, points: int = DEFAULT_DIFF_POINTS) -> np.ndarray:
    """Time derivative of order ``order`` of uniformly sampled columns by polynomial
    interpolation.

    At every sample, the degree ``points-1`` polynomial through ``points`` consecutive
    samples (centred on the sample; shifted inwards at both ends) is differentiated
    exactly. For odd ``points`` the interior stencil is the symmetric central
    difference, of accuracy ``O(dt^(points-1))`` for the second derivative and
    ``O(dt^(points-1))`` for the first; the ``(points-1)/2`` samples at each end use
    one-sided stencils, one order less accurate.

    Parameters
    ----------
    x : (T,) or (T, n) samples.
    dt : sampling interval [s].
    order : 1 or 2 (or higher, below ``points``).
    points : stencil width (> order, >= 3).
    """
    x = np.asarray(x, dtype=float)
    one = x.ndim == 1
    X = x[:, None] if one else x
    T = X.shape[0]
    if points < 3 or points <= order:
        raise ValueError("points must be >= 3 and > order")
    if T < points:
        raise RecordingError(f"too short to differentiate: {T} samples, need {points}")
    half = points // 2
    out = np.empty_like(X)
    w = derivative_weights(points, order, half)
    interior = slice(half, T - (points - 1 - half))
    acc = np.zeros((T - points + 1, X.shape[1]))
    for m in range(points):
        acc += w[m] * X[m : T - points + 1 + m]
    out[interior] = acc
    for k in range(half):  # left end: nodes 0..points-1, evaluated at k
        out[k] = derivative_weights(points, order, k) @ X[:points]
    for k in range(points - 1 - half):  # right end
        at = points - 1 - k
        out[T - 1 - k] = derivative_weights(points, order, at) @ X[T - points :]
    out /= dt**order
    return out[:, 0] if one else out


def second_derivative(x: np.ndarray, dt: float, points: int = DEFAULT_DIFF_POINTS) -> np.ndarray:
    """:func:`derivative` of order 2 (accelerations from displacements)."""
    return derivative(x, dt, 2, points)


def accelerations(rec: Recording, points: int = DEFAULT_DIFF_POINTS) -> np.ndarray:
    """Accelerations (T, n) [m/s^2] the estimator needs.

    The measured ``a`` when the recording has it; otherwise the exact first derivative of
    the ``points``-point interpolating polynomial of the velocities ``v``, or its second
    derivative of the displacements ``x`` (see :func:`derivative`): with the default 5
    points, ``(v[k-2] - 8 v[k-1] + 8 v[k+1] - v[k+2]) / (12 dt)`` and
    ``(-x[k-2] + 16 x[k-1] - 30 x[k] + 16 x[k+1] - x[k+2]) / (12 dt^2)``, error ``dt^4 x^(6) / 90``
    for the second (relative error 1.1e-4 for a sine at 1/20 of the sampling rate, 1.7e-3
    at 1/10).
    Differentiation amplifies measurement noise: white displacement noise of standard
    deviation s becomes acceleration noise of ``3.1 s / dt^2`` (5 points), white velocity
    noise ``0.95 s / dt`` — at 1 kHz a 1 um displacement noise gives 3.1 m/s^2. The
    identification and the diagnosis take that noise into account (:mod:`algid.noise`).
    """
    if rec.a is not None:
        return rec.a
    if rec.v is not None:
        return derivative(rec.v, rec.dt, 1, points)
    return second_derivative(rec.x, rec.dt, points)


def motion(rec: Recording) -> tuple[str, np.ndarray]:
    """The measured motion the estimator's accelerations come from: ``("acceleration", a)``,
    ``("velocity", v)`` or ``("displacement", x)``, in that order of preference."""
    if rec.a is not None:
        return "acceleration", rec.a
    if rec.v is not None:
        return "velocity", rec.v
    return "displacement", rec.x
