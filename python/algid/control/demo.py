"""``algid demo``: the paper's section 3-4 experiment end to end.

The Table 1 chain (5 s) tracks Bezier rest-to-rest references with the controller of
eqs. 8-10; until 0.1 s the controller uses ``m = 1 kg``, ``c = k = 0``, afterwards the
on-line estimates of the C++ estimator, which sees only the sampled accelerations and
recorded forces (see :mod:`algid.simulator` for the sampling convention). The demo prints
the true and estimated parameters at 0.1 s and at the end, when each estimate first
reaches and when it finally stays within 1 % of the truth, the RMS and peak tracking
errors, and the force overshoot at the substitution; it writes the figures as PNG and
the numbers as ``summary.json`` into ``--out``.

**Estimators** (``--estimator``). ``single`` is the paper's: one growing window from
t = 0 (``algid.ChainEstimator``), substituted under the controller's ``accept="settled"``
rule. ``continuous`` is :class:`algid.control.controller.ContinuousAdapter` over
``algid.ContinuousEstimator`` (staggered 0.3 s windows, running estimate with a one-sigma
uncertainty); until the running estimate exists (after its first window) it serves the growing window.
The controller (``accept="sigma"``) substitutes the estimates of DOF ``i`` when all of
``m_i, c_i, k_i, k_{i+1}`` are physically admissible and their relative one-sigma
uncertainty is at most 5 % (the damping's against at least 1 % of critical damping); the
first substitution waits until every DOF passes; afterwards each DOF follows the running
estimate while it passes and keeps its last passing values otherwise. ``auto`` (default)
is ``continuous`` with ``--noise-db`` or in ``--mode sampled`` and ``single`` otherwise, so
the noise-free continuous-mode demo is the paper's.

**Rig** (``--mode sampled --actuator-lag-ms L``). The DAC holds the command between samples
and a first-order actuator of time constant ``L`` follows it; the force sensors read the
actuator's output. The controller is not told ``L``: it identifies the lag from its own
commands and the measured forces (:class:`algid.control.held_input.LagEstimator`, exact on the
simulated actuator), its eq. 10 integrates the measured force and its estimator gets the
smooth-equivalent samples of :class:`algid.control.held_input.HeldLaggedInput`; the probe (below)
is on by default there too. Three rig defaults differ from the paper's set-up: eq. 10 gets
the position feedback (10c) of :mod:`algid.control.controller` (``velocity_pole`` =
:data:`RIG_VELOCITY_POLE`, 40 rad/s); the running estimate is the weak-form one with 0.3 s
windows and test functions up to 30 Hz; and the growing window that serves until then counts
as valid only while steady within 1 % over 20 ms (:data:`RIG_ESTIMATOR_OPTIONS`).

**Noise** (``--noise-db``). The SNR is meant on the accelerations the estimator actually
gets. The simulator has to fix a closed loop's noise level before the run, from the
planned motion (the reference accelerations); when the loop tracks, the actual
accelerations are the planned ones plus the probe's (below), so the demo first runs the
same loop noise-free and scales each accelerometer's noise to that run's acceleration RMS.
The SNR achieved on the noisy run's actual accelerations is reported next to the request.

**Probe** (``--excitation``). Under accelerometer noise the paper's references alone carry
too little information for either estimator. With ``--noise-db`` (and in sampled mode)
the controller therefore adds a known multisine force (:class:`algid.control.trajectories.Multisine`, six lines of
3-16 Hz, ``--excitation`` N each, default 0.05 N) to its command; its motion is in the
reported tracking error. Noise-free in continuous mode the default is no probe (the paper's
experiment).

The measured figures of the demo are in ``docs/demo.md``, built from
``bench/results/demo_report.json`` (``bench/demo_report.py``).

**Drift table.** Both estimators are also run open loop on the recorded samples
(accelerations and forces as the loop's estimator got them), and the demo reports the
largest relative error of each at 0.1, 0.5, 1 and 5 s: how far the single window drifts
under noise against the continuous running estimate.

``--topology NET.json`` runs a spring network instead, open loop (the closed loop above is the
chain's): :mod:`.network_demo`.

For ``--n`` other than 3 the chain repeats Table 1's values (masses 2.0, 2.5, 3.0 kg,
dampings 5.5, 5.0, 4.5 N s/m, stiffnesses 1000, 900, 900, 700 N/m, each list cycled to
length ``n`` or ``n + 1``) and the targets repeat ``(+5, +5, -5) mm``. For ``n = 1`` with
walls only ``k_1 + k_2`` is identifiable and is reported as ``k1``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..messages import one_line
from ..messages.progress import Progress
from ..model.chain import TABLE1, Chain, parameter_names

__all__ = ["add_parser", "run", "demo_chain", "run_scenario", "summarize", "settle_time", "format_summary", "jsonable"]

#: The controller's ``--mode`` and the ``--estimator`` in words that keep them apart (both
#: have a "continuous"): the summary's and the figures' titles.
CONTROL_WORDS = {"continuous": "continuous-time control", "sampled": "sampled control"}
ESTIMATOR_WORDS = {"single": "single-window estimator", "continuous": "continuous estimator"}

#: Relative accuracy an estimate must reach [-].
TOLERANCE = 0.01

#: Times [s] of the drift table.
DRIFT_TIMES_S = (0.1, 0.5, 1.0, 5.0)

#: Default probe amplitude per multisine line [N] when the accelerometers are noisy.
DEFAULT_EXCITATION_N = 0.05

#: Position feedback of eq. 10 on the rig [rad/s] (``TrackingController(velocity_pole=...)``).
RIG_VELOCITY_POLE = 40.0


def demo_chain(n: int) -> Chain:
    """Table 1 for ``n = 3``; Table 1's values cycled to ``n`` DOF otherwise."""
    if n == 3:
        return TABLE1
    if n < 1:
        raise ValueError(f"--n must be >= 1, got {n}")
    return Chain(np.resize(TABLE1.mass, n), np.resize(TABLE1.damping, n), np.resize(TABLE1.stiffness, n + 1))


def settle_time(t: np.ndarray, rel_err: np.ndarray, tol: float = TOLERANCE) -> tuple[float, float]:
    """First time [s] ``|rel_err| <= tol`` and the time from which it stays so to the end.

    NaN entries count as outside. Returns ``(inf, inf)`` if never within, and
    ``inf`` for the second value if the last sample is outside.
    """
    ok = np.isfinite(rel_err) & (np.abs(rel_err) <= tol)
    if not np.any(ok):
        return float("inf"), float("inf")
    first = float(t[np.argmax(ok)])
    if not ok[-1]:
        return first, float("inf")
    bad = np.nonzero(~ok)[0]
    stays = float(t[0]) if bad.size == 0 else float(t[bad[-1] + 1])
    return first, stays


def summarize(res: Any, wall_s: float = float("nan"), noise_db: float | None = None) -> dict[str, Any]:
    """Numbers of the demo from a closed-loop :class:`~algid.simulator.SimulationResult`
    (``noise_db``: the accelerometer SNR asked for [dB], None if noise-free)."""
    chain = res.chain
    log = res.controller_log
    t = res.t
    k_sw = int(log["k_switch"])
    E = res.estimates
    est = np.concatenate([E["mass"], E["damping"], E["stiffness"]], axis=1)
    true = chain.identifiable()
    names = parameter_names(chain.n)
    if chain.n == 1 and chain.boundary == "fixed":
        names[2] = "k1+k2"  # the two walls' springs act in parallel
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = est / true - 1.0
    keep = np.isfinite(true)
    if chain.boundary == "free":
        keep[-1] = False  # k_{n+1} = 0 is known, not estimated
    k_at = min(k_sw, len(t) - 1)
    params = []
    for q in np.nonzero(keep)[0]:
        first, stays = settle_time(t, rel[:, q])
        params.append(
            {
                "name": names[q],
                "true": float(true[q]),
                "at_switch": float(est[k_at, q]),
                "at_end": float(est[-1, q]),
                "rel_err_at_switch": float(rel[k_at, q]),
                "rel_err_at_end": float(rel[-1, q]),
                "first_within_1pct_s": first,
                "stays_within_1pct_s": stays,
                "max_rel_err_after_1s": float(np.nanmax(np.abs(rel[t >= 1.0, q])))
                if np.any(t >= 1.0)
                else float("nan"),
            }
        )
    # each DOF's own [m_i, c_i, k_i, k_{i+1}] (interior springs are estimated twice)
    th = np.asarray(E.get("theta", np.full((len(t), chain.n, 4), np.nan)), dtype=float)
    k_all = chain.stiffness.copy()
    if chain.n == 1 and chain.boundary == "fixed":
        k_all = np.array([k_all[0] + k_all[1], np.nan])
    th_true = np.array([[chain.mass[i], chain.damping[i], k_all[i], k_all[i + 1]] for i in range(chain.n)])
    per_dof = []
    with np.errstate(divide="ignore", invalid="ignore"):
        for i in range(chain.n):
            for j, sym in enumerate(("m", "c", "k_left", "k_right")):
                if not np.isfinite(th_true[i, j]) or th_true[i, j] == 0 or np.all(np.isnan(th[:, i, j])):
                    continue
                first, stays = settle_time(t, th[:, i, j] / th_true[i, j] - 1.0)
                per_dof.append({"dof": i + 1, "param": sym, "first_within_1pct_s": first, "stays_within_1pct_s": stays})
    x_ref = res.x_ref
    err = res.x - x_ref
    stroke = float(np.max(np.abs(x_ref)))
    after = t >= t[k_at]
    late = t >= 1.0

    def peak(mask: np.ndarray) -> float:
        return float(np.max(np.abs(err[mask]))) if np.any(mask) else float("nan")

    def rms(mask: np.ndarray) -> float:
        return float(np.sqrt(np.mean(err[mask] ** 2))) if np.any(mask) else float("nan")

    M, C, K = chain.matrices()
    u_ff = log["xdd_ref"] @ M.T + log["xd_ref"] @ C.T + x_ref @ K.T  # exact-model force
    lim = res.limits
    jump = np.abs(lim["u_plus"][k_at] - lim["u_minus"][k_at])
    win = (t >= t[k_at]) & (t <= t[k_at] + 0.2)
    dev = np.abs(res.u_applied[win] - u_ff[win])
    before = (t >= t[k_at] - 0.02) & (t < t[k_at])
    return {
        "n": chain.n,
        "mode": res.mode,
        "fs_hz": res.fs_hz,
        "duration_s": float(len(t) / res.fs_hz),
        "noise_db": noise_db,
        "accel_snr_achieved_db": (res.snr_db["accel"].tolist() if "accel" in res.snr_db else None),
        "switch_time_s": float(t[k_at]),
        "eq10": log.get("eq10"),
        "estimates_substituted_s": (
            None
            if log.get("first_accepted_s") is None
            else max(float(t[k_at]), float(log["first_accepted_s"]) + 1.0 / res.fs_hz)
        ),
        "continuous_running_from_s": log.get("running_from_s"),
        "gains": log["gains"],
        "poles_rad_s": [p.real for p in log["poles"]],
        "estimator_delay_samples": log["delay_samples"],
        "parameters": params,
        "all_first_within_1pct_s": max(p["first_within_1pct_s"] for p in params),
        "all_stay_within_1pct_s": max(p["stays_within_1pct_s"] for p in params),
        "per_dof_estimates": per_dof,
        "all_per_dof_first_within_1pct_s": (max(p["first_within_1pct_s"] for p in per_dof) if per_dof else None),
        "max_rel_err_at_switch": max(abs(p["rel_err_at_switch"]) for p in params),
        "max_rel_err_at_end": max(abs(p["rel_err_at_end"]) for p in params),
        "max_rel_err_after_1s": max(p["max_rel_err_after_1s"] for p in params),
        "stroke_m": stroke,
        "tracking": {
            "peak_after_switch_m": peak(after),
            "rms_after_switch_m": rms(after),
            "peak_after_1s_m": peak(late),
            "rms_after_1s_m": rms(late),
            "peak_after_switch_pct_stroke": 100 * peak(after) / stroke,
            "peak_after_1s_pct_stroke": 100 * peak(late) / stroke,
        },
        "substitution": {
            "force_jump_N": jump.tolist(),
            "peak_force_deviation_N": float(np.max(dev)) if dev.size else float("nan"),
            "peak_exact_model_force_N": float(np.max(np.abs(u_ff))),
            "peak_force_deviation_pct": 100 * float(np.max(dev)) / float(np.max(np.abs(u_ff))),
            "force_before_switch_N": float(np.max(np.abs(res.u_applied[before]))) if np.any(before) else float("nan"),
            "peak_force_after_switch_N": float(np.max(np.abs(res.u_applied[win]))),
            "estimate_disturbance": substitution_disturbance(res),
        },
        "peak_force_N": float(np.max(np.abs(res.u_applied))),
        "wall_s": wall_s,
    }


def _relative_errors(res: Any) -> np.ndarray:
    """(T, q) relative error [-] of every identified nonzero estimate the loop logged."""
    E, true = res.estimates, res.chain.identifiable()
    keep = np.isfinite(true) & (true != 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.abs(np.concatenate([E["mass"], E["damping"], E["stiffness"]], axis=1)[:, keep] / true[keep] - 1)
    return np.where(np.isfinite(rel), rel, np.inf)


def substitution_disturbance(res: Any, reference: Any = None, span_s: float = 0.1) -> float:
    """How far the substitution of the estimates into the law disturbs the estimates [-],
    over ``span_s`` [s] from the first interval that uses them (NaN if nothing was
    substituted).

    With ``reference``, the same loop (same noise) whose law never took the estimates: the
    largest excess of an estimate's relative error over the reference's at the same sample
    (both runs are identical up to the substitution, so the excess is what the substitution
    caused). Without: the largest growth of an estimate's relative error against its error
    on the sample before, which also counts the estimator's own early drift."""
    log, t = res.controller_log, res.t
    if log.get("first_accepted_s") is None:
        return float("nan")
    k_sub = max(int(log["k_switch"]), int(round(log["first_accepted_s"] * res.fs_hz)) + 1)
    if not 1 <= k_sub < len(t):
        return float("nan")
    rel = _relative_errors(res)
    span = slice(k_sub, k_sub + int(round(span_s * res.fs_hz)) + 1)
    if reference is None:
        base = np.where(np.isfinite(rel[k_sub - 1]), rel[k_sub - 1], 0.0)
    else:
        base = _relative_errors(reference)[span]
    with np.errstate(invalid="ignore"):
        growth = np.nan_to_num(rel[span] - base, nan=0.0, posinf=np.inf)
    return float(max(0.0, np.max(growth)))


def resolve_estimator(estimator: str, noise_db: float | None, mode: str = "continuous") -> str:
    """``"single"`` or ``"continuous"`` for ``--estimator`` (``auto``: continuous when noisy
    or on a rig, ``mode="sampled"``)."""
    if estimator == "auto":
        return "single" if noise_db is None and mode == "continuous" else "continuous"
    if estimator not in ("single", "continuous"):
        raise ValueError(f"estimator must be single, continuous or auto, got {estimator!r}")
    return estimator


def _continuous_factory(n: int, dt: float, boundary: str) -> Any:
    from .controller import ContinuousAdapter

    return ContinuousAdapter(n, dt, boundary)


#: The rig's estimator: weak-form windows of 0.3 s, test functions up to 30 Hz (twice the
#: probe's highest line), and growing-window estimates valid only while steady within 1 %
#: (see the module docstring).
RIG_ESTIMATOR_OPTIONS: dict[str, Any] = {"method": "weak_form", "window_s": 0.3, "band_hz": 30.0, "bootstrap_tol": 0.01}


def _rig_factory(n: int, dt: float, boundary: str) -> Any:
    from .controller import ContinuousAdapter

    return ContinuousAdapter(n, dt, boundary, **RIG_ESTIMATOR_OPTIONS)


def _actual_snr_noise(noise_db: float, seed: int | None, scale: np.ndarray) -> Any:
    """Accelerometer noise whose RMS is ``10**(-noise_db/20)`` times ``scale`` times the
    simulator's planned-motion level, per DOF."""
    from dataclasses import dataclass

    from ..simulator import SensorNoise

    @dataclass(frozen=True)
    class _Scaled(SensorNoise):
        scale: tuple = ()

        @property
        def ratio(self) -> Any:
            return 10.0 ** (-self.snr_db / 20.0) * np.asarray(self.scale, dtype=float)

    return _Scaled(float(noise_db), ("accel",), seed, tuple(float(v) for v in scale))


def estimator_drift(res: Any, times_s: tuple = DRIFT_TIMES_S) -> dict[str, Any]:
    """Both estimators open loop on the loop's recorded samples: largest relative error over
    the identified parameters at ``times_s`` [s], and the continuous one's largest relative
    one-sigma uncertainty there."""
    from .. import ChainEstimator
    from .controller import ContinuousAdapter

    chain = res.chain
    n, dt = chain.n, 1.0 / res.fs_hz
    true = chain.identifiable().astype(float)
    keep = np.isfinite(true) & (true != 0)
    single = ChainEstimator(n, dt, boundary=chain.boundary).run(res.a, res.u)
    th_s = np.concatenate([single["mass"], single["damping"], single["stiffness"]], axis=1)
    ad = ContinuousAdapter(n, dt, chain.boundary)
    T = len(res.t)
    th_c = np.full((T, 3 * n + 1), np.nan)
    rs_c = np.full((T, 3 * n + 1), np.nan)
    for k in range(T):
        ad.update(res.a[k], res.u[k])
        th_c[k], rs_c[k] = ad.estimate, ad.rel_sigma
    out: dict[str, Any] = {
        "times_s": list(times_s),
        "single": [],
        "continuous": [],
        "continuous_rel_sigma": [],
        "running_from_s": None if ad.running_from is None else ad.running_from * dt,
    }
    with np.errstate(divide="ignore", invalid="ignore"):
        rel_s = np.abs(th_s / true - 1.0)[:, keep]
        rel_c = np.abs(th_c / true - 1.0)[:, keep]
    for ts in times_s:
        k = min(T - 1, max(0, int(round(ts * res.fs_hz)) - 1))
        worst = lambda r: float(np.max(np.where(np.isfinite(r), r, np.inf)))  # noqa: E731
        out["single"].append(worst(rel_s[k]))
        out["continuous"].append(worst(rel_c[k]))
        sig = rs_c[k][keep]
        # no uncertainty yet (the running estimate starts after its first windows): NaN
        out["continuous_rel_sigma"].append(
            float(np.max(sig[np.isfinite(sig)])) if np.isfinite(sig).any() else float("nan")
        )
    out["single_history"], out["continuous_history"] = rel_s, rel_c
    return out


def run_scenario(
    n: int = 3,
    mode: str = "continuous",
    noise_db: float | None = None,
    seed: int | None = 0,
    duration_s: float = 5.0,
    eq10: str = "integrated",
    progress: Callable[[float], None] | None = None,
    estimator: str = "auto",
    excitation_n: float | None = None,
    drift: bool = True,
    actuator_lag_s: float = 0.0,
    controller_lag_s: float | str = "estimate",
    velocity_pole: float | None | str = "auto",
    disturbance_reference: bool = False,
) -> tuple[Any, dict[str, Any]]:
    """Simulate the demo's closed loop and summarise it; returns ``(result, summary)``.

    ``estimator``: ``single``, ``continuous`` or ``auto``; ``excitation_n``: probe amplitude
    per multisine line [N] (None: 0.05 N with noise, none without); ``drift``: also run both
    estimators open loop on the recorded samples (the drift table); ``velocity_pole``: the
    position feedback of eq. 10 [rad/s] (``"auto"``: :data:`RIG_VELOCITY_POLE` in sampled
    mode, none in continuous mode); ``disturbance_reference``: also run the same loop
    (same noise) with the estimates never substituted, for
    :func:`substitution_disturbance` against it (``estimate_disturbance_vs_reference``)."""
    from ..simulator import simulate
    from .controller import TrackingController
    from .trajectories import BezierReference, Multisine

    kind = resolve_estimator(estimator, noise_db, mode)
    if excitation_n is None:
        excitation_n = 0.0 if noise_db is None and mode == "continuous" else DEFAULT_EXCITATION_N
    chain = demo_chain(n)
    t_out, t_back = (0.0, 0.4 * duration_s), (0.5 * duration_s, 0.9 * duration_s)
    ref = BezierReference.paper(n, t_out=t_out, t_back=t_back)

    if velocity_pole == "auto":
        velocity_pole = RIG_VELOCITY_POLE if mode == "sampled" else None

    def controller(use_estimates: bool = True) -> Any:
        kw: dict[str, Any] = dict(reference=ref, eq10=eq10, use_estimates=use_estimates, velocity_pole=velocity_pole)
        if kind == "continuous":
            factory = _rig_factory if mode == "sampled" else _continuous_factory
            kw.update(estimator_factory=factory, accept="sigma")
        if excitation_n > 0:
            kw["excitation"] = Multisine(n, excitation_n)
        if mode == "sampled":
            kw["actuator_lag_s"] = controller_lag_s  # default: from the rig's own records
        return TrackingController(**kw)

    t0 = time.perf_counter()
    noise = None
    if noise_db is not None:
        # calibration: the same loop noise-free gives the actual acceleration RMS per DOF
        from ..simulator.sensors import nominal_closed_loop_rms

        ctrl0 = controller()
        cal = simulate(chain, None, duration_s, 1000.0, controller=ctrl0, mode=mode, actuator_lag_s=actuator_lag_s)
        planned = nominal_closed_loop_rms(chain, ctrl0, cal.t)["accel"]
        noise = _actual_snr_noise(noise_db, seed, np.sqrt(np.mean(cal.a_true**2, axis=0)) / planned)

    def loop(use_estimates: bool = True, report: Callable[[float], None] | None = None) -> Any:
        return simulate(
            chain,
            None,
            duration_s,
            1000.0,
            controller=controller(use_estimates),
            mode=mode,
            noise=noise,
            progress=report,
            actuator_lag_s=actuator_lag_s,
        )

    res = loop(report=progress)
    s = summarize(res, time.perf_counter() - t0, noise_db)
    if disturbance_reference:
        s["substitution"]["estimate_disturbance_vs_reference"] = substitution_disturbance(res, loop(False))
    s["estimator"] = kind
    s["excitation_n"] = float(excitation_n)
    s["actuator_lag_s"] = float(actuator_lag_s)
    if drift:
        d = estimator_drift(res)
        res.drift = d
        s["drift"] = {k: v for k, v in d.items() if not k.endswith("_history")}
    return res, s


def _fmt_t(x: float) -> str:
    return "never" if not np.isfinite(x) else f"{x:.3f}"


def format_summary(s: dict[str, Any]) -> str:
    """The human-readable report."""
    lines = [
        f"algid demo: n = {s['n']}, {CONTROL_WORDS[s['mode']]}, fs = {s['fs_hz']:.0f} Hz, "
        f"{s['duration_s']:.1f} s"
        + (f", actuator lag {1e3 * s['actuator_lag_s']:g} ms" if s.get("actuator_lag_s") else "")
        + ", accelerometers "
        + (
            "noise-free"
            if s["noise_db"] is None
            else f"{s['noise_db']:.1f} dB SNR (achieved on the actual signals: "
            + ", ".join(f"{v:.1f}" for v in s["accel_snr_achieved_db"])
            + " dB)"
        ),
        f"{ESTIMATOR_WORDS[s.get('estimator', 'single')]}"
        + (
            f" (running estimate served from {s['continuous_running_from_s']:.3f} s)"
            if s.get("continuous_running_from_s") is not None
            else ""
        )
        + (f"; probe multisine {s['excitation_n']:.3g} N per line" if s.get("excitation_n") else ""),
        f"controller: poles {s['poles_rad_s']} rad/s, eq. 10 {s['eq10']}; "
        + (
            "estimates never substituted (none passed the acceptance rule: nominal m = 1 kg, c = k = 0 throughout)"
            if s["estimates_substituted_s"] is None
            else f"estimates substituted at t = {s['estimates_substituted_s']:.3f} s"
        ),
        "",
        f"{'param':>6} {'true':>10} {'est @ switch':>13} {'rel err':>9} {'est @ end':>12} "
        f"{'rel err':>9} {'<=1% at [s]':>11} {'stays from [s]':>14}",
    ]
    for p in s["parameters"]:
        lines.append(
            f"{p['name']:>6} {p['true']:>10.4g} {p['at_switch']:>13.6g} {p['rel_err_at_switch']:>9.1e} "
            f"{p['at_end']:>12.6g} {p['rel_err_at_end']:>9.1e} {_fmt_t(p['first_within_1pct_s']):>11} "
            f"{_fmt_t(p['stays_within_1pct_s']):>14}"
        )
    tr, sb = s["tracking"], s["substitution"]
    lines += [
        "",
        f"all {len(s['parameters'])} fused estimates within 1 % first at {_fmt_t(s['all_first_within_1pct_s'])} s"
        + (
            f" ({len(s['per_dof_estimates'])} per-DOF estimates: {_fmt_t(s['all_per_dof_first_within_1pct_s'])} s)"
            if s["per_dof_estimates"]
            else ""
        )
        + ", "
        + (
            "do not all stay within 1 % to the end; "
            if not np.isfinite(s["all_stay_within_1pct_s"])
            else f"and all stay within 1 % from {s['all_stay_within_1pct_s']:.3f} s on; "
        )
        + (
            f"largest error after 1 s {100 * s['max_rel_err_after_1s']:.3g} %"
            if np.isfinite(s["max_rel_err_after_1s"])
            else "the record ends before 1 s"
        ),
        f"tracking error after the switch: peak {1e6 * tr['peak_after_switch_m']:.3g} um "
        f"({tr['peak_after_switch_pct_stroke']:.3g} % of the {1e3 * s['stroke_m']:.0f} mm stroke), "
        f"RMS {1e6 * tr['rms_after_switch_m']:.3g} um",
    ]
    if np.isfinite(tr["peak_after_1s_m"]):
        lines.append(
            f"tracking error after 1 s: peak {1e6 * tr['peak_after_1s_m']:.3g} um "
            f"({tr['peak_after_1s_pct_stroke']:.3g} % of stroke), RMS {1e6 * tr['rms_after_1s_m']:.3g} um"
        )
    lines += [
        f"substitution: force jump {', '.join(f'{j:.3g}' for j in sb['force_jump_N'])} N; "
        f"peak deviation from the exact-model force within 0.2 s {sb['peak_force_deviation_N']:.3g} N "
        f"({sb['peak_force_deviation_pct']:.3g} % of its peak {sb['peak_exact_model_force_N']:.3g} N); "
        f"largest growth of an estimate's error within 0.1 s {100 * sb['estimate_disturbance']:.3g} %",
        f"simulated in {s['wall_s']:.1f} s",
    ]
    d = s.get("drift")
    if d:
        lines += [
            "",
            "largest relative error of the estimates, both estimators open loop on the recorded samples:",
            f"{'t [s]':>8} " + " ".join(f"{t:>9g}" for t in d["times_s"]),
            f"{'single':>8} " + " ".join(_percent(e, 3) for e in d["single"]),
            f"{'contin.':>8} " + " ".join(_percent(e, 3) for e in d["continuous"]),
            f"{'(sigma)':>8} " + " ".join(_percent(e, 2) for e in d["continuous_rel_sigma"]),
        ]
    return "\n".join(lines)


def _percent(fraction: float, digits: int) -> str:
    """A table cell of 9 characters: the percentage, or ``n/a`` where there is none yet (the
    continuous estimator's sigma before its first window results)."""
    return f"{100 * fraction:>8.{digits}g}%" if np.isfinite(fraction) else f"{'n/a':>9}"


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``algid demo`` on an argparse sub-parser collection."""
    from ..messages import example

    p = subparsers.add_parser(
        "demo",
        help="reproduce the paper's closed-loop experiment (Table 1, 5 s)",
        description="Closed-loop tracking of the Table 1 chain with on-line estimates "
        "substituted at 0.1 s; prints a table and writes PNG figures.",
        epilog=example("algid demo --mode sampled --noise-db 40 --out demo-sampled/"),
    )
    p.add_argument(
        "--mode",
        choices=("continuous", "sampled"),
        default="continuous",
        help="controller inside the ODE (paper) or held at the sample rate (DAC)",
    )
    p.add_argument(
        "--noise-db",
        type=float,
        metavar="DB",
        default=None,
        help="SNR of the accelerometers [dB] (default: noise-free)",
    )
    p.add_argument(
        "--estimator",
        choices=("single", "continuous", "auto"),
        default="auto",
        help="paper's growing window, continuous running estimate, or auto "
        "(continuous with --noise-db or in sampled mode, single otherwise)",
    )
    p.add_argument(
        "--excitation",
        type=float,
        metavar="N",
        default=None,
        help="probe multisine amplitude per line [N] (default: 0.05 with --noise-db or in sampled mode, 0 otherwise)",
    )
    p.add_argument(
        "--actuator-lag-ms",
        type=float,
        metavar="MS",
        default=0.0,
        help="time constant of a first-order actuator behind the command [ms] (default: 0); "
        "in sampled mode the controller identifies it from its commands and the measured forces",
    )
    p.add_argument(
        "--velocity-pole",
        type=float,
        metavar="RAD_S",
        default=None,
        help="sampled mode: position feedback in eq. 10 [rad/s] (default: 40; 0: the paper's eq. 10)",
    )
    p.add_argument("--n", type=int, metavar="N", default=3, help="number of DOF (default: 3, Table 1)")
    p.add_argument("--seed", type=int, metavar="N", default=0, help="seed of the sensor noise")
    p.add_argument("--duration", type=float, metavar="S", default=5.0, help="record length [s]")
    p.add_argument("--out", metavar="DIR", default="./algid-demo/", help="output folder")
    p.add_argument("--no-plots", action="store_true", help="skip the figures")
    p.add_argument(
        "--topology",
        type=Path,
        metavar="NET.json",
        help="a spring network instead of the chain, run open loop (the closed loop is the chain's): the force "
        "that tracks the demo's references on it plus the probe, identified with algid identify --topology; "
        'NET.json is a model (NetworkModel.from_json) or a topology {"n": N, "springs": [[a, b], ...]} given '
        "Table 1's values cycled; takes --noise-db, --excitation (default 0.5 N), --seed, --duration, --out",
    )
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Run ``algid demo``; returns the exit code (0 ok, 2 bad arguments)."""
    if args.topology is not None:
        return run_network_demo(args)
    if args.n < 1:
        print(f"algid demo: --n must be >= 1, got {args.n}", file=sys.stderr)
        return 2
    if not args.actuator_lag_ms >= 0:
        print(f"algid demo: --actuator-lag-ms must be >= 0, got {args.actuator_lag_ms}", file=sys.stderr)
        return 2
    if args.velocity_pole is not None and (args.velocity_pole < 0 or args.mode != "sampled"):
        print("algid demo: --velocity-pole must be >= 0 and needs --mode sampled", file=sys.stderr)
        return 2
    if _too_short(args.duration):
        return 2
    progress = Progress("demo")
    try:
        res, summary = run_scenario(
            args.n,
            args.mode,
            args.noise_db,
            args.seed,
            args.duration,
            progress=progress.fraction("simulating closed loop"),
            estimator=args.estimator,
            excitation_n=args.excitation,
            actuator_lag_s=1e-3 * args.actuator_lag_ms,
            velocity_pole="auto" if args.velocity_pole is None else (args.velocity_pole or None),
        )
    except ValueError as exc:
        print(one_line(f"algid demo: error: {exc}"), file=sys.stderr)
        return 2
    finally:
        progress.close()
    print(format_summary(summary))

    def figures(out: Path) -> list[Path]:
        from ..plotting.demo import write_figures

        progress("writing figures")
        paths = write_figures(res, summary, out)
        progress.close()
        return paths

    return _write_outputs(Path(args.out), summary, None if args.no_plots else figures)


def _too_short(duration_s: float) -> bool:
    """Whether the demo's record of ``duration_s`` is too short (said on stderr)."""
    if duration_s > 0.5:
        return False
    print("algid demo: --duration must be > 0.5 s", file=sys.stderr)
    return True


def _write_outputs(out: Path, summary: dict, figures: Callable[[Path], list[Path]] | None) -> int:
    """``summary.json`` (and ``figures(out)`` unless None) written in ``out``; prints what was
    written and returns the exit code 0."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(jsonable(summary), indent=2) + "\n", encoding="utf-8")
    written = [out / "summary.json"] + ([] if figures is None else figures(out))
    print("wrote " + ", ".join(str(p) for p in written))
    return 0


def run_network_demo(args: argparse.Namespace) -> int:
    """``algid demo --topology``: :mod:`.network_demo`; returns the exit code."""
    from . import network_demo

    given = network_demo.chain_options_given(args)
    if given:
        print(f"algid demo: error: {', '.join(given)}: the chain's closed loop, not with --topology", file=sys.stderr)
        return 2
    if _too_short(args.duration):
        return 2
    progress = Progress("demo")
    try:
        model, source = network_demo.read_network(args.topology)
        res, result, summary = network_demo.run_network(
            model, args.duration, args.noise_db, args.seed, args.excitation, progress
        )
    except (ValueError, OSError) as exc:
        print(one_line(f"algid demo: error: {exc}"), file=sys.stderr)
        return 2
    finally:
        progress.close()
    print(network_demo.format_summary(summary, source))

    def figures(out: Path) -> list[Path]:
        from ..plotting.demo import write_network_figures

        return write_network_figures(res, summary, out)

    return _write_outputs(Path(args.out), summary, None if args.no_plots else figures)


def jsonable(o: Any) -> Any:
    """Plain JSON types; non-finite numbers become null (e.g. a time never reached)."""
    if isinstance(o, dict):
        return {str(k): jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple, np.ndarray)):
        return [jsonable(v) for v in (o.tolist() if isinstance(o, np.ndarray) else o)]
    if isinstance(o, (np.floating, np.integer)):
        o = o.item()
    if isinstance(o, float) and not np.isfinite(o):
        return None
    if isinstance(o, complex):
        return [o.real, o.imag]
    return o
