"""Units of recorded signals: SI conversion of the common engineering units, labels for the
rest, and the units the identified m, c, k are in.

A signal in a convertible unit (``mm``, ``um``, ``g`` for an acceleration in standard
gravities, ``kN``, ``ms``; every one in :data:`TO_SI`) is converted to SI when read. A
sensor's raw unit (:data:`LABELS`: ``V``, ``mV``, ``counts``), or any name declared as a
label with ``:label`` (``lbs:label``), is kept as it is: the numbers stay as recorded and the
label travels with the recording, so that results say ``V/V`` where the data are volts. Any
other name is an error that names the nearest known units (``gee``: did you mean ``g``?), never a
silent label. Time must be in a unit of time.
"""

from __future__ import annotations

import difflib

#: Array name of each signal -> its role.
ROLES = {"t": "time", "u": "force", "a": "acceleration", "v": "velocity", "x": "displacement"}
#: Role -> SI unit label.
SI_UNITS = {"time": "s", "force": "N", "acceleration": "m/s^2", "velocity": "m/s", "displacement": "m"}
#: Standard gravity [m/s^2] (an acceleration in ``g``).
STANDARD_GRAVITY = 9.80665

_LENGTH = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "nm": 1e-9, "in": 0.0254}
_TIME = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "min": 60.0}
#: Role -> {unit label (normalised, see :func:`normalise`): factor to the SI unit}.
TO_SI = {
    "time": _TIME,
    "force": {"N": 1.0, "kN": 1e3, "mN": 1e-3, "lbf": 4.4482216152605},
    "displacement": _LENGTH,
    "velocity": {f"{k}/s": f for k, f in _LENGTH.items()},
    "acceleration": {**{f"{k}/s^2": f for k, f in _LENGTH.items()}, "g": STANDARD_GRAVITY},
}


#: Raw sensor units kept as labels without being declared (``:label`` declares any other).
LABELS = ("V", "mV", "uV", "counts")
#: The suffix that declares a unit name a label (``--units force=lbs:label``).
LABEL_SUFFIX = ":label"


class UnitError(ValueError):
    """A unit name that is neither a known unit of its role nor a declared label."""


def accepted_units(role: str) -> str:
    """``"N, kN, mN, lbf"``: the units of ``role`` converted to SI, for messages and help."""
    return ", ".join(TO_SI[role])


def normalise(label: str) -> str:
    """A unit label in one spelling: ``"m/s²"``, ``"m s^-2"``, ``"m/s**2"``, ``"m/s2"``, ``"m/s/s"`` -> ``"m/s^2"``;
    ``"µm"`` -> ``"um"``; surrounding blanks dropped."""
    s = " ".join(str(label).split())
    s = s.replace("µ", "u").replace("μ", "u").replace("²", "^2").replace("**", "^")
    s = s.replace(" s^-2", "/s^2").replace(" s^-1", "/s").replace(" / ", "/")
    for tail in ("/s2", "/s/s"):
        if s.endswith(tail):
            s = s[: -len(tail)] + "/s^2"
    return s


def _unknown(role: str, unit: str) -> UnitError:
    """The error for a unit name of ``role`` that is neither known nor declared a label, with
    the nearest known names (case aside: ``G`` -> ``g``)."""
    known = [*TO_SI[role], *(LABELS if role != "time" else ())]
    by_case = [k for k in known if k.lower() == unit.lower()]
    near = by_case or difflib.get_close_matches(unit, known, n=3, cutoff=0.5)
    hint = f": did you mean {' or '.join(near)}?" if near else ""
    labels = f"; raw units {', '.join(LABELS)}, or any name as UNIT{LABEL_SUFFIX}" if role != "time" else ""
    return UnitError(f"unknown unit {unit!r} for {role}{hint} (known: {accepted_units(role)}{labels})")


def to_si(role: str, label: str | None) -> tuple[float | None, str]:
    """``(factor, SI label)`` that converts a signal of ``role`` in ``label`` to SI, or
    ``(None, label)`` for a raw unit (:data:`LABELS`) or a declared label (``lbs:label``).
    No label means SI. Raises :class:`UnitError` on any other name."""
    if label is None or not str(label).strip():
        return 1.0, SI_UNITS[role]
    unit = normalise(label)
    if unit.endswith(LABEL_SUFFIX) and role != "time":
        return None, unit[: -len(LABEL_SUFFIX)].strip()
    factor = TO_SI[role].get(unit)
    if factor is not None:
        return factor, SI_UNITS[role]
    if unit in LABELS and role != "time":
        return None, unit
    raise _unknown(role, unit)


def conversion_note(role: str, label: str, factor: float) -> str:
    """``"acceleration g -> m/s^2 (x 9.80665)"``."""
    return f"{role} {normalise(label)} -> {SI_UNITS[role]} (x {factor:.9g})"


#: Order of each motion as a derivative of the displacement.
_ORDER = {"displacement": 0, "velocity": 1, "acceleration": 2}


def _factor(symbol: str, power: int) -> str:
    """``symbol^power`` (``power`` > 0), a compound symbol (``"V/g"``) in parentheses."""
    text = f"({symbol})" if any(ch in symbol for ch in " /^()") else symbol
    return text if power == 1 else f"{text}^{power}"


def unit_label(units: dict[str, str], motion: str, force: int = 0, length: int = 0, time: int = 0) -> str:
    """Label of the unit force^``force`` length^``length`` s^``time`` in the units of a
    recording whose forces are in ``units["force"]`` and whose ``motion`` (``"acceleration"``,
    ``"velocity"`` or ``"displacement"``) is in ``units[motion]``.

    A length is the motion's unit integrated back to a displacement (``V s^2`` when the
    accelerations are in V); a motion in SI stands for the metre. The force and motion
    labels are kept apart even when they are the same word: a cubic spring of a Silverbox
    recorded in volts is in ``V/V^3`` (``force=1, length=-3``), in SI ``N/m^3``.
    """
    unit = units.get(motion, SI_UNITS[motion])
    order = _ORDER[motion]
    if unit == SI_UNITS[motion]:  # per metre, whatever the motion measured
        unit, order = "m", 0
    powers = [(units.get("force", SI_UNITS["force"]), force), (unit, length), ("s", time + order * length)]
    if [p for _, p in powers if p] == [1]:  # one unit alone: as it is written
        return next(sym for sym, p in powers if p)
    up = " ".join(_factor(sym, p) for sym, p in powers if p > 0)
    down = [_factor(sym, -p) for sym, p in powers if p < 0]
    if not down:
        return up or "-"
    below = down[0] if len(down) == 1 else f"({' '.join(down)})"
    return f"{up or '1'}/{below}"


def parameter_unit_labels(units: dict[str, str], motion: str) -> dict[str, str]:
    """Unit labels of the masses, dampings and springs identified from forces in
    ``units["force"]`` and the motion ``motion`` (``"acceleration"``, ``"velocity"`` or
    ``"displacement"``) in ``units[motion]`` (:func:`unit_label`).

    SI data give ``{"m": "kg", "c": "N s/m", "k": "N/m"}``; forces and displacements in
    volts give ``{"m": "V s^2/V", "c": "V s/V", "k": "V/V"}``.
    """
    labels = {name: unit_label(units, motion, force=1, length=-1, time=t) for name, t in zip("mck", (2, 1, 0))}
    return labels | ({"m": "kg"} if labels["m"] == "N s^2/m" else {})


def signal_unit_labels(units: dict[str, str], motion: str) -> dict[str, str]:
    """Unit labels of the force and of the motion integrated or differentiated from
    ``motion`` in ``units[motion]`` (:func:`unit_label`): ``{"force": "N", "displacement":
    "m", "velocity": "m/s", "acceleration": "m/s^2"}`` for SI data; ``V``, ``V``, ``V/s``,
    ``V/s^2`` for forces and displacements in volts."""
    dims = {"force": (1, 0, 0), "displacement": (0, 1, 0), "velocity": (0, 1, -1), "acceleration": (0, 1, -2)}
    return {role: unit_label(units, motion, *dim) for role, dim in dims.items()}
