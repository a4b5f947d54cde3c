"""The tests' signals: the independent high-accuracy simulation of eq. 1 and its multisine
force (:mod:`algid.simulator.exact`, shared with the benchmarks), and the effects the tests
add."""

from __future__ import annotations

from algid.simulator.exact import multisine, relative_errors, simulate_chain

__all__ = ["FRICTION_AND_OFFSET", "multisine", "relative_errors", "simulate_chain"]

#: Dry friction of a few percent of the drive's force and a constant force its sensor misses.
FRICTION_AND_OFFSET = [
    {"name": "coulomb_friction", "location": {"dof": 1}, "params": {"force": 1.5}},
    {"name": "force_offset", "location": {"dof": 1}, "params": {"offset": 3.0}},
]
