"""Realistic blind check of ``algid diagnose`` (issue 16): hidden effects under the nuisances
of measured data.

Measures: top-1 effect, location, main parameter and gap shrink of the diagnosis on three
kinds of rig with sensor and drive nuisances, false alarms, answers ``none`` on real effects,
the wall time per diagnosis. The default (30 seeds, 0:30) is a quick look and writes to
``WORK`` only; the published figures (docs/diagnosis.md, README.md, about 20 min) are::

    python bench/realistic_blind.py --seeds 20000:20300 --work /tmp/realistic-20k \
        --results bench/results/realistic_blind.json

Every seed draws a rig and everything about it; the recording (only what the rig measures)
goes to ``WORK/recordings/``, the label to ``WORK/labels/``; the diagnosis runs on the
recording alone through the code path of ``algid diagnose`` and the scoring reads labels
and diagnoses only (as ``bench/blind_diagnosis.py``, whose scoring it shares).

Rigs (probabilities 0.5 / 0.25 / 0.25):

* ``shaker``: the blind check's chain and broadband forcing (``blind_diagnosis.draw_case``,
  n = 1..4, effect size by visibility 0.5-50, accelerometer SNR 40-60 dB), with any of
  the eleven effects (``sensor_highpass`` among them: an AC-coupled accelerometer) or none,
  recorded by accelerometers (or, with probability 0.2, a laser
  vibrometer: velocities) and force sensors, with nuisances each drawn with its own
  probability: white force-sensor noise (always, 40-60 dB); a force-sensor offset (0.5;
  5-50 % of the force RMS); coloured (1/f) sensor noise as strong as the white (0.4);
  mains hum, 50 or 60 Hz and two harmonics, 3x the white noise RMS on every channel
  (0.3); the same anti-alias filter on every channel (0.5; 4th-order Butterworth at
  0.25-0.45 fs, causal); sample jitter (0.3; 1-5 % of the sample period); an extra
  structural mode above the chain's (0.3; a flexible right support or a light appendage
  at 2-4 times the highest natural frequency and 4-8 times the top of the forcing band,
  at most 0.45 fs, not recorded).
* ``axis``: the positioning axis of :func:`algid.scenarios.positioning_axis` (mass
  2-10 kg, viscous 10-50 N s/m, no spring, closed-loop bang-bang moves, 20 s, encoder of
  0.5-5 um, position only), the force as the drive commands it with 40-60 dB of current
  noise; an unrecorded constant force (0.7; 2-20 % of the force RMS); effect none,
  ``coulomb_friction``, ``stribeck_friction``, ``quadratic_damping`` or ``input_delay``.
* ``device``: the displacement-driven device of :func:`algid.scenarios.displacement_driven`
  (inertia negligible; m 0.02-0.2 kg, c 50-500 N s/m, k 5e3-5e4 N/m, amplitude 1-5 mm,
  40-60 dB on force and displacement, a force offset with probability 0.5); effect none,
  ``coulomb_friction``, ``clearance`` (a backlash: the spring bites beyond a gap of 5-30 %
  of the amplitude), ``cubic_stiffness`` or ``amplitude_damping``.

Effect sizes on the axis and the device: the effect's force is a share r of the force RMS
drawn log-uniformly in [0.03, 0.3] (a Stribeck peak 1.5-3 times its Coulomb level).

Scores (issue 16): as the blind check (top-1, location, main parameter within 20 %, in-band
gap shrink) plus the share of effect cases answered ``none`` and the share of ``none``
answers on an inadmissible linear fit.

    python bench/realistic_blind.py                                              # seeds 0:30, quick look
    python bench/realistic_blind.py --seeds 0:150 --work /tmp/realistic          # tuning seeds
    python bench/realistic_blind.py --seeds 20000:20300 --work /tmp/realistic-20k \
        --results bench/results/realistic_blind.json                             # the report
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.signal import butter, lfilter

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import blind_diagnosis as B  # noqa: E402

from algid.chain import Chain  # noqa: E402
from algid.recording import Recording, save_recording  # noqa: E402
from algid.scenarios import displacement_driven, positioning_axis  # noqa: E402
from algid.simulator import simulate  # noqa: E402

FS = 1000.0
DURATION = 10.0
AXIS_DURATION = 20.0
SHAKER_EFFECTS = B.EFFECTS + B.MORE_EFFECTS
AXIS_EFFECTS = ("none", "coulomb_friction", "stribeck_friction", "quadratic_damping", "input_delay")
DEVICE_EFFECTS = ("none", "coulomb_friction", "clearance", "cubic_stiffness", "amplitude_damping")


def _share(rng) -> float:
    return float(np.exp(rng.uniform(np.log(0.03), np.log(0.3))))


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.asarray(x) ** 2)))


# ------------------------------------------------------------------------------ nuisances


def pink(T: int, n: int, rng) -> np.ndarray:
    """Unit-RMS 1/f noise (T, n)."""
    f = np.fft.rfftfreq(T)
    g = np.where(f > 0, 1.0 / np.sqrt(np.maximum(f, 1.0 / T)), 0.0)
    w = np.fft.irfft(np.fft.rfft(rng.standard_normal((T, n)), axis=0) * g[:, None], T, axis=0)
    return w / w.std(axis=0)


def sensor_chain(t, u, y, rng, snr_db: float, info: dict) -> tuple[np.ndarray, np.ndarray]:
    """The shaker rig's sensors: white noise on both channels, then the drawn nuisances."""
    T, n = y.shape
    fs = 1.0 / (t[1] - t[0])
    white_y = 10 ** (-snr_db / 20) * y.std(axis=0)
    snr_u = float(rng.uniform(40, 60))
    white_u = 10 ** (-snr_u / 20) * u.std(axis=0)
    info["force_snr_db"] = snr_u
    if rng.uniform() < 0.3:  # jitter: the sample is taken at t_k + delta_k
        j = float(rng.uniform(0.01, 0.05))
        delta = j / fs * rng.standard_normal(T)[:, None]
        u = u + delta * np.gradient(u, 1 / fs, axis=0)
        y = y + delta * np.gradient(y, 1 / fs, axis=0)
        info["jitter_of_dt"] = j
    y = y + white_y * rng.standard_normal((T, n))
    u = u + np.where(np.any(u != 0, axis=0), white_u, 0.0) * rng.standard_normal((T, n))
    if rng.uniform() < 0.4:
        y = y + white_y * pink(T, n, rng)
        info["coloured_noise"] = True
    if rng.uniform() < 0.3:
        f0 = float(rng.choice([50.0, 60.0]))
        hum = sum(np.sin(2 * np.pi * h * f0 * t + rng.uniform(0, 2 * np.pi)) / h for h in (1, 2, 3))[:, None]
        y = y + 3 * white_y * hum / _rms(hum)
        u = u + np.where(np.any(u != 0, axis=0), 3 * white_u, 0.0) * hum / _rms(hum)
        info["mains_hz"] = f0
    if rng.uniform() < 0.5:
        b = rng.uniform(0.05, 0.5, n) * u.std(axis=0) * rng.choice([-1.0, 1.0], n)
        u = u + np.where(np.any(u != 0, axis=0), b, 0.0)
        info["force_offset"] = b.tolist()
    if rng.uniform() < 0.5:
        fc = float(rng.uniform(0.25, 0.45))
        bb, aa = butter(4, 2 * fc)
        u, y = lfilter(bb, aa, u, axis=0), lfilter(bb, aa, y, axis=0)
        info["antialias_of_fs"] = fc
    return u, y


def with_extra_mode(chain: Chain, rng, info: dict) -> Chain:
    """An (n+1)-DOF plant: the chain plus a light mass at its right end, on a flexible
    support (fixed end) or as an appendage (free end), its mode 2-4 x the chain's top and
    4-8 x the top of the forcing band, at most 0.45 fs (a higher mode of the structure,
    above the test)."""
    n = chain.n
    fmax = float(chain.natural_frequencies_hz().max())
    me = 0.1 * float(chain.mass.min())
    fe = min(max(fmax * float(rng.uniform(2.0, 4.0)), B.F_BAND_HZ[1] * float(rng.uniform(4.0, 8.0))), 0.45 * FS)
    ke = me * (2 * np.pi * fe) ** 2
    m = np.r_[chain.mass, me]
    c = np.r_[chain.damping, 0.01 * chain.damping.mean()]
    if chain.boundary == "fixed":  # k_{n+1} split in two springs in series around the light mass:
        kw = chain.stiffness[n]  # the same wall spring at low frequency, a mode ka + kb = me we^2
        S = max(ke, 4.0 * kw)
        root = np.sqrt(max(S * S - 4.0 * S * kw, 0.0))
        ka, kb = 0.5 * (S + root), 0.5 * (S - root)
        k = np.r_[chain.stiffness[:n], ka, kb]
        plant = Chain(m, c, k, "fixed")
    else:
        plant = Chain(m, c, np.r_[chain.stiffness[:n], ke, 0.0], "free")
    info["extra_mode_hz"] = float(plant.natural_frequencies_hz().max())
    return plant


# ---------------------------------------------------------------------------------- rigs


def shaker_case(seed: int, rng) -> tuple[Recording, dict]:
    case = B.draw_case(seed, DURATION, FS, effects=SHAKER_EFFECTS)
    lab, chain = case["label"], case["chain"]
    info: dict = {"rig": "shaker"}
    plant = chain
    loc = lab.get("location") or {}
    if (
        rng.uniform() < 0.3
        and not (chain.boundary == "fixed" and loc.get("spring") == chain.n + 1)
        and chain.n >= 1
        and not (chain.n == 1 and chain.boundary == "fixed")
    ):
        plant = with_extra_mode(chain, rng, info)
    n = chain.n
    u_full = np.zeros((case["u"].shape[0], plant.n))
    u_full[:, :n] = case["u"]
    r = simulate(plant, u_full, DURATION, FS, effects=case["effects"])
    # a vibrometer only where the hidden effect is not the accelerometer's own
    velocity = rng.uniform() < 0.2 and lab["effect"] not in ("sensor_bias", "sensor_lowpass", "sensor_highpass")
    y = (r.v if velocity else r.a)[:, :n]
    u, y = sensor_chain(r.t, r.u[:, :n], y, rng, lab["snr_db"], info)
    info["motion"] = "velocity" if velocity else "acceleration"
    rec = Recording(t=r.t, u=u, v=y) if velocity else Recording(t=r.t, u=u, a=y)
    lab.update(info)
    return rec, lab


def axis_case(seed: int, rng) -> tuple[Recording, dict]:
    m, c = float(rng.uniform(2, 10)), float(rng.uniform(10, 50))
    effect = AXIS_EFFECTS[int(rng.integers(len(AXIS_EFFECTS)))]
    q = float(rng.choice([0.5e-6, 1e-6, 2e-6, 5e-6]))
    probe = positioning_axis(seed, AXIS_DURATION, m, c, encoder_m=q)  # the nominal force level
    u_rms = _rms(probe.recording.u)
    v_rms = _rms(np.gradient(probe.recording.x[:, 0], 1 / FS))
    r = _share(rng)
    params: dict = {}
    if effect == "coulomb_friction":
        params = {"force": r * u_rms}
    elif effect == "stribeck_friction":
        params = {
            "force": r * u_rms,
            "static": r * u_rms * float(rng.uniform(1.5, 3.0)),
            "v_stribeck": float(rng.uniform(0.05, 0.3)) * v_rms,
        }
    elif effect == "quadratic_damping":
        params = {"c_quadratic": r * u_rms / v_rms**2}
    elif effect == "input_delay":
        params = {"delay": float(rng.uniform(0.002, 0.02))}
    effects = [] if effect == "none" else [{"name": effect, "location": {"dof": 1}, "params": params}]
    offset = float(rng.uniform(0.02, 0.2) * u_rms * rng.choice([-1, 1])) if rng.uniform() < 0.7 else 0.0
    if offset:
        effects.append({"name": "force_offset", "location": {"dof": 1}, "params": {"offset": offset}})
    sc = positioning_axis(seed, AXIS_DURATION, m, c, encoder_m=q, effects=effects)
    snr_u = float(rng.uniform(40, 60))
    u = sc.recording.u + 10 ** (-snr_u / 20) * sc.recording.u.std() * rng.standard_normal(sc.recording.u.shape)
    rec = Recording(t=sc.recording.t, u=u, x=sc.recording.x)
    lab = _label(
        seed,
        effect,
        {"dof": 1},
        params,
        Chain([m], [c], [0.0, 0.0]),
        snr_u,
        {"rig": "axis", "encoder_m": q, "force_offset_unrecorded": offset, "share": r},
    )
    return rec, lab


def device_case(seed: int, rng) -> tuple[Recording, dict]:
    m, c = float(rng.uniform(0.02, 0.2)), float(rng.uniform(50, 500))
    k, amp = float(np.exp(rng.uniform(np.log(5e3), np.log(5e4)))), float(rng.uniform(1e-3, 5e-3))
    effect = DEVICE_EFFECTS[int(rng.integers(len(DEVICE_EFFECTS)))]
    snr = float(rng.uniform(40, 60))
    x_rms = amp / np.sqrt(2)
    u_rms = k * x_rms  # the spring dominates a quasi-static device
    v_rms = x_rms * 2 * np.pi * 1.1
    r = _share(rng)
    params: dict = {}
    k_lin = k
    loc = {"dof": 1}
    if effect == "coulomb_friction":
        params = {"force": r * u_rms}
    elif effect == "clearance":
        params = {"gap": float(rng.uniform(0.05, 0.3)) * amp, "k_contact": k}
        k_lin, loc = 0.0, {"spring": 1}
    elif effect == "cubic_stiffness":
        params = {"k_cubic": float(rng.choice([-0.5, 1.0])) * r * k / x_rms**2}
        loc = {"spring": 1}
    elif effect == "amplitude_damping":
        params = {"c_amp": r * u_rms / (x_rms * v_rms)}
        loc = {"spring": 1}
    effects = [] if effect == "none" else [{"name": effect, "location": loc, "params": params}]
    sc = displacement_driven(seed, 20.0, m, c, k_lin, effects, amplitude_m=amp, noise_db=snr)
    u = sc.recording.u
    info = {"rig": "device", "share": r, "amplitude_m": amp}
    if rng.uniform() < 0.5:
        b = float(rng.uniform(0.05, 0.5) * u.std() * rng.choice([-1, 1]))
        u = u + b
        info["force_offset"] = b
    rec = Recording(t=sc.recording.t, u=u, x=sc.recording.x)
    return rec, _label(
        seed, effect, loc if effect != "none" else None, params, Chain([m], [c], [k_lin, 0.0]), snr, info
    )


def _label(seed, effect, loc, params, chain, snr, info) -> dict:
    lab = {
        "seed": seed,
        "n": chain.n,
        "boundary": chain.boundary,
        "snr_db": snr,
        "effect": effect,
        "location": loc if effect != "none" else None,
        "params": {k: float(v) for k, v in params.items()},
        "visibility": float(info.get("share", 0.0)) * 100,
        "chain": {
            "mass": chain.mass.tolist(),
            "damping": chain.damping.tolist(),
            "stiffness": chain.stiffness.tolist(),
        },
    }
    lab.update(info)
    return lab


def draw(seed: int) -> tuple[Recording, dict]:
    """The recording and label of one case (deterministic in ``seed``)."""
    rng = np.random.default_rng([seed, 16])
    rig = rng.choice(["shaker", "shaker", "axis", "device"])
    return {"shaker": shaker_case, "axis": axis_case, "device": device_case}[str(rig)](seed, rng)


# ------------------------------------------------------------------------------ stages


def generate(seed: int, work: Path) -> None:
    rec_path = work / "recordings" / f"case{seed:05d}.npz"
    lab_path = work / "labels" / f"case{seed:05d}.json"
    if rec_path.exists() and lab_path.exists():
        return
    rec, lab = draw(seed)
    rec_path.parent.mkdir(parents=True, exist_ok=True)
    lab_path.parent.mkdir(parents=True, exist_ok=True)
    save_recording(rec_path, rec)
    lab_path.write_text(json.dumps(lab, indent=1))


def score(lab: dict, res: dict) -> dict:
    row = B.score_case(lab, res)
    row["rig"] = lab["rig"]
    model = res.get("model") or {}
    row["model"] = model.get("verdict")
    row["none_on_inadmissible"] = bool(res["effect"] == "none" and not model.get("admissible", True))
    return row


def summarize(rows: list[dict]) -> dict:
    out = B.summarize(rows)
    real = [r for r in rows if r["truth"] != "none"]
    out["false_none_on_effect"] = float(np.mean([r["pred"] == "none" for r in real])) if real else None
    out["none_on_inadmissible"] = float(np.mean([r["none_on_inadmissible"] for r in rows]))
    out["per_rig"] = {}
    for rig in ("shaker", "axis", "device"):
        rs = [r for r in rows if r["rig"] == rig]
        if rs:
            s = B.summarize(rs)
            out["per_rig"][rig] = {
                k: s[k]
                for k in (
                    "cases",
                    "top1_accuracy",
                    "location_accuracy_among_correct",
                    "param_within_20pct_among_correct",
                    "median_gap_shrink_real",
                    "false_alarm_rate_none",
                )
            }
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0:30", help="seed list, e.g. 0:150 or 3,7,11:20 (default: 0:30)")
    ap.add_argument("--work", type=Path, default=Path("/tmp/algid-realistic"))
    ap.add_argument("--stage", choices=("all", "generate", "diagnose", "score"), default="all")
    ap.add_argument(
        "--results",
        type=Path,
        default=None,
        help="summary JSON (and its PNG beside it); default WORK/realistic_blind.json, "
        "the published one is bench/results/realistic_blind.json",
    )
    args = ap.parse_args(argv)
    seeds = B._parse_seeds(args.seeds)
    work = args.work
    if args.results is None:
        args.results = work / "realistic_blind.json"
    if args.stage in ("all", "generate"):
        for k, seed in enumerate(seeds):
            t0 = time.perf_counter()
            generate(seed, work)
            print(
                f"[generate {k + 1}/{len(seeds)}] seed {seed} ({time.perf_counter() - t0:.1f} s)",
                file=sys.stderr,
                flush=True,
            )
    if args.stage in ("all", "diagnose"):
        for k, seed in enumerate(seeds):
            out = work / "diagnoses" / f"case{seed:05d}.json"
            lab = json.loads((work / "labels" / f"case{seed:05d}.json").read_text())
            res = B.diagnose_case(seed, work, lab["boundary"])
            out.write_text(json.dumps(res, indent=1))
            print(
                f"[diagnose {k + 1}/{len(seeds)}] seed {seed} {lab['rig']}: {lab['effect']} -> {res['effect']} "
                f"({res['_wall_s']:.1f} s)",
                file=sys.stderr,
                flush=True,
            )
    if args.stage in ("all", "score"):
        rows = B.score_all(work, seeds, score)
        summary = summarize(rows)
        print(B.confusion_table(summary["confusion"]))
        for key in (
            "cases",
            "top1_accuracy",
            "location_accuracy_among_correct",
            "param_within_20pct_among_correct",
            "median_gap_shrink_real",
            "false_alarm_rate_none",
            "false_none_on_effect",
            "none_on_inadmissible",
            "wall_s_median",
            "wall_s_max",
        ):
            print(f"{key:36s} {summary[key]}")
        for rig, s in summary["per_rig"].items():
            print(f"{rig:8s} {s}")
        args.results.parent.mkdir(parents=True, exist_ok=True)
        args.results.write_text(json.dumps({"seeds": args.seeds, "summary": summary, "cases": rows}, indent=1))
        B.confusion_png(
            summary["confusion"],
            args.results.with_suffix(".png"),
            f"realistic blind diagnosis, seeds {args.seeds}: top-1 {summary['top1_accuracy']:.0%}",
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
