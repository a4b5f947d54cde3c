"""The recording: sampled signals of a chain on a uniform time grid, and their validation."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..messages import display
from .units import ROLES, SI_UNITS

#: Fewest samples a recording may have (the estimator's quadrature needs a few).
MIN_SAMPLES = 8
#: Tolerated relative deviation of every sample interval from the mean interval.
UNIFORM_RTOL = 1e-3
#: A time column read from a file whose steps deviate from their mean by at most this share of
#: it (a logger's rounding of its timestamps, or their jitter) is taken as uniform at the mean
#: step, with a note; beyond it the record is not uniform.
TIMESTAMP_JITTER = 0.1
#: Sampling intervals a recording may have [s]: 1 ns (1 GHz) to 1 h.
DT_RANGE_S = (1e-9, 3600.0)
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
    u : (T, n) forces applied to each mass [N, or ``units["force"]``]; None for a base-excited
        record without force (zero on every DOF).
    a : (T, n) accelerations of each mass [m/s^2, or ``units["acceleration"]``], or None.
    x : (T, n) displacements of each mass [m, or ``units["displacement"]``], or None.
    v : (T, n) velocities of each mass [m/s, or ``units["velocity"]``], or None (at least one of a, v, x).
    dt : sampling interval [s]; computed from ``t`` when None.
    n : number of degrees of freedom; taken from ``u`` when None.
    path : file the recording was read from, if any.
    units : unit label of each signal, by role (``time``, ``force``, ``acceleration``,
        ``velocity``, ``displacement``); SI for every role not given. Time is always in s;
        a label that is not SI (``"V"``, ``"counts"``) says what the numbers are.
    notes : what the reader did that the user should know (columns ignored, units converted).
    base : (T,) motion of the support (the left wall, ``x_0`` of eq. 1) of a base-excited
        record (a shake table), or None (the wall stands still); its kind is ``base_kind``:
        ``"a"`` acceleration, ``"v"`` velocity or ``"x"`` displacement, in SI units or in the
        unit of the DOFs' motion of the same kind.
    missing : (T,) bool or None: the instants whose missing samples the reader bridged
        (:mod:`.gaps`); :func:`algid.identify` leaves them out of its estimates.

    Raises
    ------
    RecordingError
        The constructor validates (see :mod:`algid.recording`).
    """

    t: np.ndarray
    u: np.ndarray
    a: np.ndarray | None = None
    x: np.ndarray | None = None
    dt: float | None = None
    n: int | None = None
    path: Path | None = None
    v: np.ndarray | None = None
    units: dict[str, str] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    base: np.ndarray | None = None
    base_kind: str = "a"
    missing: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1:
            raise RecordingError(f"t must be 1-D, got shape {t.shape}")
        T = t.size
        if T == 0:
            raise RecordingError("empty recording: no samples")
        a = None if self.a is None else _as_2d("a", self.a, T)
        x = None if self.x is None else _as_2d("x", self.x, T)
        v = None if self.v is None else _as_2d("v", self.v, T)
        if a is None and x is None and v is None:
            raise RecordingError("need accelerations a1..an, velocities v1..vn or displacements x1..xn")
        base = _base(self.base, self.base_kind, T)
        if self.u is None and base is None:
            raise RecordingError("no force columns u1..un (and no support motion a0 of a base-excited record)")
        u = (
            _as_2d("u", self.u, T)
            if self.u is not None
            else np.zeros((T, next(m for m in (a, v, x) if m is not None).shape[1]))
        )
        n = u.shape[1]
        if n < 1:
            raise RecordingError("no force columns u1..un")
        for name, arr in (("a", a), ("v", v), ("x", x)):
            if arr is not None and arr.shape[1] != n:
                raise RecordingError(f"mismatched n: {n} force columns but {arr.shape[1]} {ROLES[name]} columns")
        if self.n is not None and int(self.n) != n:
            raise RecordingError(f"mismatched n: n = {self.n} given but u has {n} columns")
        for name, arr in (("t", t[:, None]), ("u", u), ("a", a), ("v", v), ("x", x)):
            if arr is not None:
                check_finite(name, arr)
        if base is not None:
            check_finite(f"{self.base_kind}0", base[:, None])
        dt = check_time(t)
        if self.dt is not None and not math.isclose(float(self.dt), dt, rel_tol=UNIFORM_RTOL):
            raise RecordingError(f"dt = {self.dt} given but the time column has dt = {dt:.9g} s")
        self.t, self.u, self.a, self.v, self.x, self.base = t, u, a, v, x, base
        self.dt, self.n = dt, n
        self.path = None if self.path is None else Path(self.path)
        self.units = _unit_labels(self.units, self)
        self.notes = list(self.notes)
        if self.missing is not None:
            missing = np.asarray(self.missing, dtype=bool)
            if missing.shape != (T,):
                raise RecordingError(f"missing has shape {missing.shape}, expected ({T},) to match t")
            self.missing = missing if missing.any() else None

    @property
    def duration_s(self) -> float:
        """Recorded time span ``t[-1] - t[0]`` [s]."""
        return float(self.t[-1] - self.t[0])

    @property
    def fs_hz(self) -> float:
        """Sampling rate 1/dt [Hz]."""
        return 1.0 / float(self.dt)

    def columns(self) -> dict[str, np.ndarray]:
        """The recording as named 1-D columns ``t, u1..un[, a1..an][, v1..vn][, x1..xn]``;
        a base-excited record's support motion as ``a0`` (``v0``, ``x0``), its forces only on
        the DOFs that have one."""
        out: dict[str, np.ndarray] = {"t": self.t}
        if self.base is not None:
            out[f"{self.base_kind}0"] = self.base
        for key, arr in (("u", self.u), ("a", self.a), ("v", self.v), ("x", self.x)):
            if arr is not None:
                for i in range(self.n):
                    if key != "u" or self.base is None or np.any(arr[:, i] != 0.0):
                        out[f"{key}{i + 1}"] = arr[:, i]
        return out

    def is_si(self) -> bool:
        """Whether every signal is in SI units (N, m/s^2, m/s, m)."""
        return all(SI_UNITS[role] == label for role, label in self.units.items())

    @classmethod
    def from_frame(cls, frame, columns=None, units=None, dt: float | None = None) -> Recording:
        """A recording from a :class:`pandas.DataFrame`: column names as in a CSV header
        (``time``, ``u1 [N]``, ...), or mapped by ``columns``; see :func:`algid.recording.load_recording`."""
        from .frame import from_frame

        return from_frame(frame, columns=columns, units=units, dt=dt)

    def to_frame(self):
        """The recording as a :class:`pandas.DataFrame` with columns ``t, u1.., a1..``
        (:meth:`columns`); the units are in ``frame.attrs["units"]``."""
        from .frame import to_frame

        return to_frame(self)

    # ---- display: one-line repr, notebook table (algid.messages.display) -------------------------
    def _display_fields(self) -> dict:
        return display.recording_fields(self)

    __repr__ = display.Displayed.__repr__
    _repr_html_ = display.Displayed._repr_html_


def require(module: str, extra: str, what: str):
    """The optional module ``module``, or one line naming the extra that installs it."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise RecordingError(f"{what} need the {module} package: pip install 'algid[{extra}]'") from None


def _unit_labels(given: dict[str, str], rec: Recording) -> dict[str, str]:
    """The units of the roles the recording holds: given ones, else SI; time must be in s."""
    names = {ROLES[key]: key for key in ROLES}
    unknown = sorted(set(given) - set(names))
    if unknown:
        raise RecordingError(f"units: unknown role {unknown[0]!r} (expected {', '.join(names)})")
    if given.get("time", "s") != "s":
        raise RecordingError(f"units: time must be in s, got {given['time']!r} (convert t before)")
    return {role: str(given.get(role, SI_UNITS[role])) for role, key in names.items() if getattr(rec, key) is not None}


def _base(value, kind: str, T: int) -> np.ndarray | None:
    """The support motion (T,) of a base-excited record, or None."""
    if value is None:
        return None
    if kind not in ("a", "v", "x"):
        raise RecordingError(f"base_kind must be 'a', 'v' or 'x', got {kind!r}")
    arr = np.asarray(value, dtype=float)
    if arr.shape != (T,):
        raise RecordingError(f"{kind}0 has shape {arr.shape}, expected ({T},) to match t")
    return arr


def _as_2d(name: str, value, T: int) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] != T:
        raise RecordingError(f"{name} has shape {arr.shape}, expected ({T}, n) to match t")
    return arr


def check_finite(name: str, arr: np.ndarray, lines: np.ndarray | None = None) -> None:
    """Raise naming the first NaN or inf of the (T, n) signal ``name`` (its file line when known)."""
    bad = ~np.isfinite(arr)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        what = "NaN" if np.isnan(arr[row, col]) else "inf"
        column = name if name == "t" or name.endswith("0") else f"{name}{col + 1}"  # t, a0 (support)
        where = f"line {lines[row]}" if lines is not None else f"sample {row}"
        raise RecordingError(f"column {column} has {what} at {where} ({int(bad.sum())} non-finite values)")


def file_time(
    t: np.ndarray | None, dt: float | None, T: int, lines: np.ndarray | None = None
) -> tuple[np.ndarray, str]:
    """The uniform time grid of a file's record and the note that says how it was made: from
    ``dt`` [s] when given (``--rate``/``--dt``, over any time column: ``t0 + k dt``); from a
    time column whose steps vary by at most :data:`TIMESTAMP_JITTER` of their mean (rounding,
    timestamp jitter: the straight line through the timestamps); the column itself when it is uniform. Raises
    on a really non-uniform column, saying what to do."""
    if dt is not None:
        t0 = 0.0 if t is None else float(t[0])
        grid = t0 + float(dt) * np.arange(T)
        if t is None:
            return grid, f"no time column: t = k * {float(dt):.9g} s"
        mean = float((t[-1] - t[0]) / (T - 1)) if T > 1 else float("nan")
        return grid, f"time column replaced by t = t0 + k * {float(dt):.9g} s as given (its mean step {mean:.9g} s)"
    if t is None:
        raise RecordingError("no time column and no sampling interval given (--rate HZ or --dt S)")
    try:
        check_time(t, lines)
        return t, ""
    except RecordingError as err:
        if "non-uniform" not in str(err):
            raise
    step = float((t[-1] - t[0]) / (T - 1))
    dev = float(np.max(np.abs(np.diff(t) - step)))
    if dev > TIMESTAMP_JITTER * step:
        k = int(np.argmax(np.abs(np.diff(t) - step)))
        where = f"line {lines[k + 1]}" if lines is not None else f"sample {k + 1}"
        raise RecordingError(
            f"non-uniform time: step {t[k + 1] - t[k]:.9g} s at {where} is {100 * dev / step:.3g} % off the mean "
            f"step {step:.9g} s: resample the record to a uniform grid, or give --rate HZ (--dt S) to take its "
            "samples as uniform at that rate"
        )
    k = np.arange(T)
    step, t0 = np.polyfit(k, t - t[0], 1)  # the line through every timestamp
    return t[0] + t0 + step * k, (
        f"time steps vary by up to {100 * dev / step:.2g} % of their mean (rounded or jittered timestamps): "
        f"taken as uniform at {1.0 / step:.6g} Hz"
    )


def check_time(t: np.ndarray, lines: np.ndarray | None = None) -> float:
    """The sampling interval of ``t`` [s]; raise unless enough samples, increasing and uniform."""
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
