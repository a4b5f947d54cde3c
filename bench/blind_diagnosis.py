"""Blind check of ``algid diagnose`` (issue 6) on simulated recordings with a hidden effect.

Measures: how often the diagnosis names the hidden effect (top-1), its location and main
parameter, the in-band gap shrink, false alarms on effect-free cases, a confusion matrix and
the wall time per diagnosis. The default (30 seeds, 0:30) is a quick look; it writes to
``WORK`` only. The published figures (docs/diagnosis.md, docs/real_data.md) are::

    python bench/blind_diagnosis.py --seeds 0:150,3000:3150 --timing --results bench/results/blind_diagnosis.json
    python bench/blind_diagnosis.py --seeds 5000:5150 --work /tmp/algid-blind-5000 \
        --results bench/results/blind_diagnosis.fresh5000.json

For every seed: a random chain (n = 1..4, parameters from ``Chain.random``, right end
free with probability 0.2 for n >= 2), broadband forcing on every DOF (independent
random-phase multisines, flat 0.5-50 Hz, 10 N RMS), a hidden effect drawn at random
(``none`` with probability 0.2, each of the 8 effects of ``EFFECTS`` with 0.1) at a random location, a
random size and a random accelerometer SNR of 40-60 dB. The recording (``t, u1..un,
a1..an``, nothing else) goes to ``WORK/recordings/``, the label to ``WORK/labels/``; the
diagnosis is run on the recording alone through the code path of ``algid diagnose``
(``algid.diagnosis.cli.run``) and its JSON written to ``WORK/diagnoses/``; the scoring
reads labels and diagnoses only.

Effect sizes ("barely visible to strong"). What makes an effect visible is the part of
it that the linear chain cannot absorb (a quadratic damper is mostly a viscous one, a
stiff clearance mostly a spring). Its size is therefore set by a visibility ``rho``,
drawn log-uniformly in [RHO_MIN, RHO_MAX] = [0.5, 50]: the RMS of the effect's equation
error (acceleration units) left after a least-squares fit of the linear equation(s) it
enters, divided by the accelerometer noise RMS of that DOF, computed on the exact linear
steady-state response (the chain's transfer matrix at the multisine lines). The effect
parameter is solved for it: linearly for ``force``, ``c2``, ``k3`` (random sign; a
softening spring capped at 30 % of k at 3 RMS deformations), the clearance ``stiffness``
(its ``gap`` uniform in [0.3, 1.5] RMS deformations) and ``rel_change`` (random sign,
clipped to +-0.5); by bisection for ``delay`` (<= 50 ms) and ``cutoff_hz``
(low-pass <= 0.45 fs, high-pass 0.02-10 Hz, drawn by the realistic check only); ``|bias| = rho`` times the noise RMS. The visible part is capped at 30 % of
the DOF's acceleration RMS. ``rho = 0.5``: invisible in a plot of the signals, only
statistics over the record can see it; ``rho = 50``: obvious.

Scoring (issue 6): top-1 effect accuracy; location accuracy among correct effects;
relative error of the main parameter (the first one listed for the effect) among
correct effect and location; gap shrink ``gap_before / gap_after`` on cases with a real
effect (a missed effect counts as 1), with the diagnosis's primary, in-band gap (the
equation error on the signal band the diagnosis finds in the recording, see
``algid.diagnosis.core``) and, alongside, the full-band one (``*_fullband``); false
alarms on ``none``; a confusion matrix
(table and PNG). For n = 1 the two springs are one: a spring-2 label is scored as spring
1 and a drift's ``rel_change`` is scaled to the identifiable sum ``k1 + k2``.

Usage::

    python bench/blind_diagnosis.py [--seeds 0:30] [--work /tmp/algid-blind] [--duration 10]
        [--stage all|generate|diagnose|score] [--timing] [--results FILE]

Seeds are arguments; thresholds inside the diagnosis were set on a disjoint seed range
(``--seeds 1000:1100``) before the reported run; the constants of the signal-band rule
on ``--seeds 1000:1060,2000:2080`` only.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

from algid.diagnosis.candidates import EFFECTS as DIAGNOSED  # noqa: E402
from algid.diagnosis.candidates import MAIN_PARAM  # noqa: E402
from algid.model.chain import TABLE1, Chain  # noqa: E402
from algid.recording import Recording, save_recording  # noqa: E402
from algid.simulator.effects import EFFECT_LOCATIONS  # noqa: E402

EFFECTS = (
    "coulomb_friction",
    "quadratic_damping",
    "cubic_stiffness",
    "clearance",
    "input_delay",
    "sensor_bias",
    "sensor_lowpass",
    "parameter_drift",
)
#: Effects the generator can also draw (the realistic check, bench/realistic_blind.py); kept
#: out of EFFECTS so that the blind check's seeds draw the cases they always drew.
MORE_EFFECTS = ("stribeck_friction", "amplitude_damping", "sensor_highpass")
assert set(EFFECTS + MORE_EFFECTS) == set(DIAGNOSED), "the blind check draws every effect the diagnosis knows"
SPRING_EFFECTS = tuple(e for e in EFFECTS + MORE_EFFECTS if EFFECT_LOCATIONS[e] == "spring")
#: Main parameter of every effect: the diagnosis's own table.
MAIN = dict(MAIN_PARAM)
CLASSES = ("none",) + EFFECTS + MORE_EFFECTS + ("unknown",)
P_NONE = 0.2
#: Visibility range of the hidden effect ("barely visible" to "strong"), see draw_case.
RHO_MIN = 0.5
RHO_MAX = 50.0
F_BAND_HZ = (0.5, 50.0)
#: Highest cut-off of a drawn AC-coupled accelerometer [Hz] (IEPE sensors and charge
#: amplifiers: 0.1 to a few Hz).
HIGHPASS_MAX_HZ = 10.0
FORCE_RMS_N = 10.0


# ----------------------------------------------------------------------------- forcing


def multisine(n: int, duration: float, fs: float, rng: np.random.Generator) -> np.ndarray:
    """(T, n) independent random-phase multisines, flat on the lines of F_BAND_HZ with
    period ``duration`` (so the linear steady state is exactly periodic)."""
    T = int(round(duration * fs))
    df = 1.0 / duration
    k = np.arange(int(math.ceil(F_BAND_HZ[0] / df)), int(F_BAND_HZ[1] / df) + 1)
    U = np.zeros((T // 2 + 1, n), dtype=complex)
    U[k] = np.exp(2j * np.pi * rng.uniform(size=(k.size, n)))
    u = np.fft.irfft(U, n=T, axis=0)
    return u * (FORCE_RMS_N / u.std(axis=0))


def linear_response(chain: Chain, u: np.ndarray, fs: float) -> dict[str, np.ndarray]:
    """Periodic steady state x, v, a (T, n) of the linear chain under periodic u."""
    T, n = u.shape
    M, C, K = chain.matrices()
    Uf = np.fft.rfft(u, axis=0)
    w = 2 * np.pi * np.fft.rfftfreq(T, 1 / fs)
    X = np.zeros_like(Uf)
    for q in range(1, w.size):
        if np.any(Uf[q] != 0):
            X[q] = np.linalg.solve(K - w[q] ** 2 * M + 1j * w[q] * C, Uf[q])
    x = np.fft.irfft(X, n=T, axis=0)
    v = np.fft.irfft(1j * w[:, None] * X, n=T, axis=0)
    a = np.fft.irfft(-(w[:, None] ** 2) * X, n=T, axis=0)
    return {"x": x, "v": v, "a": a}


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.asarray(x) ** 2)))


def _deformation(x: np.ndarray, j: int) -> np.ndarray:
    n = x.shape[1]
    right = x[:, j - 1] if j - 1 < n else 0.0
    left = x[:, j - 2] if j - 2 >= 0 else 0.0
    return right - left


def _bisect(f, lo: float, hi: float, target: float, iters: int = 60) -> float:
    """Solve increasing f(p) = target on [lo, hi] in log space."""
    a, b = math.log(lo), math.log(hi)
    if f(hi) < target:
        return hi
    for _ in range(iters):
        mid = 0.5 * (a + b)
        if f(math.exp(mid)) < target:
            a = mid
        else:
            b = mid
    return math.exp(0.5 * (a + b))


def _lowpass(x: np.ndarray, fc: float, fs: float) -> np.ndarray:
    """First-order low-pass in the frequency domain (steady state of a periodic signal)."""
    f = np.fft.rfftfreq(x.size, 1 / fs)
    return np.fft.irfft(np.fft.rfft(x) / (1 + 1j * f / fc), n=x.size)


def _highpass(x: np.ndarray, fc: float, fs: float) -> np.ndarray:
    """First-order high-pass in the frequency domain (steady state of a periodic signal)."""
    f = np.fft.rfftfreq(x.size, 1 / fs)
    h = 1j * f / fc
    return np.fft.irfft(np.fft.rfft(x) * h / (1 + h), n=x.size)


def _delayed(x: np.ndarray, d: float, fs: float) -> np.ndarray:
    f = np.fft.rfftfreq(x.size, 1 / fs)
    return np.fft.irfft(np.fft.rfft(x) * np.exp(-2j * np.pi * f * d), n=x.size)


def _eq_columns(chain: Chain, resp: dict, u: np.ndarray, e: int) -> np.ndarray:
    """Columns of the linear equation of DOF e on the linear response: 1, u_e, v_e and the
    spring deformations seen by e (walls at 0; no spring n+1 for a free right end)."""
    x, v = resp["x"], resp["v"]
    n = chain.n
    cols = [np.ones(len(u)), u[:, e], v[:, e], x[:, e] - (x[:, e - 1] if e >= 1 else 0.0)]
    if e + 1 < n:
        cols.append(x[:, e] - x[:, e + 1])
    elif chain.boundary == "fixed" and n > 1:
        cols.append(x[:, e])
    return np.stack(cols, axis=1)


def visible_rms(chain: Chain, resp: dict, u: np.ndarray, errors: dict[int, np.ndarray]) -> float:
    """RMS over the record of the part of an effect's equation errors (acceleration units,
    per DOF equation) that the linear equations cannot absorb: the least-squares residual
    of each error on the columns of its own linear equation, pooled over the equations."""
    tot = 0.0
    for e, err in errors.items():
        X = _eq_columns(chain, resp, u, e)
        coef, *_ = np.linalg.lstsq(X, err, rcond=None)
        tot += float(np.sum((err - X @ coef) ** 2))
    return math.sqrt(tot / len(u))


def _sides(n: int, j: int) -> list[tuple[int, float]]:
    """(DOF, sign) where the force of spring j acts: DOF j with -, DOF j-1 with + (the
    acceleration equations, force on the left-hand side moved right)."""
    return [(i, sgn) for i, sgn in ((j - 1, -1.0), (j - 2, 1.0)) if 0 <= i < n]


def draw_case(seed: int, duration: float, fs: float, effects: tuple = EFFECTS) -> dict:
    """Everything about one case: chain, forcing, effect, SNR (deterministic in seed).

    Effect size: a visibility ``rho`` drawn log-uniformly in [RHO_MIN, RHO_MAX] is the
    :func:`visible_rms` of the effect divided by the accelerometer noise RMS of the DOF
    it acts on (for a spring, the mean of its two DOF); the effect parameter is solved
    for it on the linear steady-state response. ``rho`` is capped so that the visible
    part stays below 30 % of that DOF's acceleration RMS. Sensor bias: ``|bias| = rho *
    noise RMS`` (a constant offset; its double integral makes it far more visible).
    """
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 5))
    boundary = "free" if (n >= 2 and rng.uniform() < 0.2) else "fixed"
    chain = Chain.random(n, rng, boundary)
    u = multisine(n, duration, fs, rng)
    snr_db = float(rng.uniform(40.0, 60.0))
    resp = linear_response(chain, u, fs)
    effect = "none" if rng.uniform() < P_NONE else effects[int(rng.integers(len(effects)))]
    noise_rel = 10 ** (-snr_db / 20)
    rho = float(math.exp(rng.uniform(math.log(RHO_MIN), math.log(RHO_MAX))))
    label: dict = {
        "seed": seed,
        "n": n,
        "boundary": boundary,
        "snr_db": snr_db,
        "visibility": rho,
        "chain": {
            "mass": chain.mass.tolist(),
            "damping": chain.damping.tolist(),
            "stiffness": chain.stiffness.tolist(),
        },
        "duration_s": duration,
        "fs_hz": fs,
    }
    if effect == "none":
        label.update(effect="none", location=None, params={}, visibility=0.0)
        return {"chain": chain, "u": u, "label": label, "effects": []}
    x, v, a = resp["x"], resp["v"], resp["a"]
    m = chain.mass
    sigma = noise_rel * np.sqrt(np.mean(a**2, axis=0))  # accelerometer noise RMS per DOF
    a_rms = np.sqrt(np.mean(a**2, axis=0))
    sign = float(rng.choice([-1.0, 1.0]))

    def solve_linear(unit_errors: dict[int, np.ndarray], dofs: list[int]) -> float:
        """Scale of an effect whose errors are linear in its parameter."""
        target = min(rho * float(np.mean(sigma[dofs])), 0.3 * float(np.mean(a_rms[dofs])))
        return target / max(visible_rms(chain, resp, u, unit_errors), 1e-300)

    def solve_nonlinear(errors_of, lo: float, hi: float, dofs: list[int]) -> float:
        """Smallest parameter in [lo, hi] reaching the target visibility (scanned upwards:
        a very large delay or time constant is partly absorbed again by the linear
        equation, so visibility is not monotonic), refined by bisection."""
        target = min(rho * float(np.mean(sigma[dofs])), 0.3 * float(np.mean(a_rms[dofs])))
        grid = np.geomspace(lo, hi, 60)
        vis = []
        for k, p in enumerate(grid):
            vis.append(visible_rms(chain, resp, u, errors_of(p)))
            if vis[-1] >= target:
                if k == 0:
                    return float(p)
                return _bisect(lambda q: visible_rms(chain, resp, u, errors_of(q)), grid[k - 1], p, target)
        return float(grid[int(np.argmax(vis))])

    if effect in SPRING_EFFECTS:
        top = n + 1 if boundary == "fixed" else n
        j = int(rng.integers(1, top + 1))
        loc = {"spring": j}
        d = _deformation(x, j)
        sides = _sides(n, j)
        dofs = [i for i, _ in sides]
        gap = float(rng.uniform(0.3, 1.5) * _rms(d))
        shape = {
            "cubic_stiffness": d**3,
            "clearance": np.sign(d) * np.maximum(np.abs(d) - gap, 0.0),
            "parameter_drift": (np.arange(len(u)) / fs / duration) * chain.stiffness[j - 1] * d,
            "amplitude_damping": np.abs(d) * _deformation(v, j),
        }[effect]
        key = {
            "cubic_stiffness": "k_cubic",
            "clearance": "k_contact",
            "parameter_drift": "rel_change",
            "amplitude_damping": "c_amp",
        }[effect]

        def errors(p):
            return {i: sgn * p[key] * shape / m[i] for i, sgn in sides}

        scale = solve_linear(errors({key: 1.0}), dofs)
        if effect == "cubic_stiffness":
            k3 = sign * scale
            if k3 < 0:  # a softening spring must stay stable: at most 30 % of k at 3 rms(d)
                k3 = -min(-k3, 0.3 * chain.stiffness[j - 1] / (3 * _rms(d)) ** 2)
            params = {"k_cubic": float(k3)}
        elif effect == "clearance":
            params = {"gap": gap, "k_contact": float(scale)}
        elif effect == "amplitude_damping":
            params = {"c_amp": float(scale)}
        else:
            params = {"rel_change": float(np.clip(sign * scale, -0.5, 0.5))}
    else:
        i = int(rng.integers(0, n))
        loc = {"dof": i + 1}
        dofs = [i]
        ui, ai = u[:, i], a[:, i]
        if effect == "coulomb_friction":

            def errors(p):
                return {i: -p["force"] * np.sign(v[:, i]) / m[i]}

            params = {"force": solve_linear(errors({"force": 1.0}), dofs)}
        elif effect == "stribeck_friction":
            peak = float(rng.uniform(1.5, 3.0))
            vs = float(rng.uniform(0.1, 0.5) * _rms(v[:, i]))

            def errors(p):
                level = p["force"] * (1.0 + (peak - 1.0) * np.exp(-((v[:, i] / vs) ** 2)))
                return {i: -level * np.sign(v[:, i]) / m[i]}

            fc = solve_linear(errors({"force": 1.0}), dofs)
            params = {"force": fc, "static": peak * fc, "v_stribeck": vs}
        elif effect == "quadratic_damping":

            def errors(p):
                return {i: -p["c_quadratic"] * v[:, i] * np.abs(v[:, i]) / m[i]}

            params = {"c_quadratic": solve_linear(errors({"c_quadratic": 1.0}), dofs)}
        elif effect == "input_delay":

            def errors(p):
                return {i: (_delayed(ui, p["delay"], fs) - ui) / m[i]}

            params = {"delay": solve_nonlinear(lambda dd: errors({"delay": dd}), 1e-6, 0.05, dofs)}
        elif effect == "sensor_bias":

            def errors(p):  # the sensor error itself (see the docstring)
                return {i: np.full(len(u), p["bias"])}

            params = {"bias": float(sign * min(rho * sigma[i], 0.3 * a_rms[i]))}
        elif effect == "sensor_highpass":  # the error of the sensor, HP(a) - a, in equation i

            def errors(p):
                return {i: _highpass(ai, p["cutoff_hz"], fs) - ai}

            params = {"cutoff_hz": solve_nonlinear(lambda c: errors({"cutoff_hz": c}), 0.02, HIGHPASS_MAX_HZ, dofs)}
        else:  # sensor_lowpass: the error of the sensor, LP(a) - a, in equation i

            def errors(p):
                return {i: _lowpass(ai, p["cutoff_hz"], fs) - ai}

            tau = solve_nonlinear(lambda c: errors({"cutoff_hz": 1.0 / c}), 1.0 / (0.45 * fs), 1.0, dofs)
            params = {"cutoff_hz": 1.0 / tau}
    # The visibility actually reached (clipping, caps and the lowest visible cutoff change it).
    if effect == "sensor_bias":
        label["visibility"] = float(abs(params["bias"]) / sigma[i])
    else:
        label["visibility"] = visible_rms(chain, resp, u, errors(params)) / float(np.mean(sigma[dofs]))
    label["visibility_drawn"] = rho
    label.update(effect=effect, location=loc, params={k: float(v_) for k, v_ in params.items()})
    return {"chain": chain, "u": u, "label": label, "effects": [{"name": effect, "location": loc, "params": params}]}


# ----------------------------------------------------------------------------- stages


def generate(seed: int, work: Path, duration: float, fs: float) -> Path:
    """Simulate one case; write the recording and the label (skipped if both exist)."""
    from algid.simulator import simulate

    rec_path = work / "recordings" / f"case{seed:05d}.npz"
    lab_path = work / "labels" / f"case{seed:05d}.json"
    if rec_path.exists() and lab_path.exists():
        return rec_path
    case = draw_case(seed, duration, fs)
    lab = case["label"]
    res = simulate(
        case["chain"],
        case["u"],
        duration,
        fs,
        effects=case["effects"],
        noise_db=lab["snr_db"],
        noise_on=("accel",),
        seed=seed,
    )
    rec_path.parent.mkdir(parents=True, exist_ok=True)
    lab_path.parent.mkdir(parents=True, exist_ok=True)
    save_recording(rec_path, Recording(t=res.t, u=res.u, a=res.a))
    lab_path.write_text(json.dumps(lab, indent=1))
    return rec_path


def diagnose_case(seed: int, work: Path, boundary: str, plots: bool = False) -> dict:
    """Run the ``algid diagnose`` code path on one recording; return its JSON."""
    import argparse as ap

    from algid.diagnosis import cli

    rec_path = work / "recordings" / f"case{seed:05d}.npz"
    out = work / "diagnoses" / f"case{seed:05d}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    parser = ap.ArgumentParser(prog="algid")
    sub = parser.add_subparsers(dest="command")
    cli.add_parser(sub)
    argv = ["diagnose", str(rec_path), "--json", str(out), "--boundary", boundary, "--quiet"]
    if plots:
        argv += ["--plots", str(work / "plots" / f"case{seed:05d}")]
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    code = args.func(args)
    wall = time.perf_counter() - t0
    if code != 0:
        raise RuntimeError(f"algid diagnose exited with {code} on {rec_path}")
    res = json.loads(out.read_text())
    res["_wall_s"] = wall
    return res


def _loc_key(loc) -> str:
    if not loc:
        return "-"
    ((k, v),) = loc.items()
    return f"{k} {v}"


def score_case(lab: dict, res: dict) -> dict:
    """Per-case scores against the label (the n = 1 spring rule applied)."""
    truth = lab["effect"]
    loc_true = lab["location"]
    params_true = dict(lab["params"])
    if lab["n"] == 1 and loc_true and "spring" in loc_true:
        j = loc_true["spring"]
        if truth == "parameter_drift":
            k = lab["chain"]["stiffness"]
            params_true["rel_change"] *= k[j - 1] / (k[0] + k[1])
        loc_true = {"spring": 1}
    pred = res["effect"]
    out = {
        "seed": lab["seed"],
        "truth": truth,
        "pred": pred,
        "n": lab["n"],
        "snr_db": lab["snr_db"],
        "visibility": lab.get("visibility"),
        "loc_true": _loc_key(loc_true),
        "loc_pred": _loc_key(res["location"]),
        "gap_before": res["gap_before"],
        "gap_after": res["gap_after"],
        "wall_s": res.get("_wall_s"),
        "noise_floor": res.get("analysis", {}).get("noise_floor"),
        "gap_before_fullband": res.get("gap_before_fullband"),
        "gap_after_fullband": res.get("gap_after_fullband"),
        "noise_floor_fullband": res.get("analysis", {}).get("noise_floor_fullband"),
        "band_hz": (res.get("band") or {}).get("band_hz", [None, None])[1],
        "band_white_noise_fraction": (res.get("band") or {}).get("white_noise_fraction"),
    }
    out["effect_ok"] = pred == truth
    out["loc_ok"] = bool(out["effect_ok"] and (truth == "none" or out["loc_true"] == out["loc_pred"]))
    out["shrink"] = res["gap_before"] / res["gap_after"] if res["gap_after"] > 0 else float("inf")
    if out["gap_before_fullband"] is not None and out["gap_after_fullband"]:
        out["shrink_fullband"] = out["gap_before_fullband"] / out["gap_after_fullband"]
    if truth != "none" and out["loc_ok"]:
        name = MAIN[truth]
        est, tru = res["params"].get(name), params_true[name]
        out["param_true"], out["param_est"] = tru, est
        out["param_rel_err"] = abs(est - tru) / abs(tru) if est is not None and tru != 0 else float("inf")
    return out


def score_all(work: Path, seeds: list[int], score) -> list[dict]:
    """``score(label, diagnosis)`` of every seed's case in ``work``."""
    rows = []
    for seed in seeds:
        lab = json.loads((work / "labels" / f"case{seed:05d}.json").read_text())
        res = json.loads((work / "diagnoses" / f"case{seed:05d}.json").read_text())
        rows.append(score(lab, res))
    return rows


def summarize(rows: list[dict]) -> dict:
    real = [r for r in rows if r["truth"] != "none"]
    none = [r for r in rows if r["truth"] == "none"]
    correct = [r for r in real if r["effect_ok"]]
    loc_ok = [r for r in correct if r["loc_ok"]]
    perr = [r["param_rel_err"] for r in loc_ok if "param_rel_err" in r]
    shrink = [r["shrink"] if r["effect_ok"] else 1.0 for r in real]
    shrink_full = [r.get("shrink_fullband", math.nan) if r["effect_ok"] else 1.0 for r in real]
    walls = [r["wall_s"] for r in rows if r.get("wall_s") is not None]
    conf = {t: {p: 0 for p in CLASSES} for t in CLASSES[:-1]}
    for r in rows:
        conf[r["truth"]][r["pred"] if r["pred"] in CLASSES else "unknown"] += 1
    per_effect = {}
    for eff in CLASSES[:-1]:
        rs = [r for r in rows if r["truth"] == eff]
        if rs:
            per_effect[eff] = {"cases": len(rs), "top1": float(np.mean([r["effect_ok"] for r in rs]))}
            pe = [r["param_rel_err"] for r in rs if "param_rel_err" in r]
            if pe:
                per_effect[eff]["param_within_20pct"] = float(np.mean(np.array(pe) <= 0.2))
                per_effect[eff]["param_rel_err_median"] = float(np.median(pe))
    return {
        "cases": len(rows),
        "real_effect_cases": len(real),
        "none_cases": len(none),
        "top1_accuracy": float(np.mean([r["effect_ok"] for r in rows])),
        "top1_accuracy_real_effects": float(np.mean([r["effect_ok"] for r in real])) if real else None,
        "location_accuracy_among_correct": float(len(loc_ok) / len(correct)) if correct else None,
        "param_within_20pct_among_correct": float(np.mean(np.array(perr) <= 0.2)) if perr else None,
        "param_rel_err_median": float(np.median(perr)) if perr else None,
        "median_gap_shrink_real": float(np.median(shrink)) if shrink else None,
        "median_gap_shrink_real_fullband": float(np.median(shrink_full)) if shrink_full else None,
        "median_band_hz": float(np.median([r["band_hz"] for r in rows if r.get("band_hz") is not None]))
        if any(r.get("band_hz") is not None for r in rows)
        else None,
        "median_band_white_noise_fraction": float(
            np.median([r["band_white_noise_fraction"] for r in rows if r.get("band_white_noise_fraction") is not None])
        )
        if any(r.get("band_white_noise_fraction") is not None for r in rows)
        else None,
        # The most any model can shrink the gap: down to the sensor-noise floor the
        # diagnosis estimates (the gap is measured against noisy accelerations).
        "median_gap_before_over_noise_floor_real": float(
            np.median([r["gap_before"] / r["noise_floor"] for r in real if r.get("noise_floor")])
        )
        if real
        else None,
        "median_gap_after_over_noise_floor_correct": float(
            np.median([r["gap_after"] / r["noise_floor"] for r in correct if r.get("noise_floor")])
        )
        if correct
        else None,
        "median_gap_before_over_noise_floor_real_fullband": float(
            np.median(
                [r["gap_before_fullband"] / r["noise_floor_fullband"] for r in real if r.get("noise_floor_fullband")]
            )
        )
        if any(r.get("noise_floor_fullband") for r in real)
        else None,
        "median_gap_shrink_by_visibility": {
            f"{lo:g}-{hi:g}": float(np.median([sh for sh, r in zip(shrink, real) if lo <= r["visibility"] < hi]))
            for lo, hi in ((0.5, 2.0), (2.0, 10.0), (10.0, 50.0))
            if any(lo <= r["visibility"] < hi for r in real)
        },
        "top1_by_visibility": {
            f"{lo:g}-{hi:g}": float(np.mean([r["effect_ok"] for r in real if lo <= r["visibility"] < hi]))
            for lo, hi in ((0.5, 2.0), (2.0, 10.0), (10.0, 50.0))
            if any(lo <= r["visibility"] < hi for r in real)
        },
        "false_alarm_rate_none": float(np.mean([not r["effect_ok"] for r in none])) if none else None,
        "wall_s_median": float(np.median(walls)) if walls else None,
        "wall_s_max": float(np.max(walls)) if walls else None,
        "confusion": conf,
        "per_effect": per_effect,
    }


def confusion_table(conf: dict) -> str:
    short = {
        "none": "none",
        "coulomb_friction": "coul",
        "quadratic_damping": "quad",
        "cubic_stiffness": "cubic",
        "clearance": "clear",
        "input_delay": "delay",
        "sensor_bias": "bias",
        "sensor_lowpass": "lowp",
        "sensor_highpass": "highp",
        "parameter_drift": "drift",
        "stribeck_friction": "strib",
        "amplitude_damping": "ampd",
        "unknown": "unkn",
    }
    head = "true \\ pred        " + " ".join(f"{short[c]:>6s}" for c in CLASSES)
    lines = [head]
    for t, row in conf.items():
        lines.append(f"{t:18s} " + " ".join(f"{row[c]:6d}" for c in CLASSES))
    return "\n".join(lines)


def confusion_png(conf: dict, path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = list(conf)
    M = np.array([[conf[t][p] for p in CLASSES] for t in rows], dtype=float)
    frac = M / np.maximum(M.sum(axis=1, keepdims=True), 1)
    fig, ax = plt.subplots(figsize=(8.0, 6.2), dpi=110)
    ax.imshow(frac, cmap="Blues", vmin=0, vmax=1)
    for r in range(M.shape[0]):
        for c in range(M.shape[1]):
            if M[r, c]:
                ax.text(
                    c,
                    r,
                    f"{int(M[r, c])}",
                    ha="center",
                    va="center",
                    color="white" if frac[r, c] > 0.6 else "black",
                    fontsize=9,
                )
    ax.set_xticks(range(len(CLASSES)), [c.replace("_", "\n") for c in CLASSES], fontsize=7)
    ax.set_yticks(range(len(rows)), rows, fontsize=8)
    ax.set_xlabel("diagnosed effect")
    ax.set_ylabel("hidden effect")
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)


def timing_check(repeats: int = 3) -> dict:
    """Wall time of diagnosing a 20 s, 3-DOF, 1 kHz recording (Table 1, cubic spring 2)."""
    from algid.diagnosis import diagnose
    from algid.simulator import simulate

    rng = np.random.default_rng(12345)
    u = multisine(3, 20.0, 1000.0, rng)
    res = simulate(
        TABLE1,
        u,
        20.0,
        1000.0,
        effects=[{"name": "cubic_stiffness", "location": {"spring": 2}, "params": {"k_cubic": 3e5}}],
        noise_db=50.0,
        seed=1,
    )
    rec = Recording(t=res.t, u=res.u, a=res.a)
    walls = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        d = diagnose(rec)
        walls.append(time.perf_counter() - t0)
    return {
        "recording": "20 s, 3 DOF, 1 kHz (Table 1, cubic_stiffness k3 = 3e5 on spring 2, 50 dB)",
        "wall_s": walls,
        "wall_s_median": float(np.median(walls)),
        "diagnosed": d.effect,
    }


def _parse_seeds(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        if ":" in part:
            a, b = part.split(":")
            out += list(range(int(a), int(b)))
        elif part:
            out.append(int(part))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0:30", help="seed list, e.g. 0:150 or 3,7,11:20 (default: 0:30)")
    ap.add_argument(
        "--work", type=Path, default=Path("/tmp/algid-blind"), help="folder for recordings/labels/diagnoses"
    )
    ap.add_argument("--duration", type=float, default=10.0, help="record length [s]")
    ap.add_argument("--fs", type=float, default=1000.0, help="sample rate [Hz]")
    ap.add_argument("--stage", choices=("all", "generate", "diagnose", "score"), default="all")
    ap.add_argument(
        "--results",
        type=Path,
        default=None,
        help="summary JSON (and its PNG beside it); default WORK/blind_diagnosis.json, "
        "the published one is bench/results/blind_diagnosis.json",
    )
    ap.add_argument("--timing", action="store_true", help="also time a 20 s 3-DOF 1 kHz diagnosis")
    ap.add_argument("--plots", action="store_true", help="write the diagnosis figures of every case")
    args = ap.parse_args(argv)
    seeds = _parse_seeds(args.seeds)
    work = args.work
    if args.results is None:
        args.results = work / "blind_diagnosis.json"
    if args.stage in ("all", "generate"):
        for k, seed in enumerate(seeds):
            t0 = time.perf_counter()
            generate(seed, work, args.duration, args.fs)
            print(
                f"[generate {k + 1}/{len(seeds)}] seed {seed} ({time.perf_counter() - t0:.1f} s)",
                file=sys.stderr,
                flush=True,
            )
    if args.stage in ("all", "diagnose"):
        for k, seed in enumerate(seeds):
            # The diagnosis is told the boundary, as a user would tell it; never the label.
            lab = json.loads((work / "labels" / f"case{seed:05d}.json").read_text())
            res = diagnose_case(seed, work, lab["boundary"], args.plots)
            (work / "diagnoses" / f"case{seed:05d}.json").write_text(json.dumps(res, indent=1))
            print(
                f"[diagnose {k + 1}/{len(seeds)}] seed {seed}: {res['effect']} ({res['_wall_s']:.1f} s)",
                file=sys.stderr,
                flush=True,
            )
    if args.stage in ("all", "score"):
        rows = score_all(work, seeds, score_case)
        summary = summarize(rows)
        out = {"seeds": args.seeds, "duration_s": args.duration, "fs_hz": args.fs, "summary": summary, "cases": rows}
        if args.timing:
            out["timing"] = timing_check()
        table = confusion_table(summary["confusion"])
        print(table)
        for key in (
            "cases",
            "top1_accuracy",
            "location_accuracy_among_correct",
            "param_within_20pct_among_correct",
            "median_gap_shrink_real",
            "median_gap_shrink_real_fullband",
            "median_band_hz",
            "median_band_white_noise_fraction",
            "median_gap_before_over_noise_floor_real",
            "median_gap_before_over_noise_floor_real_fullband",
            "median_gap_after_over_noise_floor_correct",
            "median_gap_shrink_by_visibility",
            "top1_by_visibility",
            "false_alarm_rate_none",
            "wall_s_median",
            "wall_s_max",
        ):
            print(f"{key:36s} {summary[key]}")
        if args.timing:
            print(f"{'timing 20 s 3-DOF 1 kHz [s]':36s} {out['timing']['wall_s_median']:.2f}")
        args.results.parent.mkdir(parents=True, exist_ok=True)
        args.results.write_text(json.dumps(out, indent=1))
        png = args.results.with_suffix(".png")
        confusion_png(
            summary["confusion"],
            png,
            f"blind diagnosis, seeds {args.seeds}: top-1 {summary['top1_accuracy']:.0%} over {summary['cases']} cases",
        )
        print(f"wrote {args.results} and {png}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
