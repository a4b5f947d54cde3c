"""Identify's estimate stage: the plan run over the whole record (:mod:`.runner`).

The single window and the weak-form windows run as planned. The algebraic windows' length is
first chosen (:func:`select_window`): every candidate of the plan (:func:`.plan.window_candidates`:
multiples of its first guess, and of the force-based one) is run on the record and scored by
the root-mean-square error that the bootstrap (:func:`.surrogate.bootstrap`) measures on
:data:`SELECT_REPLICATES` surrogates of its estimate, in shares of the force (mean over the
parameters); when the best is the longest (shortest) tried, longer (shorter) ones are tried
while they score better. Longer windows average more but integrate more of the noise the
differentiation coloured (their bias grows): the record decides. The best candidate's run is
the estimate.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from ..recording.noise import NoiseModel
from .plan import Plan, window_candidates, window_limits
from .runner import Run, run_plan
from .screen import Signals
from .surrogate import bootstrap, surrogate_band
from .verdicts import scales

#: Replicates per candidate window when the algebraic windows' length is chosen.
SELECT_REPLICATES = 4
#: When the best window is the longest (shortest) tried, longer (shorter) ones by this
#: factor are tried, at most this many times, while they score better.
EXTEND_FACTOR = 1.4
EXTEND_STEPS = 4

Progress = Callable[[float], None]


@dataclass(frozen=True)
class Estimate:
    """The plan that ran (the algebraic windows' length as chosen) and its run."""

    plan: Plan
    run: Run


def estimate(sig: Signals, nm: NoiseModel, plan: Plan, boundary: str, seed: int, progress: Progress) -> Estimate:
    """Identify's estimate stage (module docstring): ``plan`` run over the record ``sig``;
    ``seed`` of the surrogates that choose the algebraic windows' length; ``progress(fraction)``."""
    progress(0.0)
    if plan.method == "algebraic":
        plan, run = select_window(sig, nm, plan, boundary, seed, progress)
    else:
        run = run_plan(sig.a, sig.rec.u, sig.dt, boundary, plan, missing=sig.missing)
    progress(1.0)
    return Estimate(plan, run)


def _score(sig: Signals, nm: NoiseModel, cand: Plan, boundary: str, seed: int) -> tuple[float, Run]:
    """The candidate ``cand`` run on the record, and its score (module docstring; inf when no
    parameter has one)."""
    n = sig.rec.n
    run = run_plan(sig.a, sig.rec.u, nm.dt, boundary, cand, missing=sig.missing)
    f_cut = surrogate_band(nm, run.theta, n, boundary)
    boot = bootstrap(
        run.theta,
        sig.motion,
        nm,
        cand,
        boundary,
        f_cut,
        sig.forced,
        SELECT_REPLICATES,
        seed,
        history=False,
        missing=sig.missing,
    )
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns: parameters not estimated
        rmse = np.sqrt(np.nanmean((boot.replicates - run.theta) ** 2, axis=0))
    share = rmse * scales(n, boundary, boot.motion, sig.rec.u, sig.forced)[0]
    return (float(np.nanmean(share)) if np.any(np.isfinite(share)) else np.inf), run


def select_window(
    sig: Signals, nm: NoiseModel, plan: Plan, boundary: str, seed: int, progress: Progress
) -> tuple[Plan, Run]:
    """The algebraic windows' length (module docstring): the best plan among the candidates of
    ``plan`` and beyond the ends of their range, and its run."""
    cands = window_candidates(plan, nm, sig.duration_s)
    scored: list[tuple[float, Run]] = []
    for cand in cands:
        scored.append(_score(sig, nm, cand, boundary, seed))
        progress(min(len(scored) / (len(cands) + EXTEND_STEPS), 1.0))
    best = _beyond(sig, nm, plan, boundary, seed, cands, scored, progress)
    return cands[best], scored[best][1]


def _beyond(sig, nm, plan: Plan, boundary: str, seed: int, cands: list, scored: list, progress: Progress) -> int:
    """The index of the best candidate once, if the best of ``cands`` (scores ``scored``) is the
    longest (shortest) tried, longer (shorter) ones by :data:`EXTEND_FACTOR` have been tried, at
    most :data:`EXTEND_STEPS`, while they score better (appended to both lists)."""
    best = min(range(len(cands)), key=lambda q: scored[q][0])
    lengths = sorted(c.window_s for c in cands)
    lo, hi = window_limits(nm, sig.duration_s)
    step = None
    if cands[best].window_s == lengths[-1]:
        step = EXTEND_FACTOR
    elif cands[best].window_s == lengths[0]:
        step = 1.0 / EXTEND_FACTOR
    for _ in range(EXTEND_STEPS if step else 0):
        L = float(np.clip(cands[best].window_s * step, lo, hi))
        if abs(L / cands[best].window_s - 1.0) < 0.05:
            break
        cand = replace(cands[best], window_s=L, window_basis=f"{L / plan.window_s:.3g} x ({plan.window_basis})")
        result = _score(sig, nm, cand, boundary, seed)
        progress(min(len(scored) / (len(cands) + EXTEND_STEPS), 1.0))
        if not result[0] < scored[best][0]:
            break
        cands.append(cand)
        scored.append(result)
        best = len(cands) - 1
    return best
