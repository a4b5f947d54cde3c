"""The sub-step schedule: how every sample interval is cut into integration steps (at
the input delays' fractions, and finer where a clearance contact or dry friction is steep),
and the dry-friction regularisation velocities that go with the step."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .effects import COULOMB_V_EPS
from .inputs import RunInputs

__all__ = ["Schedule", "substep_schedule"]

#: The dry-friction effects (regularised as ``F tanh(v / v_eps)``).
DRY_FRICTION = ("coulomb_friction", "stribeck_friction")


@dataclass(frozen=True)
class Schedule:
    """Sub-intervals of every sample interval.

    bounds : fractions ``0 = b_0 < b_1 < .. < b_J = 1`` of the interval where they start and end;
    lengths_s : their lengths [s] (J);
    v_eps : regularisation velocity [m/s] of every dry-friction effect (key: its index in
        the effects).
    """

    bounds: list[float]
    lengths_s: list[float]
    v_eps: dict[int, float]

    @property
    def J(self) -> int:
        """Sub-intervals per sample interval."""
        return len(self.lengths_s)


def substep_schedule(inp: RunInputs) -> Schedule:
    """The schedule of a run (the rules are in :mod:`algid.simulator`)."""
    ns = _clearance_substeps(inp)
    ns, v_eps = _dry_friction(inp, ns)
    cuts = {round(q / ns, 12) for q in range(1, ns)}
    if bool((inp.delays > 0).any()):
        cuts |= {round((d * inp.fs_hz) % 1.0, 12) for d in inp.delays if d > 0}
    bnds = [0.0] + sorted(c for c in cuts if 1e-9 < c < 1 - 1e-9) + [1.0]
    lens = [(bnds[q + 1] - bnds[q]) * inp.h for q in range(len(bnds) - 1)]
    return Schedule(bounds=bnds, lengths_s=lens, v_eps=v_eps)


def _clearance_substeps(inp: RunInputs) -> int:
    """Steps per interval so that a clearance contact is resolved, ``h_sub sqrt(k_c / m) <= 0.25``
    (``substeps`` if given)."""
    chain, h = inp.chain, inp.h
    ns = 1 if inp.substeps is None else inp.substeps
    for e in inp.effects:
        if e.name == "clearance" and inp.substeps is None:
            adj = [chain.mass[i - 1] for i, _ in chain.network.sides(e.spring)]
            w = math.sqrt(e.params["k_contact"] / min(adj))
            ns = max(ns, int(math.ceil(h * w / 0.25)))
    return ns


def _dry_friction(inp: RunInputs, ns: int) -> tuple[int, dict[int, float]]:
    """Steps per interval and ``v_eps`` of every dry friction: an explicit ``v_eps`` gets
    enough steps that its relaxation rate ``F / (m v_eps)`` stays below one per step, the
    others the smallest ``v_eps`` with that property at the given steps."""
    chain, h, effs = inp.chain, inp.h, inp.effects
    v_eps: dict[int, float] = {}
    peak = {q: e.params.get("static", e.params.get("force")) for q, e in enumerate(effs) if e.name in DRY_FRICTION}
    for q, e in enumerate(effs):
        if e.name in DRY_FRICTION and "v_eps" in e.params:
            v_eps[q] = e.params["v_eps"]
            if inp.substeps is None:
                ns = max(ns, int(math.ceil(peak[q] * h / (chain.mass[e.dof] * v_eps[q]))))
    for q, e in enumerate(effs):
        if e.name in DRY_FRICTION and q not in v_eps:
            v_eps[q] = max(COULOMB_V_EPS, peak[q] * h / ns / chain.mass[e.dof])
    return ns, v_eps
