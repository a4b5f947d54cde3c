"""From the columns a reader read to a :class:`Recording`: time from the file or from the
sampling interval, units converted to SI where they can be (and listed in a note), short gaps
of missing samples bridged (:mod:`.gaps`), every value checked with the file line it came from."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..messages import quote
from .columns import ROLE_KEYS, Layout
from .core import Recording, RecordingError, check_finite, file_time
from .gaps import bridge_gaps
from .units import ROLES, SI_UNITS, UnitError, conversion_note, to_si


def role_units(units: dict | None) -> dict[str, str]:
    """``{"force": "V", "displacement": "V"}`` from a mapping whose keys may be role names
    or array names (``u``, ``x``, ``accel``); raise on an unknown role."""
    out = {}
    for role, label in (units or {}).items():
        key = ROLE_KEYS.get(str(role).strip().lower())
        if key is None:
            raise RecordingError(f"units: unknown role {quote(role)} (expected {', '.join(ROLES.values())})")
        out[ROLES[key]] = str(label).strip()
    return out


def _convert(key: str, arr: np.ndarray, declared: list[str | None], source: str, notes: list[str]) -> str:
    """Convert the columns of ``arr`` (role ``key``) to SI in place where their unit allows;
    return the role's unit label."""
    role = ROLES[key]
    labels = set()
    for col, unit in enumerate(declared):
        try:
            factor, label = to_si(role, unit)
        except UnitError as err:
            raise RecordingError(f"{source}: {err}") from None
        if factor is not None and factor != 1.0:
            arr[:, col] *= factor
            note = conversion_note(role, unit, factor)
            if note not in notes:
                notes.append(note)
        labels.add(label)
    if len(labels) > 1:
        raise RecordingError(f"{source}: {role} columns in different units: {', '.join(sorted(labels))}")
    return labels.pop()


def si_assumed(layout: Layout, given: dict[str, str]) -> list[str]:
    """The note naming the columns read without a unit (in the header, the file or ``units``),
    taken as SI: ``no unit for t, u1, a1: SI assumed (s, N, m/s^2)``."""
    bare: dict[str, list[str]] = {}
    for key in ROLES:
        units = layout.units.get(key, [])
        if ROLES[key] not in given:
            names = [name for name, unit in zip(layout.names.get(key, []), units) if unit is None]
            if names:
                bare[ROLES[key]] = names
    if not bare:
        return []
    columns = ", ".join(name for names in bare.values() for name in names)
    return [f"no unit for {columns}: SI assumed ({', '.join(SI_UNITS[role] for role in bare)})"]


def assemble(
    path: Path | None,
    source: str,
    data: np.ndarray,
    layout: Layout,
    lines: np.ndarray | None = None,
    dt: float | None = None,
    units: dict | None = None,
) -> Recording:
    """The recording in ``data`` (T, len(layout.positions())), columns in position order.

    ``units`` (role -> label) overrides the units the columns declare; ``dt`` [s] gives the
    time and replaces a time column (:func:`.core.file_time`)."""
    given = role_units(units)
    order = {p: j for j, p in enumerate(layout.positions())}
    notes = layout.notes() + si_assumed(layout, given)
    labels: dict[str, str] = {}
    parts: dict[str, np.ndarray] = {}
    for key, cols in layout.groups.items():
        arr = data[:, [order[p] for p in cols]]
        kind = layout.base if key == "base" else key
        declared = [given.get(ROLES[kind], u) for u in layout.units[key]]
        if key == "t":  # a signal's missing samples are bridged below, a missing timestamp is an error
            try:
                check_finite(key, arr, lines)
            except RecordingError as err:
                raise RecordingError(f"{source}: {err}") from None
        label = _convert(kind, arr, declared, source, notes)
        parts[key] = arr
        if key == "base":
            base_label = label
        elif labels.setdefault(ROLES[key], label) != label:
            raise RecordingError(f"{source}: {ROLES[key]} columns in different units: {labels[ROLES[key]]}, {label}")
    if "base" in parts:
        _check_base_unit(source, layout.base, base_label, labels)
    try:
        t, note = file_time(parts.pop("t")[:, 0] if "t" in parts else None, dt, data.shape[0], lines)
        notes += [note] if note else []
        parts, missing, gap_notes = bridge_gaps(parts, lines, layout.names)
        return Recording(
            t=t,
            u=_forces(parts.get("u"), layout, data.shape[0]),
            base=parts["base"][:, 0] if "base" in parts else None,
            base_kind=layout.base or "a",
            a=parts.get("a"),
            v=parts.get("v"),
            x=parts.get("x"),
            dt=dt,
            path=path,
            units={role: label for role, label in labels.items() if role != "time"},
            notes=notes + gap_notes,
            missing=missing,
        )
    except RecordingError as err:
        raise RecordingError(f"{source}: {err}") from None


def _forces(u: np.ndarray | None, layout: Layout, T: int) -> np.ndarray:
    """The (T, n) forces: a base-excited record's DOFs without a force column carry none."""
    if layout.base is None:
        return u
    out = np.zeros((T, layout.n))
    if u is not None:
        out[:, layout.forced] = u
    return out


def _check_base_unit(source: str, kind: str, label: str, labels: dict[str, str]) -> None:
    """The support motion must be in the DOFs' units: SI (or converted to it), or the same
    label as the DOFs' motion of the same kind (``V`` beside ``V``)."""
    role = ROLES[kind]
    motion = next(ROLES[k] for k in "avx" if ROLES[k] in labels)
    si = label == SI_UNITS[role] and labels[motion] == SI_UNITS[motion]
    if not si and labels.get(role) != label:
        raise RecordingError(
            f"{source}: support motion {kind}0 in {quote(label)} but the {motion} of the DOFs in "
            f"{quote(labels[motion])}: give both in SI units or both in the same unit"
        )
