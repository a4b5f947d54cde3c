"""The unmodelled effects the simulator can switch on: their names, locations and
parameters (:class:`Effect`), validated when an effect is made."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..messages.deprecation import warn_renamed
from ..model.chain import Chain
from ..model.network import NetworkModel

__all__ = ["COULOMB_V_EPS", "EFFECT_LOCATIONS", "EFFECT_NAMES", "Effect", "as_effect"]

#: Smallest velocity scale [m/s] of the dry-friction regularisation ``F tanh(v / v_eps)``
#: (the default is ``max(COULOMB_V_EPS, F / (m_i f_sub))``, see :mod:`algid.simulator`).
COULOMB_V_EPS = 1e-4

#: ``name -> (location key, required params, optional params)``.
_EFFECT_SPECS: dict[str, tuple[str, tuple[str, ...], tuple[str, ...]]] = {
    "coulomb_friction": ("dof", ("force",), ("v_eps",)),
    "quadratic_damping": ("dof", ("c_quadratic",), ()),
    "cubic_stiffness": ("spring", ("k_cubic",), ()),
    "clearance": ("spring", ("gap", "k_contact"), ()),
    "input_delay": ("dof", ("delay",), ()),
    "sensor_bias": ("dof", ("bias",), ()),
    "sensor_lowpass": ("dof", ("cutoff_hz",), ()),
    "sensor_highpass": ("dof", ("cutoff_hz",), ()),
    "parameter_drift": ("spring", ("rel_change",), ()),
    "force_offset": ("dof", ("offset",), ()),
    "stribeck_friction": ("dof", ("force", "static", "v_stribeck"), ("v_eps",)),
    "amplitude_damping": ("spring", ("c_amp",), ()),
}

#: Effect parameters renamed so that none shares a name with a chain parameter
#: (``k3`` is the third spring): ``effect -> {old: new}``, the old names warn.
_RENAMED_PARAMS = {
    "quadratic_damping": {"c2": "c_quadratic"},
    "cubic_stiffness": {"k3": "k_cubic"},
    "clearance": {"stiffness": "k_contact"},
}

#: The effect names the simulator knows (part of the public interface).
EFFECT_NAMES: tuple[str, ...] = tuple(_EFFECT_SPECS)
#: Where each effect sits: ``"dof"`` or ``"spring"``.
EFFECT_LOCATIONS: dict[str, str] = {name: spec[0] for name, spec in _EFFECT_SPECS.items()}


@dataclass(frozen=True)
class Effect:
    """One unmodelled effect switched on in the plant or its sensors.

    Parameters
    ----------
    name : str
        One of :data:`EFFECT_NAMES`:

        ``coulomb_friction``  location ``{"dof": i}``, params ``{"force": F [N]}``
            (optional ``"v_eps"`` [m/s]): a force ``-F tanh(v_i / v_eps)`` on mass i
            (smooth, steep dry friction; default ``v_eps`` in :mod:`algid.simulator`).
        ``quadratic_damping``  ``{"dof": i}``, ``{"c_quadratic": [N s^2/m^2]}``: ``-c_quadratic v_i |v_i|``.
        ``cubic_stiffness``  ``{"spring": j}``, ``{"k_cubic": [N/m^3]}``: spring force
            ``k_cubic d_j^3`` added to spring j (negative ``k_cubic`` softens).
        ``clearance``  ``{"spring": j}``, ``{"gap": [m], "k_contact": [N/m]}``: a contact
            in parallel with spring j, force ``k_contact (|d_j| - gap) sign(d_j)`` when
            ``|d_j| > gap``, zero otherwise.
        ``input_delay``  ``{"dof": i}``, ``{"delay": [s]}``: the force reaching mass i lags
            the recorded one by ``delay``.
        ``sensor_bias``  ``{"dof": i}``, ``{"bias": [m/s^2]}``: accelerometer i reads
            ``bias`` more than the truth.
        ``sensor_lowpass``  ``{"dof": i}``, ``{"cutoff_hz": [Hz]}``: accelerometer i is a
            first-order low-pass ``a_meas' = 2 pi f_c (a - a_meas)``, starting settled
            (``a_meas(0) = a(0+)``).
        ``sensor_highpass``  ``{"dof": i}``, ``{"cutoff_hz": [Hz]}``: accelerometer i is AC
            coupled (an IEPE sensor, a charge amplifier), the first-order high-pass
            ``a_meas = a - z``, ``z' = 2 pi f_c (a - z)``, settled on the structure at rest
            before the record (``z(0) = 0``, ``a_meas(0) = a(0+)``). Only the accelerometer
            reads it: the positions and velocities of a result are the plant's. Not together
            with ``sensor_lowpass`` on the same DOF.
        ``parameter_drift``  ``{"spring": j}``, ``{"rel_change": r}``: stiffness of spring j
            becomes ``k_j (1 + r t / duration)`` (linear over the record).
        ``force_offset``  ``{"dof": i}``, ``{"offset": [N]}``: a constant force on mass i
            that the force sensor does not see (gravity on an inclined axis, a preload,
            a drive's current-sensor offset).
        ``stribeck_friction``  ``{"dof": i}``, ``{"force": F_c [N], "static": F_s [N],
            "v_stribeck": v_s [m/s]}`` (optional ``"v_eps"``): dry friction that breaks
            away at ``F_s`` and falls to ``F_c`` with speed,
            ``-(F_c + (F_s - F_c) exp(-(v_i / v_s)^2)) tanh(v_i / v_eps)``.
        ``amplitude_damping``  ``{"spring": j}``, ``{"c_amp": [N s/m^2]}``: micro-slip in
            the joint of spring j, a damping force ``c_amp |d_j| d_j'`` whose equivalent
            viscous damping grows with the deformation amplitude.
    location : dict
        ``{"dof": i}`` with ``1 <= i <= n`` or ``{"spring": j}`` with ``1 <= j <= n+1``
        (``j <= n`` for a free right end); 1-based as in the paper.
    params : dict
        Effect parameters in SI units as listed above.
    """

    name: str
    location: Mapping[str, int]
    params: Mapping[str, float]

    def __post_init__(self) -> None:
        if self.name not in _EFFECT_SPECS:
            raise ValueError(f"unknown effect {self.name!r}; known: {', '.join(EFFECT_NAMES)}")
        key, required, optional = _EFFECT_SPECS[self.name]
        loc = dict(self.location) if self.location is not None else {}
        if set(loc) != {key}:
            raise ValueError(f"effect {self.name!r} takes location {{{key!r}: index}}, got {loc!r}")
        idx = loc[key]
        if isinstance(idx, bool) or not float(idx).is_integer():
            raise ValueError(f"effect {self.name!r}: {key} index must be an integer, got {idx!r}")
        params = dict(self.params) if self.params is not None else {}
        for old, new in _RENAMED_PARAMS.get(self.name, {}).items():
            if old in params and new not in params:
                warn_renamed(f"effect {self.name!r} parameter {old!r}", repr(new), stacklevel=5)
                params[new] = params.pop(old)
        missing = [p for p in required if p not in params]
        unknown = [p for p in params if p not in required + optional]
        if missing or unknown:
            raise ValueError(
                f"effect {self.name!r} takes params {required}"
                + (f" (optional {optional})" if optional else "")
                + f"; missing {missing}, unknown {unknown}"
            )
        clean = {}
        for p, val in params.items():
            try:
                val = float(val)
            except (TypeError, ValueError):
                raise ValueError(f"effect {self.name!r}: param {p!r} must be a number, got {val!r}") from None
            if not math.isfinite(val):
                raise ValueError(f"effect {self.name!r}: param {p!r} must be finite, got {val}")
            clean[p] = val
        _check_param_ranges(self.name, clean)
        object.__setattr__(self, "location", {key: int(idx)})
        object.__setattr__(self, "params", clean)

    @property
    def dof(self) -> int | None:
        """0-based DOF index, or None for a spring effect."""
        return self.location["dof"] - 1 if "dof" in self.location else None

    @property
    def spring(self) -> int | None:
        """1-based spring index, or None for a DOF effect."""
        return self.location.get("spring")

    def check(self, chain: Chain | NetworkModel) -> None:
        """Raise ``ValueError`` if the location does not exist on ``chain`` (or a network model)."""
        n = chain.n
        if "dof" in self.location:
            i = self.location["dof"]
            if not 1 <= i <= n:
                raise ValueError(f"effect {self.name!r}: dof {i} outside 1..{n}")
        else:
            j = self.location["spring"]
            top = chain.network.size
            where = f"{chain.boundary} right end" if isinstance(chain, Chain) else "the network's springs"
            if not 1 <= j <= top:
                raise ValueError(f"effect {self.name!r}: spring {j} outside 1..{top} ({where})")

    def to_dict(self) -> dict:
        """JSON-friendly ``{"effect", "location", "params"}``."""
        return {"effect": self.name, "location": dict(self.location), "params": dict(self.params)}


def _check_param_ranges(name: str, p: dict) -> None:
    positive = {"cutoff_hz", "v_eps", "v_stribeck"}
    nonneg = {"force", "c_quadratic", "gap", "k_contact", "delay", "static", "c_amp"}
    for key, val in p.items():
        if key in positive and not val > 0:
            raise ValueError(f"effect {name!r}: {key} must be > 0, got {val}")
        if key in nonneg and val < 0:
            raise ValueError(f"effect {name!r}: {key} must be >= 0, got {val}")
    if name == "stribeck_friction" and p["static"] < p["force"]:
        raise ValueError(f"effect 'stribeck_friction': static ({p['static']}) must be >= force ({p['force']})")
    if name == "parameter_drift" and not p["rel_change"] > -1.0:
        raise ValueError(f"effect 'parameter_drift': rel_change must be > -1, got {p['rel_change']}")


def as_effect(e: Effect | Mapping[str, Any]) -> Effect:
    """``e`` as an :class:`Effect` (dicts ``{"name" or "effect", "location", "params"}``)."""
    if isinstance(e, Effect):
        return e
    if isinstance(e, Mapping):
        name = e.get("name", e.get("effect"))
        return Effect(name, e.get("location", {}), e.get("params", {}))
    raise ValueError(f"effects must be Effect instances or dicts, got {type(e).__name__}")
