"""The diagnosis pipeline: linear fit, candidate search, noise-aware selection."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..chain import Chain
from ..recording import Recording, accelerations
from .candidates import (
    EFFECTS,
    MAX_DELAY_SAMPLES,
    CandidateFit,
    Context,
    all_candidates,
    fit_candidate,
    raw_residual,
)
from .core import METRIC, Prepared, detrend, integrals, prepare, window_length
from .linear import LinearFit, fit_linear, reconstruct_states
from .locate import locate

#: One-sided threshold on the paired t statistic of the per-window error reductions.
T_CRIT = 5.0
#: Smallest relative reduction of the withheld squared error that is reported.
MIN_REL_REDUCTION = 0.01
#: With no candidate beyond noise, a linear gap this many times the sensor-noise floor is
#: reported as ``unknown`` rather than ``none``.
UNKNOWN_FLOOR_RATIO = 3.0
#: Effects whose regressors depend on the reconstructed states (refitted once with
#: states reconstructed under the candidate model).
STATE_EFFECTS = ("coulomb_friction", "quadratic_damping", "cubic_stiffness", "clearance", "parameter_drift")


@dataclass
class Scored:
    """A candidate fit with its withheld-data score."""

    fit: CandidateFit
    gap_after: float
    reduction: np.ndarray  # (nw * S,) per-sub-block reduction of the withheld squared error
    t_stat: float
    rel_reduction: float

    @property
    def significant(self) -> bool:
        return self.t_stat >= T_CRIT and self.rel_reduction >= MIN_REL_REDUCTION


@dataclass
class Diagnosis:
    """Result of :func:`diagnose` (see :meth:`to_json` for the published fields)."""

    effect: str
    location: dict | None
    params: dict[str, float]
    params_std: dict[str, float]
    gap_before: float
    gap_after: float
    ranking: list[Scored]
    P: Prepared
    lin: LinearFit
    best: Scored | None
    timings: dict[str, float] = field(default_factory=dict)
    where: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)

    @property
    def metric(self) -> str:
        return METRIC

    def residuals(self) -> tuple[np.ndarray, np.ndarray]:
        """In-sample equation errors (N, n) [m/s^2] of the linear model and of the model
        with the reported effect (the same array twice for ``none``/``unknown``)."""
        before = self.lin.resid
        if self.best is None:
            return before, before
        raw = raw_residual(self.extra["ctx"], self.best.fit)
        return before, detrend(self.P, raw).reshape(raw.shape)


def _progress(cb: Callable[[str], None] | None, msg: str) -> None:
    if cb is not None:
        cb(msg)


def score(P: Prepared, lin: LinearFit, fit: CandidateFit, denom: float) -> Scored:
    """Withheld-error reduction of a candidate against the linear model."""
    # Per sub-block reduction of the withheld error over the candidate's equations.
    red = (lin.cv.test_sub[:, :, fit.eqs].sum(axis=2) - fit.cv.test_sub.sum(axis=2)).ravel()
    total_lin = lin.cv.test_sse.sum()
    after = total_lin - red.sum()
    sd = red.std(ddof=1)
    t = float(red.mean() / (sd / np.sqrt(red.size))) if sd > 0 else (np.inf if red.mean() > 0 else 0.0)
    return Scored(fit=fit, gap_after=float(np.sqrt(max(after, 0.0) / denom)), reduction=red, t_stat=t,
                  rel_reduction=float(red.sum() / total_lin))


def lowest_frequency_hz(lin: LinearFit, boundary: str) -> float:
    """Lowest undamped natural frequency [Hz] of the fitted chain (nan if unphysical)."""
    f = natural_frequencies(lin, boundary)
    return float(f[f > 0].min()) if np.any(f > 0) else float("nan")


def diagnose(rec: Recording, boundary: str = "fixed", progress: Callable[[str], None] | None = None,
             effects: tuple[str, ...] = EFFECTS) -> Diagnosis:
    """Locate and explain the gap between a recording and the linear chain.

    Parameters
    ----------
    rec : Recording
        Forces [N] and accelerations [m/s^2] (or displacements [m]) of every DOF.
    boundary : {"fixed", "free"}
        Right end of the chain.
    progress : callable or None
        Called with a short message at every stage.
    effects : candidate effects to try (default: all of :data:`EFFECTS`).

    Returns
    -------
    Diagnosis
    """
    if boundary not in ("fixed", "free"):
        raise ValueError(f"boundary must be 'fixed' or 'free', got {boundary!r}")
    clock = time.perf_counter()
    timings = {}
    a = accelerations(rec)
    u = rec.u
    dt = float(rec.dt)
    T = a.shape[0]
    skip = int(min(max(MAX_DELAY_SAMPLES, round(0.1 / dt)), T // 10))
    _progress(progress, f"{rec.n} DOF, {T} samples at {1 / dt:g} Hz: linear fit")
    # Window length from the lowest natural frequency of a first fit on 1 s windows.
    A = integrals(a, dt)
    L0 = window_length(dt, 1.0, T - skip)
    lin0 = fit_linear(prepare(a, u, dt, L0, boundary, skip, A=A))
    f_low = lowest_frequency_hz(lin0, boundary)
    L = window_length(dt, f_low if np.isfinite(f_low) else 1.0, T - skip)
    P = prepare(a, u, dt, L, boundary, skip, A=A)
    lin = fit_linear(P)
    timings["linear"] = time.perf_counter() - clock
    denom = float(np.sum(P.a**2))
    gap_before = float(np.sqrt(lin.cv.test_sse.sum() / denom))

    ctx = Context(P=P, lin=lin, x=lin.x, v=lin.v)
    todo = [(e, loc) for e, loc in all_candidates(P) if e in effects]
    scored: list[Scored] = []
    for k, (eff, loc) in enumerate(todo):
        _progress(progress, f"candidate {k + 1}/{len(todo)}: {eff} at {'DOF' if eff not in ('cubic_stiffness', 'clearance', 'parameter_drift') else 'spring'} {loc + 1 if eff not in ('cubic_stiffness', 'clearance', 'parameter_drift') else loc}")
        try:
            fit = fit_candidate(ctx, eff, loc)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError):
            continue
        scored.append(score(P, lin, fit, denom))
    timings["candidates"] = time.perf_counter() - clock - timings["linear"]

    # Refit the leading state-dependent candidates with states reconstructed under them.
    scored.sort(key=lambda s: s.gap_after)
    for idx in range(min(3, len(scored))):
        s = scored[idx]
        if s.fit.effect in STATE_EFFECTS and s.significant:
            raw = raw_residual(ctx, s.fit)
            thetas = list(lin.theta_a)
            for e, th in zip(s.fit.eqs, s.fit.thetas):
                thetas[e] = th
            x, v = reconstruct_states(P, thetas, raw)
            ctx2 = Context(P=P, lin=lin, x=x, v=v)
            loc = s.fit.location.get("dof", s.fit.location.get("spring"))
            loc = loc - 1 if "dof" in s.fit.location else loc
            scored[idx] = score(P, lin, fit_candidate(ctx2, s.fit.effect, loc), denom)
    scored.sort(key=lambda s: s.gap_after)
    timings["candidates"] = time.perf_counter() - clock - timings["linear"]

    _progress(progress, "locating the gap")
    natural = natural_frequencies(lin, boundary)
    where = locate(P, lin, natural)
    floor_rel = float(np.sqrt(sum(p["noise_floor"] ** 2 * np.sum(P.a[:, p["dof"] - 1] ** 2)
                                  for p in where["per_dof"]) / denom))
    best = next((s for s in scored if s.significant), None)
    excess = gap_before**2 - floor_rel**2
    if best is None:
        effect, location, params, std, gap_after = "none", None, {}, {}, gap_before
        explained = 0.0
        if gap_before > UNKNOWN_FLOOR_RATIO * floor_rel:
            effect = "unknown"
    else:
        effect, location = best.fit.effect, best.fit.location
        params, std, gap_after = best.fit.params, best.fit.params_std, best.gap_after
        explained = float((gap_before**2 - gap_after**2) / excess) if excess > 0 else 1.0
    timings["total"] = time.perf_counter() - clock
    return Diagnosis(effect=effect, location=location, params=params, params_std=std,
                     gap_before=gap_before, gap_after=gap_after, ranking=scored, P=P, lin=lin,
                     best=best, timings=timings, where=where,
                     extra={"natural_hz": natural.tolist(), "noise_floor": floor_rel,
                            "explained_excess": explained, "ctx": ctx})


def natural_frequencies(lin: LinearFit, boundary: str) -> np.ndarray:
    """Undamped natural frequencies [Hz] of the fitted chain (empty if unphysical)."""
    n = len(lin.theta)
    k = np.nan_to_num(lin.stiffness().copy())
    if n == 1:
        k = np.array([k[0], 0.0])
    try:
        ch = Chain(np.abs(lin.mass), np.abs(lin.damping()), np.abs(k), boundary if n > 1 else "fixed")
        return ch.natural_frequencies_hz()
    except ValueError:
        return np.array([])
