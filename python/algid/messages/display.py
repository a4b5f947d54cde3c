"""How algid objects show themselves: a one-line ``repr`` (class, size, sampling, state,
validity; never whole arrays) and, in notebooks, ``_repr_html_``: the same fields as a small
table, followed by the parameter table when the object holds estimates.

A class opts in by deriving from :class:`Displayed` and defining ``_display_fields()`` (and
``_display_parameters()`` for estimates); a dataclass that keeps its own field order for
``__init__`` assigns ``__repr__``/``_repr_html_`` from :class:`Displayed` in its body instead.
"""

from __future__ import annotations

import html
import math

import numpy as np

#: Units of the packed parameters by the first letter of their name (SI; a recording whose
#: signals are not in N and m/s^2 gives its parameters in the matching units).
PARAMETER_UNITS = {"m": "kg", "c": "N s/m", "k": "N/m"}


def number(value, digits: int = 6) -> str:
    """A float as ``%.{digits}g``, ``nan`` for a missing value."""
    value = float(value)
    return "nan" if math.isnan(value) else f"{value:.{digits}g}"


def one_line(name: str, fields: dict) -> str:
    """``Name(key=value, ...)`` with the values as given (strings unquoted)."""
    return f"{name}({', '.join(f'{key}={value}' for key, value in fields.items())})"


def html_table(name: str, fields: dict, parameters: list[tuple] | None = None) -> str:
    """A two-column table of ``fields`` under the class name, then, if given, the parameter
    rows ``(name, value, sigma, unit)`` (sigma may be None)."""
    esc = html.escape
    rows = "".join(
        f"<tr><th style='text-align:left'>{esc(str(k))}</th><td>{esc(str(v))}</td></tr>" for k, v in fields.items()
    )
    out = f"<table><caption><b>{esc(name)}</b></caption>{rows}</table>"
    if parameters:
        head = "<tr><th>parameter</th><th>estimate</th><th>sigma</th><th>unit</th></tr>"
        cells = ((esc(p), number(v), "" if s is None else number(s, 2), esc(u)) for p, v, s, u in parameters)
        body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in cells)
        out += f"<table>{head}{body}</table>"
    return out


def parameter_rows(names: list[str], values, sigmas=None, units: dict | None = None) -> list[tuple]:
    """``(name, value, sigma, unit)`` rows of packed estimates (sigma None when not known);
    ``units`` labels ``m``, ``c``, ``k`` (default :data:`PARAMETER_UNITS`, SI)."""
    units = units or PARAMETER_UNITS
    values = np.asarray(values, dtype=float)
    sig = [None] * len(names) if sigmas is None else [float(s) for s in np.asarray(sigmas, dtype=float)]
    return [(p, float(v), s, units[p[0]]) for p, v, s in zip(names, values, sig)]


def validity(valid) -> str:
    """``"2/3 DOF"`` from a per-DOF boolean array."""
    valid = np.asarray(valid, dtype=bool)
    return f"{int(valid.sum())}/{valid.size} DOF"


class Displayed:
    """Mixin: ``repr`` and ``_repr_html_`` from ``_display_fields()`` (and
    ``_display_parameters()`` when the class has estimates)."""

    def __repr__(self) -> str:
        return one_line(type(self).__name__, self._display_fields())

    def _repr_html_(self) -> str:
        return html_table(type(self).__name__, self._display_fields(), getattr(self, "_display_parameters", list)())


def recording_fields(rec) -> dict:
    """The summary of a :class:`algid.Recording`: size, sampling, signals present, file."""
    signals = [name for name in ("u", "a", "v", "x") if getattr(rec, name, None) is not None]
    fields = {
        "n": rec.n,
        "samples": int(np.asarray(rec.t).size),
        "duration_s": number(rec.duration_s),
        "dt_s": number(rec.dt),
        "signals": "+".join(signals),
    }
    units = getattr(rec, "units", None)
    if units and not rec.is_si():  # a recording that declares non-SI units says which
        fields["units"] = " ".join(f"{role}:{label}" for role, label in units.items())
    if getattr(rec, "path", None) is not None:
        fields["path"] = repr(str(rec.path))
    return fields
