"""Whether eq. 1 explains a record, and eq. 1 with named effects estimated together:
identify's model check (:func:`model_check`), before the plan.

0. The fit check of every linear identification (:func:`fit_check`): the diagnosis's
   verdict on the record. Unless it is ``none``, a biased linear fit is not called valid. (An
   impact record's check is the output error of the chain identify estimates,
   :mod:`.impact_fit`, after the estimate: the diagnosis's windows do not fit a decay.)

1. The effects: ``NAME[:LOCATION]`` in the diagnosis's vocabulary (``coulomb_friction:1``,
   ``cubic_stiffness:2``), or ``auto``: the effect :func:`algid.diagnose` reports as
   significant (with ``none`` or ``unknown`` the linear chain is identified as without
   effects, and the result says so).
2. The fit: the diagnosis's integral equations of the record's windows with the effects'
   columns (:func:`algid.diagnosis.engine.diagnose` with ``given``), cross-validated over
   the folds; the chain and the effects' parameters with their jackknife standard
   deviations are those of :func:`algid.diagnosis.corrected.corrected_model`.
3. The verdicts (:func:`.verdicts.judge`): an estimate is valid when the record determines
   it and the chain with the effects explains the record to its noise: the withheld gap it
   leaves is at most :data:`algid.diagnosis.engine.FIT_FLOOR_RATIO` times the noise
   floor (the test by which the diagnosis calls a record ``none``). An effect parameter is
   determined when it is beyond three standard deviations from zero with a physical sign.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from ..diagnosis.candidates import EFFECTS, MAIN_PARAM, PHYSICAL
from ..diagnosis.corrected import corrected_model, effect_parts, linear_model
from ..diagnosis.engine import FIT_FLOOR_RATIO, diagnose
from ..diagnosis.report import location_text
from ..recording.noise import NoiseModel
from .motion import band_limited_motion
from .plan import Plan
from .screen import Signals, on_time_signals
from .surrogate import surrogate_band
from .verdicts import judge

#: A determined effect parameter lies beyond this many standard deviations from zero.
EFFECT_Z = 3.0


def effect_label(effects: list[dict]) -> str:
    """``coulomb_friction at DOF 1 + cubic_stiffness at spring 2``."""
    return " + ".join(f"{e['effect']} at {location_text(e['location'])}" for e in effects)


def _effect_verdicts(effects: list[dict], misfit: str, units: dict) -> list[dict]:
    """The effects with ``valid``, ``reason`` and ``units`` of their parameters (module docstring)."""
    out = []
    for e in effects:
        main = MAIN_PARAM[e["effect"]]
        value, sd = float(e["params"][main]), float(e["params_std"].get(main, math.nan))
        rule = PHYSICAL.get(e["effect"])
        reason = ""
        if rule is not None and not rule(e["params"]):
            reason = f"{main} = {value:.4g} has an unphysical sign: the effect does not fit this record"
        elif not (math.isfinite(sd) and abs(value) > EFFECT_Z * sd):
            reason = f"{main} not determined: {value:.4g} +- {sd:.2g} is within {EFFECT_Z:g} sigma of zero"
        elif misfit:
            reason = misfit
        out.append(
            {
                **e,
                "valid": not reason,
                "reason": reason or None,
                "units": {k: units.get(k, "") for k in e["params"]},
            }
        )
    return out


#: The candidates the fit check of the linear chain tries (:func:`fit_check`): every effect of
#: the diagnosis but Stribeck friction, whose Coulomb part stands out wherever it does.
CHECKED_EFFECTS = tuple(e for e in EFFECTS if e != "stribeck_friction")


def fit_check(rec, boundary: str) -> tuple[dict, object]:
    """Does the linear chain explain the record to its noise? The diagnosis's verdict
    (:func:`algid.diagnose` over :data:`CHECKED_EFFECTS`, on its quick grids): ``none`` (no candidate beyond
    noise, the withheld gap within :data:`FIT_FLOOR_RATIO` of the noise floor) or not.
    Returns ``gap``, ``noise_floor``, ``explains_record``, ``diagnosis`` (the effect and
    location it finds, or ``unknown``) and ``misfit``: the reason that makes the linear
    chain's determined estimates ``model_misfit`` ("" when it explains the record); and the
    diagnosis itself."""
    d = diagnose(rec, boundary, effects=CHECKED_EFFECTS, quick=True, notch=False)  # identify notched it
    out = {"gap": d.gap_before, "noise_floor": float(d.extra["noise_floor"]), "explains_record": d.effect == "none"}
    if d.effect == "none":
        return {**out, "diagnosis": "none", "misfit": ""}, d
    if d.best is None:
        found, hint = "unknown", "`algid diagnose` for where the gap sits"
    else:
        found = effect_label(effect_parts(d.effect, d.location, d.params, d.params_std))
        spec = " ".join(f"--effect {e}:{next(iter(loc.values()))}" for e, loc in _specs(d))
        hint = f"`algid diagnose` for the evidence, or `algid identify {spec}` for the chain with it"
    why = (
        f"the linear chain leaves a withheld gap of {d.gap_before:.3g}, {d.gap_before / out['noise_floor']:.3g}x "
        f"the noise floor, and the diagnosis's test finds {found}: run {hint}"
    )
    return {**out, "diagnosis": found, "misfit": why}, d


@dataclass(frozen=True)
class ModelCheck:
    """Identify's model check: ``result`` the fields of the :class:`~.result.Identification`
    beyond the recording's when the diagnosis's fit is the answer (the chain with the effects
    asked for; the linear chain of a record it does not explain), None when the estimators are
    to run; ``fit`` the check's ``model_fit`` for them, ``misfit`` its reason ("" when the linear
    chain explains the record); ``sig`` the signals the later stages read (realigned when the
    check found a multiplexed converter's channel skew: :func:`.screen.on_time_signals`)."""

    result: dict | None
    fit: dict
    misfit: str
    sig: Signals


def model_check(
    sig: Signals, nm: NoiseModel, boundary: str, effects: list, skipped: str, progress: Callable[[str], None]
) -> ModelCheck:
    """Identify's model check (module docstring), before any estimator runs: the fit with the
    ``effects``, else the fit check (``skipped``: why not, "" to run it) whose misfit makes the
    diagnosis's linear fit the answer: one linear fit per record, whichever command prints it.
    Not on an impact record: its check judges the chain identify estimates (:mod:`.impact_fit`).
    ``progress(stage)`` before each diagnosis."""
    note = ""
    if effects:
        progress("diagnose")
        fitted, note = fit_with_effects(sig.rec, sig.motion, sig.kind, nm, boundary, effects)
        if fitted is not None:
            return ModelCheck(fitted, {}, "", sig)
    if sig.transient is not None:
        return ModelCheck(None, {"source": note} if note else {}, "", sig)
    progress("withheld-window test")
    check, d = ({"misfit": ""}, None) if skipped else fit_check(sig.raw, boundary)
    sig = on_time_signals(sig, None if d is None else d.extra.get("timing"))
    misfit = check.pop("misfit")
    fit = {**check, **({"source": note} if note else {})}
    if misfit:
        fields = diagnosis_fields(
            sig.rec, sig.motion, sig.kind, nm, boundary, d, linear_model(d), "the linear chain", misfit
        )
        fields["model_fit"].update(check)
        return ModelCheck(fields, fit, misfit, sig)
    return ModelCheck(None, fit, misfit, sig)


def _specs(d) -> list[tuple[str, dict]]:
    parts = d.location.get("parts", [d.location])
    return list(zip(d.effect.split("+"), parts))


def _packed(cm: dict, key: str) -> np.ndarray:
    return np.array([math.nan if v is None else v for v in cm[key]], dtype=float)


def fit_with_effects(rec, motion, kind, nm, boundary: str, effects) -> tuple[dict | None, str]:
    """Stages 2 and 3 of the module docstring: the fields of an
    :class:`~.result.Identification` beyond the recording's (``plan, theta, sigma, ...,
    effects, model_fit``) and the line that says where the effects came from; ``None`` and
    the reason when ``auto`` finds no effect (the caller identifies the linear chain)."""
    auto = list(effects) == ["auto"]
    if "auto" in effects and not auto:
        raise ValueError("--effect auto takes the diagnosis's effect: give it alone")
    d = diagnose(rec, boundary, given=None if auto else list(effects), notch=False)  # identify notched it
    if d.best is None:
        return None, f"the diagnosis reports {d.effect!r}: no effect to add"
    cm = corrected_model(d)
    floor = float(d.extra["noise_floor"])
    label = effect_label(cm["effects"])
    misfit = ""
    if d.gap_after > FIT_FLOOR_RATIO * floor:
        misfit = (
            f"the chain with {label} leaves a withheld gap of {d.gap_after:.3g}, {d.gap_after / floor:.3g}x "
            "its noise floor: it does not explain this record; run `algid diagnose`"
        )
    source = (
        f"effect from the diagnosis (`--effect auto`): {label}, z = {d.best.z:.3g}"
        if auto
        else f"effect given: {label}"
    )
    fit = {"gap": d.gap_after, "noise_floor": floor, "explains_record": not misfit, "gap_linear": d.gap_before}
    fields = diagnosis_fields(rec, motion, kind, nm, boundary, d, cm, f"the chain with {label}", misfit)
    fields["model_fit"].update({**fit, "source": source})
    fields["effects"] = _effect_verdicts(cm["effects"], misfit, d.units)
    return fields, source


def diagnosis_plan(d, model: str, effects: bool) -> Plan:
    """The :class:`~.plan.Plan` that names the diagnosis ``d``'s fit of ``model`` (with effects or not)."""
    return Plan(
        estimator="augmented" if effects else "integral_equations",
        reason=f"{model}: the diagnosis's integral equations, {int(d.lin.cv.theta_folds.shape[0])} folds",
        window_s=d.P.L * d.P.dt,
        prefilter_hz=math.nan,
        stagger=1,
        window_basis=f"{d.P.form} form, band {d.band.f_hi:.4g} Hz",
        method="integral_equations",
    )


def diagnosis_fields(rec, motion, kind, nm, boundary: str, d, cm: dict, model: str, misfit: str) -> dict:
    """The fields of an :class:`~.result.Identification` beyond the recording's for the chain
    model ``cm`` the diagnosis ``d`` fitted (:mod:`algid.diagnosis.corrected`: the linear
    chain, or the chain with effects, named ``model``), judged with ``misfit`` (stage 3)."""
    n, forced = rec.n, np.any(rec.u != 0.0, axis=0)
    theta = np.concatenate([_packed(cm, k) for k in ("mass", "damping", "stiffness")])
    sigma = np.concatenate([_packed(cm, f"sigma_{k}") for k in ("mass", "damping", "stiffness")])
    mo = band_limited_motion(motion, kind, nm.dt, surrogate_band(nm, np.nan_to_num(theta), n, boundary))
    verdicts = [
        replace(v, reason=v.reason.replace("the linear chain does not fit", f"{model} does not fit"))
        for v in judge(theta, sigma, n, boundary, mo, rec.u, forced, nm, misfit=misfit)
    ]
    folds = int(d.lin.cv.theta_folds.shape[0])
    return {
        "plan": diagnosis_plan(d, model, bool(cm["effects"])),
        "theta": theta,
        "sigma": sigma,
        "raw": theta,
        "bias": np.zeros_like(theta),
        "method_bias": np.full_like(theta, np.nan),
        "verdicts": verdicts,
        "time_s": np.array([rec.t.size * rec.dt]),
        "history": theta[None],
        "history_sigma": sigma[None],
        "windows": folds,
        "replicates": 0,
        "effects": [],
        "model_fit": {"folds": folds},
        "diagnosis": d,
    }
