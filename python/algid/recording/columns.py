"""Which column of a file is which signal: header names with their units, a user's mapping
of roles to column names, and the columns left out (listed in a note, never silently).

A header name is a signal name and an optional unit in brackets or parentheses:
``t``, ``time``, ``Time [s]``, ``t (s)``, ``u1 [N]``, ``a1 (m/s^2)``, ``x1[mm]`` (names
case-insensitive). pandas' index column (empty or ``Unnamed: 0``) and any column whose
name is not a signal name are ignored. A mapping ``{"t": "Time", "u": ["F_shaker"],
"a": ["acc_wing", "acc_payload"]}`` names the columns of some roles (``t``/``time``,
``u``/``force``, ``a``/``acceleration``, ``v``/``velocity``, ``x``/``displacement``), DOF by
DOF; the roles it does not name are found by their header names as above.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from ..messages import listing, quote
from .core import RecordingError
from .units import ROLES

_WITH_UNIT = re.compile(r"^(?P<name>.*?)\s*[\[(](?P<unit>[^\[\]()]*)[\])]\s*$")
_SIGNAL = re.compile(r"^([uavx])([1-9][0-9]*)$")
#: The support's motion of a base-excited record (a shake table): ``a0``, ``v0`` or ``x0``.
_BASE = re.compile(r"^([avx])0$")
TIME_NAMES = ("t", "time")
#: Role names a mapping (or ``--units``) may use -> array name.
ROLE_KEYS = {**{key: key for key in ROLES}, **{role: key for key, role in ROLES.items()}, "accel": "a"}


def split_name(raw: str) -> tuple[str, str | None]:
    """``"Time [s]"`` -> ``("Time", "s")``; ``"u1"`` -> ``("u1", None)``."""
    text = str(raw).strip()
    m = _WITH_UNIT.match(text)
    return (m.group("name"), m.group("unit").strip() or None) if m else (text, None)


def _is_index(name: str) -> bool:
    key = name.lower()
    return key in ("", "index") or key.startswith("unnamed:")


@dataclass
class Layout:
    """Where every signal is among a file's columns.

    ``groups`` maps ``"t"`` (absent when the file has no time column) to ``[position]``,
    ``"a"``, ``"v"``, ``"x"`` to the positions of DOF 1..n, ``"u"`` to those of the DOFs
    ``forced`` (all of them unless the record has a support motion) and ``"base"`` (a
    base-excited record) to the position of the support's motion ``a0``, ``v0`` or ``x0``,
    whose kind is ``base``; ``units`` gives the unit each of those columns declares (None
    when it declares none), ``names`` their names in the file (without the unit)."""

    n: int
    groups: dict[str, list[int]]
    units: dict[str, list[str | None]]
    ignored: list[str] = field(default_factory=list)
    base: str | None = None  #: "a", "v" or "x": the support motion's kind (None: no support motion)
    forced: list[int] = field(default_factory=list)  #: DOFs (0-based) with a force column
    names: dict[str, list[str]] = field(default_factory=dict)

    def positions(self) -> list[int]:
        """The positions read, in file order."""
        return sorted(p for cols in self.groups.values() for p in cols)

    def notes(self) -> list[str]:
        """The note listing the ignored columns (none when nothing was ignored)."""
        if not self.ignored:
            return []
        shown = [quote(name) + (" (index)" if _is_index(name) else "") for name in self.ignored]
        return [f"ignored column{'s' if len(shown) > 1 else ''} {listing(shown)}"]


def _find(name: str, stripped: list[str], bare: list[str]) -> int | None:
    """Position of the column called ``name`` (whole header, or its name without the unit,
    or that name in any case), or None."""
    for candidates, probe in ((stripped, name), (bare, name), ([b.lower() for b in bare], name.lower())):
        if probe in candidates:
            return candidates.index(probe)
    return None


def _mapped(names: list[str], columns: dict, source: str) -> dict[str, list[int]]:
    """Role -> positions named by a mapping (checked against the file's columns)."""
    stripped = [str(n).strip() for n in names]
    bare = [split_name(n)[0] for n in names]
    out: dict[str, list[int]] = {}
    used: set[int] = set()
    for role, wanted in columns.items():
        key = ROLE_KEYS.get(str(role).lower())
        if key is None:
            raise RecordingError(f"columns: unknown role {quote(role)} (expected {', '.join(ROLE_KEYS)})")
        wanted = [wanted] if isinstance(wanted, str) else list(wanted)
        if key == "t" and len(wanted) != 1:
            raise RecordingError(f"columns: time is one column, got {len(wanted)}")
        out[key] = []
        for name in wanted:
            name = str(name).strip()
            pos = _find(name, stripped, bare)
            if pos is None:
                known = listing([quote(n) for n in names])
                raise RecordingError(f"{source}: no column {quote(name)} for {ROLES[key]} (columns: {known})")
            if pos in used:
                raise RecordingError(f"columns: column {quote(name)} given for two signals")
            used.add(pos)
            out[key].append(pos)
    return out


def resolve(
    names: list[str], source: str, columns: dict | None = None, need_time: bool = True, declared: list | None = None
) -> Layout:
    """The :class:`Layout` of a file whose columns are ``names``.

    Checked before anything is allocated from them: an index above the number of columns
    (``u10000000`` in a header of five) is refused at once. ``need_time=False`` when the
    sampling interval is given, so the file may have no time column. ``declared`` gives the
    unit of a column whose name has none (an HDF5 attribute, a UFF field)."""
    mapped = _mapped(names, columns or {}, source)
    seen: set[str] = set()
    groups: dict[str, dict[int, int]] = {key: {} for key in "uavx"}
    base: dict[str, int] = {}
    ignored: list[str] = []
    tpos = mapped["t"][0] if "t" in mapped else None
    taken = {p for cols in mapped.values() for p in cols}
    for pos, raw in enumerate(names):
        name, _ = split_name(raw)
        key = name.lower()
        m = _SIGNAL.match(key)
        if key in seen and (m or key in TIME_NAMES or _BASE.match(key)):
            raise RecordingError(f"{source}: duplicate column {quote(name)}")
        seen.add(key)
        if pos in taken:
            continue
        if _BASE.match(key):
            base[key[0]] = pos
            continue
        if key in TIME_NAMES and "t" not in mapped:
            if tpos is not None:
                raise RecordingError(f"{source}: two time columns, {quote(names[tpos])} and {quote(raw)}")
            tpos = pos
        elif m and m.group(1) not in mapped:
            if len(m.group(2)) > 9 or int(m.group(2)) > len(names):
                raise RecordingError(
                    f"{source}: column {quote(name)} numbers a DOF beyond the file's {len(names)} columns"
                )
            groups[m.group(1)][int(m.group(2))] = pos
        else:
            ignored.append(str(raw).strip())
    for key, cols in mapped.items():
        if key != "t":
            groups[key] = {i + 1: p for i, p in enumerate(cols)}
    unnamed = f" (columns not recognised: {listing([quote(n) for n in ignored])})" if ignored else ""
    if len(base) > 1:
        raise RecordingError(f"{source}: two support motions {listing([k + '0' for k in base])}: keep one")
    try:
        out = _complete(groups, source, bool(base))
    except RecordingError as err:
        raise RecordingError(f"{err}{unnamed}") from None
    if tpos is not None:
        out["t"] = [tpos]
    elif need_time:
        raise RecordingError(f"{source}: missing column 't' (name it, or give the sampling rate){unnamed}")
    forced = sorted(i - 1 for i in groups["u"])
    if base:
        out["base"] = list(base.values())
    n = len(out["a"] if "a" in out else out["v"] if "v" in out else out["x"])
    declared = declared or [None] * len(names)
    units = {key: [split_name(names[p])[1] or declared[p] for p in cols] for key, cols in out.items()}
    read = {key: [split_name(names[p])[0] for p in cols] for key, cols in out.items()}
    return Layout(n=n, groups=out, units=units, ignored=ignored, names=read, base=next(iter(base), None), forced=forced)


def _complete(groups: dict[str, dict[int, int]], source: str, base: bool = False) -> dict[str, list[int]]:
    """Positions of DOF 1..n of every role present; raise on a missing role, DOF or a mismatched n.
    With a support motion (``base``) the forces are optional: any DOFs may have one."""
    motions = [key for key in "avx" if groups[key]]
    if not groups["u"] and not base:
        raise RecordingError(
            f"{source}: missing force columns u1..un (or the support's acceleration a0 of a base-excited record)"
        )
    if not motions:
        n = max(groups["u"]) if groups["u"] else "n"  # a support motion alone says nothing of n
        raise RecordingError(f"{source}: missing columns a1..a{n} (or velocities v1..v{n}, or displacements x1..x{n})")
    n = max(groups["u"]) if groups["u"] and not base else max(groups[motions[0]])
    out: dict[str, list[int]] = {}
    for key, cols in groups.items():
        if not cols:
            continue
        top = max(cols)
        if top != n and (key != "u" or top > n):
            what = (
                f"force columns u1..u{n}" if not base else f"{ROLES[motions[0]]} columns {motions[0]}1..{motions[0]}{n}"
            )
            raise RecordingError(f"{source}: mismatched n: {what} but {ROLES[key]} columns up to {key}{top}")
        if key == "u" and base:
            out[key] = [cols[i] for i in sorted(cols)]
            continue
        missing = [f"{key}{i}" for i in range(1, n + 1) if i not in cols]
        if missing:
            raise RecordingError(f"{source}: missing column{'s' if len(missing) > 1 else ''} {listing(missing)}")
        out[key] = [cols[i] for i in range(1, n + 1)]
    return out
