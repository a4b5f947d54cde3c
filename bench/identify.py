"""Figures of ``algid identify`` / :func:`algid.identify` on noisy, slow and measured-like records.

Sections (all through the Python entry point the command line calls):

* ``accuracy``: Table 1, ``Chain.random(5, default_rng(5))`` and a free-end chain
  ``Chain.random(3, default_rng(7), boundary="free")``, 10 s at 1 kHz under the tests'
  multisine-plus-offset force (7 lines, 1.3-31 Hz), white noise at 40 dB on forces and
  accelerations, seeds 0..S-1: worst relative error per family (m, c, k), median over the
  seeds; the same records through the paper's single growing window for comparison.
* ``short``: Table 1, 0.2 s, noise-free: the error at 0.1 s and at the end.
* ``slow``: the positioning axis of :func:`algid.simulator.scenarios.positioning_axis` (5 kg, 25 N s/m,
  no spring, bang-bang moves under a saturated PID, 1 um encoder only, 20 s), seeds 0..S-1:
  mass and damping errors, the spring's verdict, valid negative parameters.
* ``band``: a 2-DOF chain (m 2, 1 kg; c 4, 2 N s/m; k 4800, 2000, 3000 N/m) under random
  forcing band-limited to 0.5-25 Hz on both DOFs, 20 s, 40 dB on forces and accelerations,
  five records per seed: validity and the largest |error| / sigma of a valid estimate.
* ``friction``: positioning axes with Coulomb friction (mass 2-20 kg, viscous 10-60 N s/m,
  Coulomb level 3-15 % of the drive's force limit, encoder step 1-10 um, 20 s, four axes
  per seed drawn from the seed): the linear fit's verdict, and ``--effect auto`` and
  ``--effect coulomb_friction:1``: relative errors of mass, viscous coefficient and Coulomb
  level, their |error| / sigma, validity.
* ``calibration``: the continuous benchmark's records (``bench/crlb.py``: Table 1 and the
  random 5-DOF chain, 20 Hz band-limited white forcing on every DOF, exact simulation), 10 s
  and 60 s, SNR 20-60 dB on the accelerations ("accel") or on both channels, seeds
  0..S-1: the median of |error| / sigma per SNR (pooled over systems, channels, seeds and
  parameters; 0.67 for a calibrated Gaussian sigma), and per family.
* ``one_force``: one shaker: Table 1 and random 4- and 6-DOF chains, the continuous
  benchmark's forcing on DOF 1 only and, separately, on an interior DOF, 20 s, 40 dB on the
  accelerations, seeds 0..S-1: validity, worst error per family, largest |error| / sigma and
  the error over the Cramer-Rao bound of that record per family (``bench/crlb.py``); and
  2 s of the same case noise-free (the single growing window): the largest relative error.
* ``suites``: every record of the accuracy suite (``bench/accuracy.py``), of the calibration
  section and of the blind diagnosis check (``bench/blind_diagnosis.py``, seeds given by
  ``--blind-seeds``): how many produce a valid mass that is not positive, and a valid
  damping or spring below zero by more than three sigma; on the blind cases, the fit
  check's figures: effect cases with any valid estimate, ``none`` cases with every estimate
  valid, and the largest |error| / sigma of a valid estimate on those.

The default (one seed, blind seeds 0:10) runs every section on fewer records and writes to
the temporary folder; the published figures (docs/identify.md) take three seeds
and 150 blind cases, 17 minutes here (the machine busy with other work):

    python bench/identify.py                                    # one seed, blind seeds 0:10
    python bench/identify.py --seeds 3 --blind-seeds 0:150 --json bench/results/identify.json
    python bench/identify.py --only accuracy,short,slow        # a subset of the sections
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
import algid  # noqa: E402
from algid.identification import crlb as C  # noqa: E402
from algid.model.chain import TABLE1, Chain  # noqa: E402
from algid.recording import Recording  # noqa: E402
from algid.simulator import simulate  # noqa: E402
from algid.simulator.exact import multisine, simulate_chain  # noqa: E402
from algid.simulator.scenarios import positioning_axis  # noqa: E402

FS = 1000.0
SNRS = (20, 30, 40, 50, 60)
#: Record length of the blind diagnosis check's cases [s] (its default).
BLIND_DURATION_S = 10.0
SECTIONS = ("accuracy", "short", "slow", "band", "friction", "calibration", "one_force", "suites")


def accuracy_systems() -> dict[str, Chain]:
    return {
        "table1": TABLE1,
        "random5": Chain.random(5, np.random.default_rng(5)),
        "free3": Chain.random(3, np.random.default_rng(7), boundary="free"),
    }


def families(n: int) -> dict[str, slice]:
    return {"m": slice(0, n), "c": slice(n, 2 * n), "k": slice(2 * n, 3 * n + 1)}


def worst_per_family(chain: Chain, theta: np.ndarray) -> dict[str, float]:
    truth = chain.identifiable()
    with np.errstate(invalid="ignore", divide="ignore"):
        err = np.abs(theta / truth - 1.0)
    keep = np.isfinite(truth) & (truth != 0)
    return {f: float(np.max(np.where(keep[s], err[s], 0.0))) for f, s in families(chain.n).items()}


def multisine_record(chain: Chain, seed: int, duration: float = 10.0, snr: float = 40.0) -> Recording:
    r = simulate(
        chain, multisine(chain.n, seed=seed), duration, FS, noise_db=snr, noise_on=("accel", "force"), seed=seed
    )
    return Recording(t=r.t, u=r.u, a=r.a)


# ---------------------------------------------------------------------------------- sections


def section_accuracy(seeds: int) -> dict:
    out = {}
    for name, chain in accuracy_systems().items():
        rows = []
        for seed in range(seeds):
            rec = multisine_record(chain, seed)
            t0 = time.perf_counter()
            res = algid.identify(rec, boundary=chain.boundary)
            wall = time.perf_counter() - t0
            win = algid.identify(rec, boundary=chain.boundary, estimator="window", replicates=2)
            rows.append(
                {
                    "seed": seed,
                    "worst": worst_per_family(chain, res.theta),
                    "worst_single_window": worst_per_family(chain, win.theta),
                    "valid": res.valid,
                    "window_s": res.plan.window_s,
                    "prefilter_hz": res.plan.prefilter_hz,
                    "wall_s": wall,
                }
            )
        med = {f: float(np.median([r["worst"][f] for r in rows])) for f in "mck"}
        med_w = {f: float(np.median([r["worst_single_window"][f] for r in rows])) for f in "mck"}
        out[name] = {"median_worst": med, "median_worst_single_window": med_w, "runs": rows}
        print(
            f"accuracy {name:8s} worst per family, median over {seeds} seeds: "
            + " ".join(f"{f} {100 * v:.3f} %" for f, v in med.items())
            + "   (single window: "
            + " ".join(f"{f} {100 * v:.3g} %" for f, v in med_w.items())
            + ")",
            flush=True,
        )
    return out


def section_short() -> dict:
    t, a, u, _ = simulate_chain(TABLE1, multisine(3), 0.2)
    res = algid.identify(Recording(t=t, u=u, a=a))
    truth = TABLE1.identifiable()
    at = int(np.searchsorted(res.time_s, 0.1))
    out = {
        "estimator": res.plan.estimator,
        "max_rel_error_end": float(np.max(np.abs(res.theta / truth - 1))),
        "max_rel_error_at_0.1s": float(np.max(np.abs(res.history[at] / truth - 1))),
        "valid": res.valid,
    }
    print(
        f"short    Table 1 0.2 s noise-free: {out['estimator']}, max error at 0.1 s "
        f"{out['max_rel_error_at_0.1s']:.2e}, at the end {out['max_rel_error_end']:.2e}",
        flush=True,
    )
    return out


def section_slow(seeds: int) -> dict:
    rows = []
    for seed in range(seeds):
        sc = positioning_axis(seed=seed, duration_s=20.0)
        res = algid.identify(sc.recording)
        bad = [
            v.name
            for p, v in enumerate(res.verdicts)
            if v.valid and np.isfinite(res.theta[p]) and res.theta[p] < -3 * res.sigma[p]
        ]
        rows.append(
            {
                "seed": seed,
                "mass_rel_error": float(res.mass[0] / 5.0 - 1),
                "damping_rel_error": float(res.damping[0] / 25.0 - 1),
                "spring": float(res.stiffness[0]),
                "spring_sigma": float(res.sigma_stiffness[0]),
                "spring_status": res.verdict("k1").status,
                "valid": res.valid,
                "valid_negative": bad,
                "window_s": res.plan.window_s,
            }
        )
        print(
            f"slow     axis seed {seed}: m {100 * rows[-1]['mass_rel_error']:+.3f} %, c "
            f"{100 * rows[-1]['damping_rel_error']:+.3f} %, k {rows[-1]['spring']:.3g} +- "
            f"{rows[-1]['spring_sigma']:.2g} N/m ({rows[-1]['spring_status']}), valid {res.valid}, "
            f"valid negative: {bad or 'none'}",
            flush=True,
        )
    return {"runs": rows}


def section_band(seeds: int) -> dict:
    from scipy.signal import butter, sosfiltfilt

    chain = Chain([2.0, 1.0], [4.0, 2.0], [4800.0, 2000.0, 3000.0])
    truth, rows = chain.identifiable(), []
    for seed in range(5 * seeds):
        F = np.random.default_rng(seed).standard_normal((int(20 * FS), 2))
        F = 20.0 * sosfiltfilt(butter(4, (0.5, 25.0), btype="bandpass", fs=FS, output="sos"), F, axis=0)
        r = simulate(chain, F, 20.0, FS, noise_db=40, noise_on=("accel", "force"), seed=seed)
        res = algid.identify(Recording(t=r.t, u=r.u, a=r.a))
        z = np.abs(res.theta - truth) / res.sigma
        valid = [p for p, v in enumerate(res.verdicts) if v.status in ("ok", "negligible")]
        rows.append({"seed": seed, "valid": res.valid, "max_abs_z_valid": float(max(z[valid], default=0.0))})
    worst = max(r["max_abs_z_valid"] for r in rows)
    print(f"band     2-DOF, 0.5-25 Hz: valid {sum(r['valid'] for r in rows)}/{len(rows)}, largest |z| {worst:.2f}")
    return {"runs": rows, "max_abs_z_valid": worst}


def friction_axes(seeds: int):
    """(label, truth, recording) of the ``friction`` section's axes."""
    for seed in range(seeds):
        rng = np.random.default_rng(1000 + seed)
        for k in range(4):
            m, c = float(rng.uniform(2.0, 20.0)), float(rng.uniform(10.0, 60.0))
            level = float(rng.uniform(0.03, 0.15)) * 12.0 * m  # of the drive's force limit
            q = float(np.exp(rng.uniform(np.log(1e-6), np.log(1e-5))))
            friction = {"name": "coulomb_friction", "location": {"dof": 1}, "params": {"force": level}}
            sc = positioning_axis(
                seed=4 * seed + k, duration_s=20.0, mass_kg=m, viscous_ns_m=c, encoder_m=q, effects=[friction]
            )
            yield f"seed {seed} axis {k}", {"m": m, "c": c, "force": level, "encoder_m": q}, sc.recording


def section_friction(seeds: int) -> dict:
    rows = []
    for label, truth, rec in friction_axes(seeds):
        row = {"case": label, **truth, "linear_valid": algid.identify(rec, boundary="free").valid}
        for spec in ("auto", "coulomb_friction:1"):
            res = algid.identify(rec, boundary="free", effects=[spec])
            e = res.effects[0] if res.effects else None
            est = {"m": res.mass[0], "c": res.damping[0], "force": e["params"]["force"] if e else np.nan}
            sd = {"m": res.sigma_mass[0], "c": res.sigma_damping[0], "force": e["params_std"]["force"] if e else np.nan}
            row[spec] = {
                "valid": res.valid,
                "effect": e["effect"] if e else None,
                **{f"{k}_rel_error": float(est[k] / truth[k] - 1) for k in est},
                **{f"{k}_z": float((est[k] - truth[k]) / sd[k]) for k in est},
            }
        rows.append(row)
        a = row["auto"]
        print(
            f"friction {label}: linear valid {row['linear_valid']}; auto {a['effect']}: m {100 * a['m_rel_error']:+.2f} %,"
            f" c {100 * a['c_rel_error']:+.2f} %, F {100 * a['force_rel_error']:+.2f} %, valid {a['valid']}",
            flush=True,
        )
    worst = {
        spec: {k: float(np.nanmax([abs(r[spec][f"{k}_rel_error"]) for r in rows])) for k in ("m", "c", "force")}
        for spec in ("auto", "coulomb_friction:1")
    }
    return {
        "runs": rows,
        "worst_rel_error": worst,
        "valid": {spec: sum(r[spec]["valid"] for r in rows) for spec in ("auto", "coulomb_friction:1")},
        "linear_valid": sum(r["linear_valid"] for r in rows),
        "cases": len(rows),
    }


def calibration_records(seeds: int, duration: float):
    """(system, snr, channels, seed, chain, Recording) of the continuous benchmark."""
    for name, chain in (("table1", TABLE1), ("random5", Chain.random(5, np.random.default_rng(5)))):
        for seed in range(seeds):
            rec = C.simulate(chain, duration, seed=seed)
            for snr in SNRS:
                for chans in (("accel",), ("accel", "force")):
                    a, u = rec.noisy(snr, chans, seed * 100 + snr)
                    yield name, snr, "+".join(chans), seed, chain, Recording(t=np.arange(a.shape[0]) / FS, u=u, a=a)


def section_calibration(seeds: int, durations=(10.0, 60.0)) -> tuple[dict, list]:
    out, masses = {}, []
    for duration in durations:
        rows = []
        for name, snr, chans, seed, chain, rec in calibration_records(seeds, duration):
            res = algid.identify(rec)
            truth = C.params_of(chain)
            z = np.abs(res.theta - truth) / res.sigma
            rows.append(
                {
                    "system": name,
                    "snr_db": snr,
                    "channels": chans,
                    "seed": seed,
                    "z": z.tolist(),
                    "rel_error": (res.theta / truth - 1).tolist(),
                    "n": chain.n,
                }
            )
            masses.append(_suite_row(f"continuous/{name}/{duration:g}s/{snr}dB/{chans}/{seed}", res))
        table = {}
        for snr in SNRS:
            zs = np.concatenate([r["z"] for r in rows if r["snr_db"] == snr])
            fam = {}
            for f in "mck":
                fam[f] = float(
                    np.median(
                        np.concatenate([np.asarray(r["z"])[families(r["n"])[f]] for r in rows if r["snr_db"] == snr])
                    )
                )
            table[str(snr)] = {"median_abs_z": float(np.median(zs)), "per_family": fam, "values": int(zs.size)}
            print(
                f"calib    {duration:4.0f} s {snr} dB: median |error|/sigma {table[str(snr)]['median_abs_z']:.2f} "
                f"(m {fam['m']:.2f}, c {fam['c']:.2f}, k {fam['k']:.2f}; {zs.size} values)",
                flush=True,
            )
        out[f"{duration:g}s"] = {"table": table, "runs": rows}
    return out, masses


def one_force_cases():
    """(system, chain, forced DOF 0-based): Table 1 and random 4- and 6-DOF chains, the force
    on DOF 1 and on an interior DOF."""
    for name, chain in (
        ("table1", TABLE1),
        ("random4", Chain.random(4, np.random.default_rng(4))),
        ("random6", Chain.random(6, np.random.default_rng(6))),
    ):
        for dof in (0, chain.n // 2):
            yield name, chain, dof


def section_one_force(seeds: int, duration: float = 20.0, snr: float = 40.0) -> dict:
    """One shaker: the continuous benchmark's forcing on one DOF only, noise on the
    accelerations (the Cramer-Rao bound's case, ``bench/crlb.py --forced``); per case the
    worst error per family, validity, the largest |error| / sigma and, per family, the error
    over the bound (median of |error| / bound over seeds and parameters, / 0.6745: 1 at the
    bound)."""
    out = {}
    for name, chain, dof in one_force_cases():
        truth, fam = C.params_of(chain), families(chain.n)
        rows, ratios = [], {f: [] for f in "mck"}
        for seed in range(seeds):
            rec = C.simulate(chain, duration, seed=seed, forced=[dof])
            a, u = rec.noisy(snr, ("accel",), seed)
            res = algid.identify(Recording(t=np.arange(a.shape[0]) / FS, u=u, a=a))
            bound = C.crlb(rec, snr, (duration,))[float(duration)] * np.abs(truth)
            err = np.abs(res.theta - truth)
            for f in "mck":
                ratios[f] += list(err[fam[f]] / bound[fam[f]])
            rows.append(
                {
                    "seed": seed,
                    "valid": bool(res.valid),
                    "invalid": [r for r in res.reasons if "negligible" not in r],
                    "worst": worst_per_family(chain, res.theta),
                    "max_abs_z": float(np.nanmax(err / res.sigma)),
                }
            )
        x_crlb = {f: float(np.median(v) / 0.6745) for f, v in ratios.items()}
        key = f"{name}/dof{dof + 1}"
        clean = C.simulate(chain, 2.0, seed=0, forced=[dof])  # noise-free: the single growing window
        res0 = algid.identify(Recording(t=np.arange(clean.a.shape[0]) / FS, u=clean.u, a=clean.a))
        noise_free = {
            "estimator": res0.plan.estimator,
            "valid": bool(res0.valid),
            "max_rel_error": float(np.nanmax(np.abs(res0.theta / truth - 1))),
        }
        out[key] = {"x_crlb": x_crlb, "runs": rows, "noise_free_2s": noise_free}
        worst = {f: max(r["worst"][f] for r in rows) for f in "mck"}
        print(
            f"one force {key:13s} valid {sum(r['valid'] for r in rows)}/{seeds}  worst "
            + " ".join(f"{f} {100 * worst[f]:.3f} %" for f in "mck")
            + "  x CRLB "
            + " ".join(f"{f} {x_crlb[f]:.2f}" for f in "mck")
            + f"  max |z| {max(r['max_abs_z'] for r in rows):.1f}"
            + f"  noise-free {noise_free['estimator']} {noise_free['max_rel_error']:.1e}",
            flush=True,
        )
    return out


def _suite_row(label: str, res) -> dict:
    n = res.n
    bad_mass = [v.name for p, v in enumerate(res.verdicts[:n]) if v.valid and not res.theta[p] > 0]
    bad_neg = [
        v.name
        for p, v in enumerate(res.verdicts[n:], start=n)
        if v.valid and np.isfinite(res.theta[p]) and res.theta[p] < -3 * res.sigma[p]
    ]
    return {"record": label, "valid_nonpositive_mass": bad_mass, "valid_negative": bad_neg}


def _fit_check_row(res, chain: Chain, effect: str) -> dict:
    """What the fit check makes of a blind case: the estimates called valid (``ok`` or
    ``negligible``, not the springs fixed by the model), all of them where they could be, and
    the largest |error| / sigma of a valid one against the simulated chain."""
    truth = chain.identifiable()
    estimated = [v for v in res.verdicts if v.status not in ("known", "not_separable")]
    valid = [p for p, v in enumerate(res.verdicts) if v.status in ("ok", "negligible")]
    z = [abs(res.theta[p] - truth[p]) / res.sigma[p] for p in valid if np.isfinite(res.sigma[p]) and res.sigma[p] > 0]
    return {
        "effect": effect,
        "valid_estimates": len(valid),
        "estimates": len(estimated),
        "max_abs_z_valid": float(max(z, default=0.0)),
        "fit_check": res.model_fit.get("diagnosis"),
    }


def section_suites(blind_seeds: list[int], calib_rows: list) -> dict:
    import accuracy
    import blind_diagnosis as B

    rows = list(calib_rows)
    rng = np.random.default_rng(1)
    chains = (
        [("table1", TABLE1)]
        + [(f"random_n{n}", Chain.random(n, rng)) for n in (1, 2, 5, 10)]
        + [(f"free_n{n}", Chain.random(n, rng, boundary="free")) for n in (1, 3, 5)]
    )
    for name, chain in chains:
        forces = [("multisine", multisine(chain.n, 1), ())] + [
            ("step", *accuracy.step_force(chain.n, edge_s=0.002, seed=1))
        ]
        for fname, force, breaks in forces:
            t, a, u, _ = simulate_chain(chain, force, 0.5, FS, breaks=breaks)
            res = algid.identify(Recording(t=t, u=u, a=a), boundary=chain.boundary)
            rows.append(_suite_row(f"accuracy/{name}/{fname}", res))
    checks = []
    for seed in blind_seeds:
        case = B.draw_case(seed, BLIND_DURATION_S, FS)
        lab = case["label"]
        r = simulate(
            case["chain"],
            case["u"],
            lab["duration_s"],
            lab["fs_hz"],
            effects=case["effects"],
            noise_db=lab["snr_db"],
            noise_on=("accel",),
            seed=seed,
        )
        res = algid.identify(Recording(t=r.t, u=r.u, a=r.a), boundary=lab["boundary"])
        rows.append(_suite_row(f"blind/{seed}/{lab['effect']}", res))
        checks.append(_fit_check_row(res, case["chain"], lab["effect"]))
    nonpos = [r for r in rows if r["valid_nonpositive_mass"]]
    neg = [r for r in rows if r["valid_negative"]]
    effect = [c for c in checks if c["effect"] != "none"]
    none = [c for c in checks if c["effect"] == "none"]
    fit_check = {
        "effect_cases": len(effect),
        "effect_cases_with_a_valid_estimate": sum(c["valid_estimates"] > 0 for c in effect),
        "none_cases": len(none),
        "none_cases_all_valid": sum(c["valid_estimates"] == c["estimates"] for c in none),
        "none_max_abs_z_valid": max((c["max_abs_z_valid"] for c in none), default=0.0),
        "cases": checks,
    }
    print(
        f"suites   {len(rows)} records: {len(nonpos)} with a valid mass <= 0, {len(neg)} with a valid damping or "
        f"spring below -3 sigma; blind effect cases with a valid estimate {fit_check['effect_cases_with_a_valid_estimate']}"
        f"/{len(effect)}, none cases all valid {fit_check['none_cases_all_valid']}/{len(none)} (largest |error| / "
        f"sigma of a valid estimate {fit_check['none_max_abs_z_valid']:.2f})",
        flush=True,
    )
    return {
        "records": len(rows),
        "valid_nonpositive_mass": nonpos,
        "valid_negative": neg,
        "fit_check": fit_check,
        "rows": rows,
    }


def _seeds(text: str) -> list[int]:
    out = []
    for part in text.split(","):
        if ":" in part:
            a, b = part.split(":")
            out.extend(range(int(a), int(b)))
        elif part:
            out.append(int(part))
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--seeds", type=int, default=1, help="seeds per system (default: 1; the docs: 3)")
    p.add_argument(
        "--blind-seeds", default="0:10", help="blind-check cases of the suites (default: 0:10; the docs: 0:150)"
    )
    p.add_argument("--only", default=",".join(SECTIONS), help=f"comma-separated sections of {SECTIONS}")
    p.add_argument(
        "--json",
        type=Path,
        default=Path(tempfile.gettempdir()) / "algid-bench" / "identify.json",
        help="where the figures go (default: TMP/algid-bench/identify.json; the docs': bench/results/identify.json)",
    )
    args = p.parse_args(argv)
    only = [s for s in args.only.split(",") if s]
    unknown = set(only) - set(SECTIONS)
    if unknown:
        p.error(f"unknown sections {sorted(unknown)}")
    t0 = time.perf_counter()
    doc: dict = {"seeds": args.seeds, "fs_hz": FS}
    if "accuracy" in only:
        doc["accuracy"] = section_accuracy(args.seeds)
    if "short" in only:
        doc["short"] = section_short()
    if "slow" in only:
        doc["slow"] = section_slow(args.seeds)
    if "band" in only:
        doc["band"] = section_band(args.seeds)
    if "friction" in only:
        doc["friction"] = section_friction(args.seeds)
    calib_rows: list = []
    if "calibration" in only:
        doc["calibration"], calib_rows = section_calibration(args.seeds)
    if "one_force" in only:
        doc["one_force"] = section_one_force(args.seeds)
    if "suites" in only:
        doc["suites"] = section_suites(_seeds(args.blind_seeds), calib_rows)
    doc["wall_s"] = time.perf_counter() - t0
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(doc, indent=1))
    print(f"wrote {args.json} ({doc['wall_s']:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
