"""``identify`` reads as its stages, each entered once (issue 38): a tracer on one
``algid.identify`` call lists every call made from ``identification/engine.py`` into another
module of the library; the stage modules are entered in order, once each, and no other module
of ``identification`` is entered from the engine (a decision taken by a return trip, such as
re-planning from a first estimate or running candidate windows, would show up here)."""

from __future__ import annotations

import sys
from pathlib import Path

import algid
from algid.identification import engine
from algid.model.chain import TABLE1
from algid.recording import Recording
from algid.simulator import simulate
from algid.simulator.exact import multisine

PACKAGE = Path(algid.__file__).parent

#: screen -> noise model -> model check -> plan -> estimate -> uncertainty -> verdicts
STAGES = [
    "identification.screen",
    "recording.noise",
    "identification.augmented",
    "identification.plan",
    "identification.estimate",
    "identification.uncertainty",
    "identification.verdicts",
]


def _module(filename: str) -> str | None:
    """``identification.plan`` for a file of the library, None for any other."""
    path = Path(filename)
    if not path.is_relative_to(PACKAGE):
        return None
    return ".".join(path.relative_to(PACKAGE).with_suffix("").parts)


def entered_from_engine(call) -> tuple[list[str], object]:
    """The library modules that the frames of engine.py call into while ``call()`` runs, in
    order (one entry per call), and what ``call()`` returned."""
    here = engine.__file__
    entered: list[str] = []

    def profile(frame, event, arg):
        caller = frame.f_back
        if event == "call" and caller is not None and caller.f_code.co_filename == here:
            module = _module(frame.f_code.co_filename)
            if module is not None and module != "identification.engine":
                entered.append(module)

    sys.setprofile(profile)
    try:
        result = call()
    finally:
        sys.setprofile(None)
    return entered, result


def test_identify_enters_each_stage_once_and_in_order():
    # Table 1 from displacements: the algebraic windows, whose plan starts from a first estimate
    # of the chain and whose length is chosen among candidates by the bootstrap
    sim = simulate(TABLE1, multisine(3, 6), 2.0, noise_db=60.0, noise_on=("position", "force"), seed=6)
    rec = Recording(t=sim.t, u=sim.u, x=sim.x_meas)
    entered, res = entered_from_engine(lambda: algid.identify(rec, replicates=2))
    assert res.plan.method == "algebraic" and " x (" in res.plan.window_basis  # a candidate other than the guess
    in_stages = [m for m in entered if m in STAGES or m.startswith("identification.")]
    assert in_stages == STAGES, entered
