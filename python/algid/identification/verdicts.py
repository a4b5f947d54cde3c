"""Is each estimate physically admissible, and does the record determine it?

Every parameter is measured against the force it stands for in the record: its
*share* is ``|theta| s / F`` and its *uncertainty share* ``sigma s / F``, with ``s`` the
standard deviation of its regressor in the signal band (the surrogate motion of
:mod:`.surrogate`: acceleration for a mass, velocity for a damping, deformation for a
spring) and ``F`` that of the recorded force on its DOF (the larger of the two DOF a spring
joins). Statuses, in the order they are tested:

* ``known``: a spring fixed by the model (free right end: 0); ``not_separable``: k2 of one
  DOF between walls (only k1 + k2 is identifiable; it is reported as k1).
* ``not_identifiable``: the DOF has no scale (only ratios of its parameters are determined):
  it carries no force and, when the estimator carries the scale along the springs (the weak
  form's joint solve; the single window and the algebraic windows, whose DOF without force
  take their mass from the spring they share with a scaled neighbour), no interior spring
  joins it to a DOF that has one (:func:`scaled_dofs`: a spring estimated in both equations
  it enters passes the scale on, so one force scales a whole chain; its force scale ``F`` is
  then the largest in-band term of its equation); the estimator
  returned no value; the uncertainty share exceeds :data:`UNDETERMINED`; a damping or spring
  consistent with zero (within three sigma) whose three sigma stand for more than
  :data:`ZERO_BOUND` of the force. A mass is not identifiable unless it is above zero by
  three sigma, its relative uncertainty is at most :data:`RELATIVE` and its term is not
  negligible (inertia is then not determined by the record: quasi-static, or the
  acceleration lost in the noise).
* ``inadmissible``: a mass below zero by three sigma, or a damping or spring below zero by
  three sigma, that is not negligible: eq. 1 does not fit the record.
* ``model_misfit``: the fitted model does not explain the record to its noise (``misfit``,
  the diagnosis's withheld-window test, :func:`.augmented.fit_check`, or on an impact record
  the chain's output error over the decays, :mod:`.impact_fit`): the estimate is
  biased by what the model leaves out; this verdict takes precedence over every other but
  ``known`` and ``not_separable`` wherever the fit gives a value. (The window results' scatter beyond the noise
  scales the standard deviations up, :mod:`.uncertainty`; it is no verdict of its own:
  coloured sensor noise scatters them too.)
* ``negligible``: the share plus three uncertainty shares stays below :data:`NEGLIGIBLE`,
  or a damping or spring is consistent with zero within :data:`ZERO_BOUND` of the force:
  the term does not matter in this record (the spring of an axis without one); valid.
* ``ok``: valid.

A DOF is valid when its mass, damping and both springs are ``ok``, ``negligible``,
``known`` or ``not_separable``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..model.chain import dof_parameter_names, parameter_names, spring_deformation
from ..recording.noise import NoiseModel
from .motion import Motion
from .screen import Signals

if TYPE_CHECKING:  # uncertainty imports this module (through estimate)
    from .uncertainty import Uncertainty

#: Uncertainty share above which a parameter is not determined by the record.
UNDETERMINED = 0.2
#: Relative uncertainty above which a non-negligible parameter is not determined.
RELATIVE = 0.5
#: Share below which a term does not matter in the record.
NEGLIGIBLE = 0.01
#: A damping or spring consistent with zero is determined (as zero) when three sigma of it
#: stand for at most this share of the force.
ZERO_BOUND = 0.05
#: In-band acceleration over its in-band noise below which inertia is lost in the noise.
ACCEL_SNR = 3.0

VALID = ("ok", "negligible", "known", "not_separable")
STATUSES = ("ok", "negligible", "known", "not_separable", "not_identifiable", "inadmissible", "model_misfit")
DIAGNOSE = "the linear chain does not fit this record, run `algid diagnose`"


@dataclass(frozen=True)
class Verdict:
    """Status of one parameter (module docstring) and the one-line reason when it is not
    ``ok``; ``share`` and ``sigma_share`` as defined there (nan where undefined)."""

    name: str
    status: str
    reason: str
    share: float
    sigma_share: float

    @property
    def valid(self) -> bool:
        return self.status in VALID


def accel_noise_in_band(nm: NoiseModel, i: int) -> float:
    """Standard deviation of the noise the estimator sees on acceleration i in the band
    ``[0, f_hi]`` [m/s^2]: a white floor for a measured acceleration, the differentiated
    floor (``(2 pi f)^2`` or ``(2 pi f)^4`` times the velocity or displacement floor) for a
    derived one."""
    ch, f = nm.motions[i], nm.f_hi
    order = {"acceleration": 0, "velocity": 1, "displacement": 2}[nm.motion]
    # int_0^f (2 pi g)^(2 order) floor dg
    return float(np.sqrt(ch.floor_psd * (2 * np.pi) ** (2 * order) * f ** (2 * order + 1) / (2 * order + 1)))


def _mass_reason(m: float, share: float, snr: float) -> str:
    if snr < ACCEL_SNR:
        return "mass not identifiable: the acceleration is at the noise floor in the forced band"
    if share < 0.05:
        return (
            f"mass not identifiable: the inertia force is {100 * share:.2g} % of the force in the band "
            "(the record is quasi-static)"
        )
    return "mass not identifiable: not determined by the record"


def scaled_dofs(forced: np.ndarray, n: int, joint: bool) -> np.ndarray:
    """(n,) DOFs whose equation has a scale: the forced ones and, when the estimator carries
    the scale along the springs (``joint``: the weak form's joint solve, and the single window
    and algebraic windows of ChainEstimator), every DOF joined to one of them by interior
    springs: a spring estimated in both equations it enters carries the scale across."""
    scaled = np.asarray(forced, dtype=bool).copy()
    while joint:
        joined = [(j - 2, j - 1) for j in range(2, n + 1) if scaled[j - 2] != scaled[j - 1]]
        for a, b in joined:
            scaled[a] = scaled[b] = True
        joint = bool(joined)
    return scaled


def _force_scales(theta: np.ndarray, n: int, mo: Motion, u: np.ndarray, forced: np.ndarray, scaled) -> np.ndarray:
    """(n,) force standard deviation per DOF: the recorded force where there is one; on a DOF
    scaled through its springs, the largest in-band term of its equation (inertia, damping or
    a spring force, from ``theta``); 0 elsewhere."""
    F = np.where(forced, np.std(u, axis=0), 0.0)
    th = np.nan_to_num(np.asarray(theta, dtype=float))
    for i in np.flatnonzero(scaled & ~forced):
        terms = [th[i] * np.std(mo.a[:, i]), th[n + i] * np.std(mo.v[:, i])]
        terms += [th[2 * n + j - 1] * np.std(spring_deformation(mo.x, j, n)) for j in (i + 1, i + 2)]
        F[i] = max(abs(t) for t in terms)
    return F


def scales(
    n: int,
    boundary: str,
    mo: Motion,
    u: np.ndarray,
    forced: np.ndarray,
    theta: np.ndarray | None = None,
    scaled: np.ndarray | None = None,
) -> tuple[np.ndarray, list]:
    """Per packed parameter: ``s / F`` (regressor over force standard deviation, module
    docstring; NaN where no DOF it enters is scaled) and the DOF it belongs to. ``scaled``
    (:func:`scaled_dofs`, default the forced DOFs) with ``theta`` for the DOFs scaled through
    their springs."""
    scaled = np.asarray(forced, dtype=bool) if scaled is None else scaled
    F = _force_scales(np.zeros(3 * n + 1) if theta is None else theta, n, mo, u, np.asarray(forced, bool), scaled)
    ratio, dofs = [], []
    for name in parameter_names(n):
        fam, idx = name[0], int(name[1:]) - 1
        if fam == "k":
            near = [i for i in (idx - 1, idx) if 0 <= i < n]
            reg = np.std(spring_deformation(mo.x, idx + 1, n))
        else:
            near = [idx]
            reg = np.std(mo.a[:, idx] if fam == "m" else mo.v[:, idx])
        force = max((F[i] for i in near if scaled[i]), default=0.0)
        ratio.append(reg / force if force > 0 else np.nan)
        dofs.append(near)
    return np.array(ratio), dofs


def judge(
    theta: np.ndarray,
    sigma: np.ndarray,
    n: int,
    boundary: str,
    mo: Motion,
    u: np.ndarray,
    forced: np.ndarray,
    nm: NoiseModel,
    joint: bool = False,
    misfit: str = "",
) -> list[Verdict]:
    """One :class:`Verdict` per packed parameter ``m1..mn, c1..cn, k1..k{n+1}``; ``joint``:
    the estimator carries the scale along the springs, so an unforced DOF takes its scale
    from them (:func:`scaled_dofs`); ``misfit``: why the fitted model does not explain the
    record to its noise (the withheld-window test), which makes every determined estimate
    ``model_misfit``."""
    scaled = scaled_dofs(forced, n, joint)
    ratio, dofs = scales(n, boundary, mo, u, forced, theta, scaled)
    out: list[Verdict] = []
    for p, name in enumerate(parameter_names(n)):
        fam, idx = name[0], int(name[1:]) - 1
        if fam == "k" and idx == n and boundary == "free":
            out.append(Verdict(name, "known", f"free right end: k{n + 1} = 0", np.nan, np.nan))
        elif fam == "k" and n == 1 and boundary == "fixed" and idx == 1:
            out.append(
                Verdict(
                    name,
                    "not_separable",
                    "one DOF between walls: only k1 + k2 is identifiable, reported as k1",
                    np.nan,
                    np.nan,
                )
            )
        else:
            v = _one(
                name,
                fam,
                float(theta[p]),
                float(sigma[p]),
                ratio[p],
                dofs[p],
                [i for i in dofs[p] if scaled[i]],
                mo,
                nm,
                joint,
            )
            valued = v.status == "not_identifiable" and math.isfinite(v.share)  # a value the misfit spreads
            if misfit and (v.status in ("ok", "negligible", "inadmissible") or valued):
                v = Verdict(name, "model_misfit", f"{_WHAT[fam]} biased: {misfit}", v.share, v.sigma_share)
            out.append(v)
    return out


@dataclass(frozen=True)
class Judged:
    """Identify's verdicts and the estimates as reported: ``theta``, ``sigma`` (3n+1,) with no
    value (NaN) where the record has no scale for it (an unforced DOF) or the estimator's
    systems were singular."""

    verdicts: list
    theta: np.ndarray
    sigma: np.ndarray


def judge_estimate(unc: Uncertainty, sig: Signals, nm: NoiseModel, boundary: str, misfit: str = "") -> Judged:
    """Identify's verdicts stage: :func:`judge` of the estimate with its uncertainty ``unc``
    on the record ``sig``; every estimator carries the scale along the springs (the weak form's
    joint solve; the single window and the algebraic windows through eq. 7's ratios)."""
    u = sig.rec.u
    verdicts = judge(unc.theta, unc.sigma, sig.rec.n, boundary, unc.motion, u, sig.forced, nm, True, misfit)
    blank = np.array([v.status == "not_identifiable" and not np.isfinite(v.share) for v in verdicts])
    return Judged(verdicts, np.where(blank, np.nan, unc.theta), np.where(blank, np.nan, unc.sigma))


_WHAT = {"m": "mass", "c": "damping", "k": "stiffness"}


def _one(name, fam, th, sg, ratio, dofs, dofs_f, mo, nm, joint) -> Verdict:
    what = _WHAT[fam]
    if not dofs_f:
        where = " and ".join(str(i + 1) for i in dofs)
        how = "nor a spring path to a forced DOF" if joint else "and its equation is solved alone, so it has no scale"
        return Verdict(
            name,
            "not_identifiable",
            f"{what} not identifiable: no force on DOF {where} {how}; only ratios of its parameters are determined",
            np.nan,
            np.nan,
        )
    if not (np.isfinite(th) and np.isfinite(sg)):
        return Verdict(
            name,
            "not_identifiable",
            f"{what} not identifiable: the estimator's systems were singular "
            "throughout (the record does not excite this DOF enough)",
            np.nan,
            np.nan,
        )
    share = abs(th) * ratio
    ss = sg * ratio
    tiny = share + 3 * ss <= NEGLIGIBLE
    rel = sg / abs(th) if th != 0 else np.inf
    if fam == "m":
        i = dofs[0]
        snr = np.std(mo.a[:, i]) / max(accel_noise_in_band(nm, i), 1e-300)
        if th < -3 * sg and not tiny and ss <= UNDETERMINED:
            return Verdict(name, "inadmissible", f"negative mass: {DIAGNOSE}", share, ss)
        if th <= 3 * sg or tiny or ss > UNDETERMINED or rel > RELATIVE:
            return Verdict(name, "not_identifiable", _mass_reason(th, share, snr), share, ss)
        return Verdict(name, "ok", "", share, ss)
    if ss > UNDETERMINED:
        return Verdict(
            name,
            "not_identifiable",
            f"{what} not identifiable: its uncertainty is {100 * ss:.2g} % of the force in the band",
            share,
            ss,
        )
    if th < -3 * sg and not tiny:
        return Verdict(name, "inadmissible", f"negative {what}: {DIAGNOSE}", share, ss)
    if abs(th) <= 3 * sg:
        if 3 * ss <= ZERO_BOUND:
            return Verdict(
                name,
                "negligible",
                f"{what} consistent with zero: |{name}| < {3 * sg:.3g} (three "
                f"sigma), {100 * 3 * ss:.2g} % of the force at most",
                share,
                ss,
            )
        return Verdict(
            name,
            "not_identifiable",
            f"{what} not identifiable: consistent with zero within {100 * 3 * ss:.2g} % of the force (three sigma)",
            share,
            ss,
        )
    if tiny:
        return Verdict(
            name,
            "negligible",
            f"{what} negligible: it stands for {100 * (share + 3 * ss):.2g} % of the force at most (three sigma)",
            share,
            ss,
        )
    return Verdict(name, "ok", "", share, ss)


def dof_validity(verdicts: list[Verdict], n: int, network=None) -> np.ndarray:
    """(n,) a DOF is valid when its m, c and both springs (a ``network``'s: every spring on
    it) are valid (module docstring)."""
    by = {v.name: v for v in verdicts}

    def names(i: int) -> list[str]:
        if network is None:
            return dof_parameter_names(i)
        return [f"m{i + 1}", f"c{i + 1}"] + [f"k{s}" for s, _, _ in network.incident(i + 1)]

    return np.array([all(by[k].valid for k in names(i)) for i in range(n)])
