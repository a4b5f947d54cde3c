"""``algid.identify(rec, topology=net)``: a spring network (:class:`algid.model.network.Network`)
identified by the diagnosis's windowed equation-error fit (the estimator a chain record gets
when the linear chain misfits it, :mod:`.augmented`), then by output error.

1. Screen and noise model as for a chain (:mod:`.engine`, stages 1-2).
2. The fit check (:func:`.augmented.fit_check` on the network): the diagnosis's equations of
   every DOF with the springs incident on it, cross-validated over the folds; then all of them
   in one joint fit (:mod:`algid.diagnosis.joint`, through
   :func:`algid.diagnosis.corrected.linear_model`): each spring one unknown of both DOFs it
   joins, the equations weighted by their error variances, a DOF without force scaled along
   its springs from a forced one; standard deviations by the jackknife over the folds.
3. The joint fit refined by output error (:mod:`.output_error`): the network simulated under
   the recorded forces and fitted to the recorded accelerations by Gauss-Newton, its standard
   deviations those of the Gauss-Newton covariance. Kept only where its assumptions hold
   (:func:`output_error`): every DOF's residual is its accelerometer's white noise, within
   :data:`FLOOR_RATIO`. Noise on the forces, which the simulation passes through the network's
   resonances, shows as a larger residual; the joint fit stays the answer then, as it does for
   a DOF without scale or a record of velocities or displacements.
4. Verdicts (:func:`judge_network`): what the topology and the forces cannot give
   (:meth:`~algid.model.network.Network.identifiability`: springs in parallel give their sum,
   reported in the first of them; a DOF without force nor a path of springs to one has no
   scale) gets its reason; a mass above zero by three sigma, a damping or spring not below zero
   by three sigma, each with a relative uncertainty of at most :data:`.verdicts.RELATIVE`, is
   ``ok`` when the fit check passes or the output error is kept (the network then predicts
   every DOF's acceleration to its noise, the stronger test of the two), ``model_misfit``
   otherwise.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..diagnosis.corrected import linear_model
from ..model.network import Network
from ..recording.noise import analyse
from .augmented import diagnosis_plan, fit_check
from .output_error import refine
from .screen import on_time_signals, screened_signals
from .verdicts import RELATIVE, Verdict


def refuse_chain_options(boundary: str = "fixed", estimator: str = "auto", effects=()) -> None:
    """A one-line ``ValueError`` when an option of the chain's comes with a network: a boundary
    other than ``fixed``, an estimator other than ``auto``, effects."""
    given = [
        flag
        for flag, on in (
            ("--boundary", boundary != "fixed"),
            ("--estimator", estimator != "auto"),
            ("--effect", bool(effects)),
        )
        if on
    ]
    if given:
        raise ValueError(
            f"{', '.join(given)}: the chain's, not with --topology "
            "(a network's joint fit has no boundary or estimator and takes no effects)"
        )


def _parallel_reasons(net: Network) -> dict[str, str]:
    """``k<s>`` -> reason for every spring of a parallel group: the sum is reported in the first."""
    out = {}
    for group in net.parallel_groups():
        if len(group) > 1:
            names = [f"k{s}" for s in group]
            a, b = net.springs[group[0] - 1]
            for s in group:
                out[f"k{s}"] = (
                    f"{' + '.join(names)} in parallel between {'ground' if not a else f'DOF {a}'} and "
                    f"{'ground' if not b else f'DOF {b}'}: only their sum is identifiable; it is reported as {names[0]}"
                )
    return out


def _determined(name: str, value: float, sd: float) -> tuple[str, str]:
    """``(status, reason)`` of an estimate the record can give (module docstring, step 3)."""
    what = {"m": "mass", "c": "damping", "k": "spring"}[name[0]]
    if not (math.isfinite(value) and math.isfinite(sd)):
        return "not_identifiable", f"{what} not identifiable: the fit gives no value"
    if value < -3 * sd or (name[0] == "m" and value <= 0):
        return "inadmissible", f"{what} {value:.4g} +- {sd:.2g} is below zero: the network does not fit the record"
    if sd > RELATIVE * abs(value):
        return "not_identifiable", f"{what} not identifiable: {value:.4g} +- {sd:.2g} is not determined by the record"
    return "ok", ""


def judge_network(theta: np.ndarray, sigma: np.ndarray, net: Network, forced, misfit: str) -> list[Verdict]:
    """One :class:`~.verdicts.Verdict` per packed parameter ``m1..mn, c1..cn, k1..kS`` (module
    docstring, step 3); ``forced`` the 1-based DOFs with a force, ``misfit`` the fit check's
    reason ("" when the network explains the record)."""
    parallel = _parallel_reasons(net)
    reasons = net.identifiability(forced=forced)
    out = []
    for name, value, sd in zip(net.parameter_names(), theta, sigma):
        if name in parallel:
            status, why = "not_separable", parallel[name]
        elif name in reasons:
            status, why = "not_identifiable", f"not identifiable: {reasons[name]}"
        else:
            status, why = _determined(name, float(value), float(sd))
            if misfit and status != "not_identifiable":
                status, why = "model_misfit", misfit.replace("the linear chain", "the linear network")
        out.append(Verdict(name, status, why, math.nan, math.nan))
    return out


#: The output error is kept when no DOF's residual exceeds its accelerometer's white-noise floor
#: by more than this factor: then the recorded forces carry no noise that matters and the
#: residual is the white sensor noise the Gauss-Newton covariance assumes.
FLOOR_RATIO = 1.15


def output_error(d, net: Network, theta: np.ndarray, sigma: np.ndarray, floor) -> tuple:
    """Step 3 of the module docstring: the joint fit ``theta, sigma`` refined by output error
    on the diagnosis's record (:func:`.output_error.refine`), kept when every mass and damper
    has a value, the masses stay positive and every DOF's residual RMS is within
    :data:`FLOOR_RATIO` of its accelerometer's noise ``floor`` (n,) [m/s^2] (None: a record of
    velocities or displacements, not refined). Returns ``theta, sigma`` and a summary
    (``kept``, ``residual_over_floor``: the largest ratio, None when the refinement failed) or
    None when not tried."""
    n = net.n
    if floor is None or not np.all(np.isfinite(theta[: 2 * n])):
        return theta, sigma, None
    new, new_sigma, resid = refine(net, theta, d.P.a_full, d.P.u_full, d.P.dt)
    ratio = float(np.max(resid / np.maximum(floor, 1e-300)))
    kept = bool(np.all(np.isfinite(new[np.isfinite(theta)])) and np.all(new[:n] > 0) and ratio <= FLOOR_RATIO)
    summary = {"kept": kept, "residual_over_floor": ratio if math.isfinite(ratio) else None}
    return (new, new_sigma, summary) if kept else (theta, sigma, summary)


def identify_network(rec, net: Network, progress) -> dict:
    """The fields of an :class:`~.result.Identification` of record ``rec`` on the network
    ``net`` (module docstring); ``progress(stage)`` before each stage."""
    if rec.base is not None:
        raise ValueError("a base-excited record (support motion a0) is identified as a chain only")
    sig = screened_signals(rec, None)
    if sig.transient is not None:
        raise ValueError("an impact record is identified as a chain only: the diagnosis's windows do not fit a decay")
    nm = analyse(sig.rec.u, sig.motion, sig.dt, sig.kind)
    progress("withheld-window test")
    check, d = fit_check(sig.raw, net)
    sig = on_time_signals(sig, d.extra.get("timing"))
    misfit = check.pop("misfit")
    cm = linear_model(d)
    theta = np.array([math.nan if v is None else v for v in cm["mass"] + cm["damping"] + cm["stiffness"]])
    sigma = np.array(
        [math.nan if v is None else v for v in cm["sigma_mass"] + cm["sigma_damping"] + cm["sigma_stiffness"]]
    )
    progress("output error")
    floor = np.array([c.sigma for c in nm.motions]) if nm.motion == "acceleration" else None
    theta, sigma, oe = output_error(d, net, theta, sigma, floor)
    if oe and oe["kept"]:  # every DOF's acceleration predicted to its noise: the network explains the record
        misfit = ""
    forced = [i + 1 for i in np.nonzero(np.any(sig.rec.u != 0.0, axis=0))[0]]
    folds = int(d.lin.cv.theta_folds.shape[0])
    plan = diagnosis_plan(d, "the linear network", False)
    return {
        "sig": sig,
        "noise": nm,
        "plan": replace(plan, reason=f"{plan.reason}, refined by output error") if oe and oe["kept"] else plan,
        "theta": theta,
        "sigma": sigma,
        "raw": theta,
        "bias": np.zeros_like(theta),
        "method_bias": np.full_like(theta, np.nan),
        "verdicts": judge_network(theta, sigma, net, forced, misfit),
        "time_s": np.array([sig.rec.t.size * sig.rec.dt]),
        "history": theta[None],
        "history_sigma": sigma[None],
        "windows": folds,
        "replicates": 0,
        "model_fit": {**check, "folds": folds, **({"output_error": oe} if oe else {})},
        "diagnosis": d,
    }
