"""Base excitation (a shake table): the support moves, its motion is measured and the masses'
forces may be missing. The support is the left wall of eq. 1 with ``x_0`` no longer 0:

    m_1 a_1 + c_1 v_1 + k_1 (x_1 - x_0) + k_2 (x_1 - x_2) = u_1

(dampers to ground on the absolute velocities, as eq. 1 has them). That is exactly DOF 1's
equation of the (n+1)-DOF chain whose first mass is the support (DOF 0), and every DOF's
algebraic system uses only its own and its neighbours' motion and its force. So identify runs
its one path on that augmented chain (:func:`augment`) and drops DOF 0 afterwards
(:func:`reduce`). DOF 0's own equation holds the shaker's reaction, which no sensor reads; it
is given a force that makes it exact or keeps it out of the others' estimates:

* **No force on any DOF**: the record determines the chain up to a common scale only. DOF 0's
  force is ``kappa (x_0 - x_1)`` with ``kappa`` = :data:`KAPPA` (the double integral of
  ``a_0 - a_1``, or the single one of ``v_0 - v_1``, or ``x_0 - x_1`` itself): its equation holds
  exactly with ``m_0 = c_0 = k_0 = 0`` and ``k_1 = kappa`` (the polynomial an integral's start
  leaves is an initial condition, which every estimator eliminates), so the estimators scale
  the chain by ``k_1 = kappa`` (normalisation) through the springs, as one force would. The
  estimates are then the chain scaled so that ``k_1 = 1`` in the force unit per displacement
  unit; the ratios ``c_i / m_i``, ``k_i / m_i``, ``k_{i+1} / m_i`` and the modes (which depend
  only on ``M^-1 K`` and ``M^-1 C``) are the record's, the masses, dampings and springs
  themselves ``not_identifiable`` (:data:`SCALE_REASON`).
* **A force on some DOF**: it gives the scale; DOF 0 has no force, takes its scale from DOF 1
  and passes none on. The support's equation (the shaker's unmeasured reaction) must then stay
  out of the others': the single window and the paper's algebraic windows solve every DOF
  alone (the spring ``k_1`` is DOF 1's own estimate, DOF 0 having taken its scale through it),
  the weak form's joint solve would pool it, so the plan takes the algebraic windows
  (:func:`.plan.make_plan` with ``joint=False``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..model.chain import parameter_names
from ..recording import Recording, accelerations, base_acceleration
from ..recording import motion as recording_motion

#: Scale given to the chain without a force: DOF 0's force is ``KAPPA (x_0 - x_1)``, so ``k_1 = KAPPA``.
KAPPA = 1.0
SCALE_REASON = "base excitation without a force: the chain is known up to scale (only ratios and modes)"
#: Why identify's fit check (the diagnosis's withheld-window test) does not run on a base-excited
#: record: it tests every equation, the support's too, which holds the shaker's unmeasured reaction
#: (with a force) or the double integral of the accelerations' noise (without: no white force
#: noise, as its noise floor assumes, so a linear chain would fail it).
FIT_CHECK_SKIPPED = (
    "not run: the diagnosis's test would take in the support's equation, whose force is the shaker's "
    "unmeasured reaction; the verdicts do not include the fit check"
)
_ORDER = {"acceleration": 2, "velocity": 1, "displacement": 0}


def cumulative_integral(y: np.ndarray, dt: float) -> np.ndarray:
    """``int_0^t y`` at every sample, 0 at the first: each interval integrates the cubic through
    the four samples around it (``(-y_{k-1} + 13 y_k + 13 y_{k+1} - y_{k+2}) dt / 24``; the end
    intervals the cubic through the first or last four), error ``O(dt^5)`` per interval."""
    y = np.asarray(y, dtype=float)
    if y.size < 4:
        raise ValueError("need at least 4 samples")
    inner = (-y[:-3] + 13 * y[1:-2] + 13 * y[2:-1] - y[3:]) / 24
    first = (9 * y[0] + 19 * y[1] - 5 * y[2] + y[3]) / 24
    last = (9 * y[-1] + 19 * y[-2] - 5 * y[-3] + y[-4]) / 24
    return np.concatenate([[0.0], np.cumsum(np.concatenate([[first], inner, [last]])) * dt])


def augment(rec: Recording) -> tuple[Recording, str]:
    """The (n+1)-DOF record ``[support, DOF 1..n]`` of a base-excited record and
    :data:`SCALE_REASON` when it has no force ("" otherwise). The motions keep their kind when
    the support's is the DOFs' (``x0`` beside ``x1..xn``); otherwise both are accelerations."""
    kind, y = recording_motion(rec)
    if rec.base_kind == kind[0]:
        y0 = rec.base
    else:
        kind, y, y0 = "acceleration", accelerations(rec), base_acceleration(rec)
    scale = "" if np.any(rec.u != 0.0) else SCALE_REASON
    u0 = np.zeros(rec.t.size)
    if scale:
        u0 = y0 - y[:, 0]
        for _ in range(_ORDER[kind]):
            u0 = cumulative_integral(u0, float(rec.dt))
        u0 = KAPPA * u0
    motions = {kind[0]: np.column_stack([y0, y])}
    note = "base excitation: the support is DOF 0 of the estimated chain" + (", scaled by k1 = 1" if scale else "")
    out = Recording(
        t=rec.t,
        u=np.column_stack([u0, rec.u]),
        dt=rec.dt,
        path=rec.path,
        units={role: label for role, label in rec.units.items() if role != "time"},
        notes=[*rec.notes, note],
        **motions,
    )
    return out, scale


def _kept(n: int) -> np.ndarray:
    """Packed indices of DOF 1..n in the (n+1)-DOF chain (``m_0``, ``c_0``, ``k_0`` dropped)."""
    N = n + 1
    return np.r_[1:N, N + 1 : 2 * N, 2 * N + 1 : 3 * N + 1]


def _renamed(verdicts: list, n: int, scale: str) -> list:
    """DOF 1..n's verdicts under their own names; without a scale, every determined
    parameter ``not_identifiable`` (:data:`SCALE_REASON`, its shares kept)."""
    out = []
    for v in (verdicts[p] for p in _kept(n)):
        name = f"{v.name[0]}{int(v.name[1:]) - 1}"
        if scale and v.status not in ("known", "not_separable"):
            out.append(replace(v, name=name, status="not_identifiable", reason=scale))
        else:
            out.append(replace(v, name=name))
    return out


def ratios(theta: np.ndarray, sigma: np.ndarray, n: int, boundary: str) -> dict[str, tuple[float, float]]:
    """``{"c1/m1": (value, std), "k1/m1": .., "k2/m1": .., ...}`` of packed estimates: what a
    record without scale determines. The std combines the two relative uncertainties as if
    independent."""
    m, c, k = theta[:n], theta[n : 2 * n], theta[2 * n :]
    sm, sc, sk = sigma[:n], sigma[n : 2 * n], sigma[2 * n :]
    out = {}
    for i in range(n):
        springs = (i, i + 1) if not (boundary == "free" and i == n - 1) else (i,)
        for name, value, sd in [(f"c{i + 1}", c[i], sc[i])] + [(f"k{j + 1}", k[j], sk[j]) for j in springs]:
            r = value / m[i]
            out[f"{name}/m{i + 1}"] = (float(r), float(abs(r) * np.hypot(sd / value, sm[i] / m[i])))
    return out


def reduce(result, scale: str, verdicts_aug: list, check_skipped: str = ""):
    """The :class:`~.result.Identification` of DOF 1..n from that of the augmented chain
    (``verdicts_aug`` its verdicts before any blanking)."""
    n = result.n - 1
    keep = _kept(n)
    nm = result.noise
    fit = dict(result.model_fit)
    if check_skipped:
        fit = {"explains_record": None, "skipped": check_skipped}
    return replace(
        result,
        n=n,
        theta=result.theta[keep],
        sigma=result.sigma[keep],
        raw=result.raw[keep],
        bias=result.bias[keep],
        method_bias=result.method_bias[keep],
        verdicts=_renamed(verdicts_aug, n, scale),
        history=result.history[:, keep],
        history_sigma=result.history_sigma[:, keep],
        noise=replace(nm, forces=nm.forces[1:], motions=nm.motions[1:]),
        model_fit=fit,
        scale=scale,
        ratios=_judged_ratios(result, keep, verdicts_aug, n) if scale else {},
    )


def _judged_ratios(result, keep: np.ndarray, verdicts_aug: list, n: int) -> dict[str, dict]:
    """The ratios (:func:`ratios`) with ``valid``: both estimates they divide were valid."""
    theta, sigma = result.theta[keep], result.sigma[keep]
    valid = {name: verdicts_aug[p].valid for name, p in zip(parameter_names(n), keep)}
    out = {}
    for name, (value, sd) in ratios(theta, sigma, n, result.boundary).items():
        top, bottom = name.split("/")
        out[name] = {"value": value, "sigma": sd, "valid": bool(valid[top] and valid[bottom])}
    return out
