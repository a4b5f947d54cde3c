"""``algid.identify(rec, topology=net)``: a spring network (:class:`algid.model.network.Network`)
identified by the diagnosis's windowed equation-error fit, the estimator a chain record gets
when the linear chain misfits it (:mod:`.augmented`).

1. Screen and noise model as for a chain (:mod:`.engine`, stages 1-2).
2. The fit check (:func:`.augmented.fit_check` on the network): the diagnosis's equations of
   every DOF with the springs incident on it, cross-validated over the folds; then all of them
   in one joint fit (:mod:`algid.diagnosis.joint`, through
   :func:`algid.diagnosis.corrected.linear_model`): each spring one unknown of both DOFs it
   joins, the equations weighted by their error variances, a DOF without force scaled along
   its springs from a forced one; standard deviations by the jackknife over the folds.
3. Verdicts (:func:`judge_network`): what the topology and the forces cannot give
   (:meth:`~algid.model.network.Network.identifiability`: springs in parallel give their sum,
   reported in the first of them; a DOF without force nor a path of springs to one has no
   scale) gets its reason; a mass above zero by three sigma, a damping or spring not below zero
   by three sigma, each with a relative uncertainty of at most :data:`.verdicts.RELATIVE`, is
   ``ok`` when the fit check passes, ``model_misfit`` when it does not.
"""

from __future__ import annotations

import math

import numpy as np

from ..diagnosis.corrected import linear_model
from ..model.network import Network
from ..recording.noise import analyse
from .augmented import diagnosis_plan, fit_check
from .screen import on_time_signals, screened_signals
from .verdicts import RELATIVE, Verdict


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
    forced = [i + 1 for i in np.nonzero(np.any(sig.rec.u != 0.0, axis=0))[0]]
    folds = int(d.lin.cv.theta_folds.shape[0])
    return {
        "sig": sig,
        "noise": nm,
        "plan": diagnosis_plan(d, "the linear network", False),
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
        "model_fit": {**check, "folds": folds},
        "diagnosis": d,
    }
