"""Units of recorded signals: SI conversion of the common engineering units, labels for the
rest, and the units the identified m, c, k are in.

A signal in a convertible unit (``mm``, ``um``, ``g`` for an acceleration in standard
gravities, ``kN``, ``ms``) is converted to SI when read. A unit that is not a physical unit
of the role (``V``, ``mV``, ``counts``) is kept as it is: the numbers stay as recorded and
the label travels with the recording, so that results say ``V/V`` where the data are volts.
Time must be in a unit of time.
"""

from __future__ import annotations

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


def normalise(label: str) -> str:
    """A unit label in one spelling: ``"m/s²"``, ``"m s^-2"``, ``"m/s**2"``, ``"m/s2"`` -> ``"m/s^2"``;
    ``"µm"`` -> ``"um"``; surrounding blanks dropped."""
    s = " ".join(str(label).split())
    s = s.replace("µ", "u").replace("μ", "u").replace("²", "^2").replace("**", "^")
    s = s.replace(" s^-2", "/s^2").replace(" s^-1", "/s").replace(" / ", "/")
    if s.endswith("/s2"):
        s = s[:-1] + "^2"
    return s


def to_si(role: str, label: str | None) -> tuple[float | None, str]:
    """``(factor, SI label)`` that converts a signal of ``role`` in ``label`` to SI, or
    ``(None, label)`` for a unit kept as a label. No label means SI."""
    if label is None or not str(label).strip():
        return 1.0, SI_UNITS[role]
    unit = normalise(label)
    factor = TO_SI[role].get(unit)
    return (None, unit) if factor is None else (factor, SI_UNITS[role])


def conversion_note(role: str, label: str, factor: float) -> str:
    """``"acceleration g -> m/s^2 (x 9.80665)"``."""
    return f"{role} {normalise(label)} -> {SI_UNITS[role]} (x {factor:.9g})"


def parameter_unit_labels(units: dict[str, str], motion: str) -> dict[str, str]:
    """Unit labels of the masses, dampings and springs identified from forces in
    ``units["force"]`` and the motion ``motion`` (``"acceleration"``, ``"velocity"`` or
    ``"displacement"``) in ``units[motion]``.

    SI data give ``{"m": "kg", "c": "N s/m", "k": "N/m"}``; forces and displacements in
    volts give ``{"m": "V s^2/V", "c": "V s/V", "k": "V/V"}``.
    """
    force = units.get("force", SI_UNITS["force"])
    unit = units.get(motion, SI_UNITS[motion])
    if force == SI_UNITS["force"] and unit == SI_UNITS[motion]:
        return {"m": "kg", "c": "N s/m", "k": "N/m"}
    if unit == SI_UNITS[motion]:  # forces in a label, motion in SI: per metre
        unit, motion = "m", "displacement"
    per = {
        "displacement": (f"{force} s^2/{unit}", f"{force} s/{unit}", f"{force}/{unit}"),
        "velocity": (f"{force} s/{unit}", f"{force}/{unit}", f"{force}/({unit} s)"),
        "acceleration": (f"{force}/{unit}", f"{force}/({unit} s)", f"{force}/({unit} s^2)"),
    }[motion]
    return dict(zip("mck", per))
