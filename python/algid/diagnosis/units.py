"""The units of what a diagnosis reports, in the units the recording declares.

A diagnosis works in the recording's own units: forces in ``units["force"]`` and the motion
it measured (accelerations, velocities or displacements) in that motion's unit, so that the
linear chain, the states it reconstructs and every effect parameter are in units built from
those two and the second (:func:`algid.recording.units.unit_label`). SI data give kg,
N s/m, N/m and, for a cubic spring, N/m^3; a Silverbox recorded in volts (force and
displacement in V) gives V s^2/V, V s/V, V/V and V/V^3.
"""

from __future__ import annotations

from ..recording.units import parameter_unit_labels, signal_unit_labels, unit_label

#: Effect parameter -> exponents of (force, length, time) of its unit
#: (the parameters of :mod:`.candidates`; ``excess`` is the Stribeck peak over the Coulomb level).
PARAMETER_DIMENSIONS = {
    "force": (1, 0, 0),
    "static": (1, 0, 0),
    "excess": (1, 0, 0),
    "v_scale": (0, 1, -1),
    "v_stribeck": (0, 1, -1),
    "c_amp": (1, -2, 1),
    "c_quadratic": (1, -2, 2),
    "k_cubic": (1, -3, 0),
    "gap": (0, 1, 0),
    "k_contact": (1, -1, 0),
    "delay": (0, 0, 1),
    "bias": (0, 1, -2),
}
#: Effect parameters whose unit does not depend on the recording.
FIXED_UNITS = {"cutoff_hz": "Hz", "rel_change": "-"}


def diagnosis_units(units: dict[str, str], motion: str) -> dict[str, str]:
    """Unit label of every number a diagnosis reports, by name: ``m``, ``c``, ``k`` of the
    linear chain, the signals ``force``, ``displacement``, ``velocity``, ``acceleration`` and
    every effect parameter (``k_cubic``, ``gap``, ...), for a recording with ``units`` (by role)
    whose motion measured is ``motion`` (:func:`algid.recording.motion`)."""
    params = {name: unit_label(units, motion, *dims) for name, dims in PARAMETER_DIMENSIONS.items()}
    return signal_unit_labels(units, motion) | parameter_unit_labels(units, motion) | params | FIXED_UNITS


#: The units of a diagnosis of SI data.
SI = diagnosis_units({}, "acceleration")
