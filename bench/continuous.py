"""Issue 4 benchmark: continuous operation under noise and parameter changes, side by side with
RLS and a UKF, against the Cramer-Rao lower bound.

Systems: Table 1 (3 DOF) and a random 5-DOF chain (``Chain.random(5, default_rng(5))``), 1 kHz,
60 s of broadband forcing (every DOF: white noise through a 4th-order 20 Hz Butterworth, RMS
10 N; exact simulation, see bench/crlb.py), chain in a stationary random state at t = 0.
Noise: white, RMS = 10^(-SNR/20) x the channel's RMS, SNR in {none, 60, 40, 20} dB, on the
accelerations only ("accel", force known: the case the Cramer-Rao bound is computed for) and
on accelerations and forces ("accel+force").

Estimators:
* ``continuous``: algid.ContinuousEstimator with its defaults (weak-form windows; no tuning);
* ``rls``: RLS with forgetting on row 1 of eqs. 3-4 over reseeded windows, fed the signals
  through the algebraic windows' prefilter (Butterworth, order 4 at fs/20: it works on the
  algebraic windows' regressors and gains as much from it as they do), two settings
  tuned on a separate seed (``--tune``): ``rls-inf`` (no forgetting: best on a constant
  system) and ``rls-fair`` (best worst-case score over the issue's targets, see ``score``);
* ``ukf``: filterpy UKF on states and log-parameters, the random-walk intensity tuned the
  same way; it runs 4x decimated on low-passed signals and only on a subset (``--ukf-*``;
  a full-rate 60 s UKF in Python costs ~90 s per run).

Figures per parameter family (m, c, k): median and 95th percentile over (seeds x parameters)
of the relative error at 1, 10 and 60 s; the first time every parameter of the family is
within 1 % (median over seeds); the error as a multiple of the Cramer-Rao bound (median over
seeds x parameters of |error| / sigma_CRLB, divided by 0.6745 so that an efficient unbiased
estimator scores 1). Tracking (noise on both channels): one spring drops 20 % at 30 s (k2 of
Table 1, k3 of the 5-DOF chain), the last spring drifts -10 % linearly over 60 s; the delay
until the stepped spring's estimate is within 2 % of its new value for good, the drifting
spring's worst error over 10-60 s and its share of time within 2 %, and the change events on
unchanged parameters (false alarms); events on constant systems are counted too.

The default runs one seed per system (a quick look at every figure); the published tables
(docs/continuous.md, bench/results/continuous.json) come from three seeds and the UKF at 40
and 20 dB, the 16-seed rows from ``--seeds 16 --no-ukf --snr 40`` (docs/continuous.md):

    python bench/continuous.py                 # one seed per system
    python bench/continuous.py --seeds 3 --ukf-snr 40 20 --json bench/results/continuous.json
    python bench/continuous.py --tune          # re-tune the baselines on seed 1000
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from pathlib import Path

import numpy as np
from scipy.signal import butter, lfilter

HERE = Path(__file__).resolve().parent
import baselines  # noqa: E402

import algid  # noqa: E402
from algid.identification import crlb as C  # noqa: E402
from algid.model.chain import TABLE1, Chain  # noqa: E402

FS = 1000.0
DT = 1.0 / FS
DURATION = 60.0
TIMES = (1.0, 10.0, 60.0)
GRID = 10  # history resolution [samples]
STEP_AT, STEP_FACTOR, DRIFT = 30.0, 0.8, -0.10
TUNE_SEED = 1000

#: Baseline settings from ``--tune`` (Table 1, seed 1000, 40 dB on accelerations and forces).
TUNED = {
    "rls-inf": {"window_s": 0.1, "memory_s": float("inf")},  # windows 0.1/0.3/1 s: best at 10 s
    "rls-fair": {"window_s": 0.1, "memory_s": 0.3},  # score 1.27 (step tracked in 1.2 s)
    "ukf": {"q_param": 3e-3},  # score 0.64 (q = 0: 0.027-0.17 % but no tracking)
}


def systems() -> dict[str, Chain]:
    return {"table1": TABLE1, "random5": Chain.random(5, np.random.default_rng(5))}


def families(n: int) -> dict[str, np.ndarray]:
    return {"m": np.arange(n), "c": np.arange(n, 2 * n), "k": np.arange(2 * n, 3 * n + 1)}


def tracking_params(name: str, n: int) -> tuple[int, int]:
    """(stepped parameter index, drifting parameter index) into m, c, k."""
    return (2 * n + 1 if name == "table1" else 2 * n + 2), 3 * n


def schedule_for(chain: Chain, name: str):
    p0 = C.params_of(chain)
    js, jd = tracking_params(name, chain.n)

    def schedule(t):
        p = p0.copy()
        if t >= STEP_AT:
            p[js] *= STEP_FACTOR
        p[jd] *= 1.0 + DRIFT * t / DURATION
        return p

    return schedule


def noise_seed(seed: int, snr, config: str) -> int:
    return int(seed * 1000 + (0 if snr is None else int(snr)) * 3 + (1 if config == "accel+force" else 0))


def noise_channels(config: str) -> tuple[str, ...]:
    return ("accel",) if config == "accel" else ("accel", "force")


# ---------------------------------------------------------------------------------------------
# estimators -> estimate histories on the GRID (row r: data up to sample (r+1) GRID - 1)


def read_index(T: int) -> np.ndarray:
    return np.arange(GRID - 1, T, GRID)


#: ``--set`` options of the continuous estimator (none: its defaults, as benchmarked in the docs)
OPTIONS: dict[str, float] = {}


def run_continuous(a, u, n, sigma_out: list | None = None):
    est = algid.ContinuousEstimator(n, DT, **OPTIONS)
    t0 = time.perf_counter()
    out = est.run(a, u)
    cost = (time.perf_counter() - t0) / a.shape[0]
    if sigma_out is not None:
        sigma_out.append(out["sigma"][read_index(a.shape[0])])
    return out["estimate"][read_index(a.shape[0])], out["events"], cost


SETTLE = 115  # samples: the prefilter's start-up transient below 1e-6 (as the C++ settle_samples)


def prefilter(a, u):
    """The algebraic windows' prefilter (Butterworth order 4 at fs/20, causal), given to RLS:
    it works on the same regressors and gains the same."""
    b, den = butter(4, 0.05 * 2.0)
    return lfilter(b, den, a, axis=0), lfilter(b, den, u, axis=0)


def rls_prefiltered(a, u, read, **kw):
    """RLS on the prefiltered signals, its windows starting after the filter has settled
    (as the continuous estimator's do); NaN before."""
    af, uf = prefilter(a, u)
    read = np.asarray(read)
    res = baselines.rls(af[SETTLE:], uf[SETTLE:], DT, np.maximum(read - SETTLE, 0), **kw)
    for r in res if isinstance(res, list) else [res]:
        r[read < SETTLE] = np.nan
    return res


def run_rls(a, u, n, settings: dict[str, dict]):
    """All RLS settings sharing a window length in one pass (on prefiltered signals)."""
    read = read_index(a.shape[0])
    out = {}
    by_window: dict[float, list[str]] = {}
    for name, s in settings.items():
        by_window.setdefault(s["window_s"], []).append(name)
    for w, names in by_window.items():
        t0 = time.perf_counter()
        res = rls_prefiltered(a, u, read, window_s=w, memory_s=[settings[k]["memory_s"] for k in names])
        cost = (time.perf_counter() - t0) / a.shape[0] / len(names)
        for k, r in zip(names, res):
            out[k] = (r, cost)
    return out


def run_ukf(a, u, chain: Chain, rec_clean_a, rec_clean_u, snr, config, seconds, q_param, seed):
    T = int(round(seconds * FS))
    read = read_index(T)
    ratio = 0.0 if snr is None else 10 ** (-snr / 20)
    sigma_a = ratio * C.rms(rec_clean_a)
    sigma_u = ratio * C.rms(rec_clean_u) if config == "accel+force" else np.zeros(chain.n)
    t0 = time.perf_counter()
    est, diverged = baselines.ukf(
        a[:T],
        u[:T],
        DT,
        read,
        truth0=C.params_of(chain),
        sigma_a=sigma_a,
        sigma_u=sigma_u,
        q_param=q_param,
        seed=seed,
        boundary=chain.boundary,
    )
    cost = (time.perf_counter() - t0) / T
    return est, diverged, cost


# ---------------------------------------------------------------------------------------------
# metrics


def errors_at(hist: np.ndarray, truth: np.ndarray, t_s: float) -> np.ndarray:
    """|relative error| per parameter with data up to t_s (NaN where not available)."""
    r = int(round(t_s * FS / GRID)) - 1
    if r >= hist.shape[0]:
        return np.full(truth.shape[-1], np.nan)
    tr = truth[min(r, truth.shape[0] - 1)] if truth.ndim == 2 else truth
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.abs(hist[r] / tr - 1.0)


def first_within(hist: np.ndarray, truth: np.ndarray, cols: np.ndarray, tol: float = 0.01) -> float:
    with np.errstate(invalid="ignore", divide="ignore"):
        ok = np.all(np.abs(hist[:, cols] / truth[cols] - 1.0) <= tol, axis=1)
    hit = np.nonzero(ok)[0]
    return float((hit[0] + 1) * GRID * DT) if hit.size else float("inf")


def settle_delay(hist: np.ndarray, truth_grid: np.ndarray, col: int, after_s: float, tol: float = 0.02) -> float:
    """Time after ``after_s`` until the estimate stays within ``tol`` of the truth (inf if never)."""
    t = (np.arange(hist.shape[0]) + 1) * GRID * DT
    with np.errstate(invalid="ignore", divide="ignore"):
        bad = ~(np.abs(hist[:, col] / truth_grid[: hist.shape[0], col] - 1.0) <= tol)
    late = t >= after_s
    idx = np.nonzero(bad & late)[0]
    if idx.size == 0:
        return 0.0
    if idx[-1] == hist.shape[0] - 1:
        return float("inf")
    return float(t[idx[-1] + 1] - after_s)


def summarise(errs: list[np.ndarray], fam: dict[str, np.ndarray]) -> dict:
    """errs: per seed, (len(TIMES), P) relative errors -> per family med / p95 per time."""
    E = np.stack(errs)  # seeds x times x P
    out = {}
    for f, cols in fam.items():
        out[f] = {}
        for i, t in enumerate(TIMES):
            v = E[:, i, cols].ravel()
            v = v[np.isfinite(v)] if np.isfinite(v).any() else v
            out[f][f"{t:g}s"] = {
                "median": float(np.median(v)) if v.size and np.isfinite(v).all() else None,
                "p95": float(np.percentile(v, 95)) if v.size and np.isfinite(v).all() else None,
            }
    return out


def crlb_multiple(errs: list[np.ndarray], bounds: list[np.ndarray], fam) -> dict:
    """median(|err| / sigma_crlb) / 0.6745 per family and time."""
    E, B = np.stack(errs), np.stack(bounds)  # seeds x times x P
    out = {}
    for f, cols in fam.items():
        out[f] = {}
        for i, t in enumerate(TIMES):
            r = (E[:, i, cols] / B[:, i, cols]).ravel()
            out[f][f"{t:g}s"] = float(np.median(r) / 0.6745) if np.isfinite(r).all() else None
    return out


def subset_share_within(errs: list[np.ndarray], bounds: list[np.ndarray], fam, size: int = 3, limit: float = 2.0):
    """Share of the ``size``-seed subsets of the run in which every family is within ``limit`` x
    the bound at 10 and 60 s: how often a ``size``-seed verdict holds (None: no more seeds)."""
    if len(errs) <= size:
        return None
    ok = []
    for subset in itertools.combinations(range(len(errs)), size):
        x = crlb_multiple([errs[i] for i in subset], [bounds[i] for i in subset], fam)
        ok.append(all(x[f][t] <= limit for f in fam for t in ("10s", "60s")))
    return float(np.mean(ok))


def score(errs10: np.ndarray, fam, step_delay: float | None = None) -> float:
    """Worst ratio to the issue's targets: m and k 0.5 %, c 2 % at 10 s (worst parameter), and
    the step tracked to 2 % in 1 s (a step never tracked counts as 10 s); < 1 meets them all."""
    acc = max(
        np.nanmax(errs10[fam["m"]]) / 0.005, np.nanmax(errs10[fam["c"]]) / 0.02, np.nanmax(errs10[fam["k"]]) / 0.005
    )
    if step_delay is None:
        return acc
    return max(acc, (step_delay if np.isfinite(step_delay) else 10.0) / 1.0)


# ---------------------------------------------------------------------------------------------
# tuning of the baselines


def tune(which=("rls", "ukf")) -> dict:
    chain, name = TABLE1, "table1"
    fam = families(chain.n)
    js, _ = tracking_params(name, chain.n)
    const = C.simulate(chain, 12.0, seed=TUNE_SEED)
    track = C.simulate(chain, 40.0, seed=TUNE_SEED + 1, schedule=schedule_for(chain, name))
    a, u = const.noisy(40.0, ("accel", "force"), seed=TUNE_SEED)
    at, ut = track.noisy(40.0, ("accel", "force"), seed=TUNE_SEED + 1)
    truth_t = track.truth[read_index(track.t.size)]
    th = C.params_of(chain)
    report = {"rls": [], "ukf": []}
    mems = [0.3, 1.0, 3.0, 10.0, 30.0, float("inf")]
    for w in (0.1, 0.3, 1.0) if "rls" in which else ():
        ests = rls_prefiltered(a, u, read_index(a.shape[0]), window_s=w, memory_s=mems)
        estt = rls_prefiltered(at, ut, read_index(at.shape[0]), window_s=w, memory_s=mems)
        for mem, e, et in zip(mems, ests, estt):
            e10 = errors_at(e, th, 10.0)
            d = settle_delay(et, truth_t, js, STEP_AT)
            report["rls"].append(
                {
                    "window_s": w,
                    "memory_s": mem,
                    "score": score(e10, fam, d),
                    "err10": {f: float(np.max(e10[c])) for f, c in fam.items()},
                    "step_delay_s": d,
                }
            )
            print(
                f"rls window {w:g} s memory {mem:g} s: score {report['rls'][-1]['score']:.2f} "
                f"(m {100 * np.max(e10[fam['m']]):.3f} c {100 * np.max(e10[fam['c']]):.3f} "
                f"k {100 * np.max(e10[fam['k']]):.3f} %, step {d:.2f} s)",
                flush=True,
            )
    sa, su = 0.01 * C.rms(const.a), 0.01 * C.rms(const.u)
    for q in (0.0, 3e-4, 1e-3, 3e-3, 1e-2) if "ukf" in which else ():
        e, _ = baselines.ukf(
            a[:10000], u[:10000], DT, read_index(10000), truth0=th, sigma_a=sa, sigma_u=su, q_param=q, seed=TUNE_SEED
        )
        et, _ = baselines.ukf(
            at[:33000],
            ut[:33000],
            DT,
            read_index(at.shape[0]),
            truth0=th,
            sigma_a=0.01 * C.rms(track.a),
            sigma_u=0.01 * C.rms(track.u),
            q_param=q,
            seed=TUNE_SEED + 1,
        )
        e10 = errors_at(e, th, 10.0)
        d = settle_delay(et, truth_t, js, STEP_AT)
        report["ukf"].append(
            {
                "q_param": q,
                "score": score(e10, fam, d),
                "err10": {f: float(np.max(e10[c])) for f, c in fam.items()},
                "step_delay_s": d,
            }
        )
        print(
            f"ukf q {q:g}: score {report['ukf'][-1]['score']:.2f} (m {100 * np.max(e10[fam['m']]):.3f} "
            f"c {100 * np.max(e10[fam['c']]):.3f} k {100 * np.max(e10[fam['k']]):.3f} %, step {d:.2f} s)",
            flush=True,
        )
    report["chosen"] = {}
    if report["rls"]:
        best_rls = min(report["rls"], key=lambda r: r["score"])
        best_inf = min(
            (r for r in report["rls"] if not np.isfinite(r["memory_s"])),
            key=lambda r: score(
                np.array([r["err10"][f] for f in ("m", "m", "m", "c", "c", "c", "k", "k", "k", "k")]), fam
            ),
        )
        report["chosen"]["rls-inf"] = {"window_s": best_inf["window_s"], "memory_s": best_inf["memory_s"]}
        report["chosen"]["rls-fair"] = {"window_s": best_rls["window_s"], "memory_s": best_rls["memory_s"]}
    if report["ukf"]:
        report["chosen"]["ukf"] = {"q_param": min(report["ukf"], key=lambda r: r["score"])["q_param"]}
    print("chosen:", report["chosen"])
    return report


# ---------------------------------------------------------------------------------------------
# the benchmark


def fmt(x, pct=True, width=6):
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return f"{'-':>{width}}"
    return f"{100 * x:>{width}.3f}" if pct else f"{x:>{width}.2f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=1, help="seeds per system (0 .. seeds-1; the docs: 3)")
    ap.add_argument("--snr", type=str, nargs="+", default=["none", "60", "40", "20"])
    ap.add_argument("--ukf-seconds", type=float, default=10.0, help="UKF record length on constant systems [s]")
    ap.add_argument(
        "--ukf-snr", type=float, nargs="*", default=[40.0], help="SNRs the UKF runs at (accel noise); the docs add 20"
    )
    ap.add_argument("--ukf-track-seeds", type=int, default=1, help="seeds of the UKF tracking runs (33 s each)")
    ap.add_argument("--no-ukf", action="store_true")
    ap.add_argument(
        "--tune",
        nargs="*",
        choices=["rls", "ukf"],
        default=None,
        help="re-tune the baselines (seed 1000) and exit; default both",
    )
    ap.add_argument(
        "--set",
        metavar="OPTION=VALUE",
        action="append",
        default=[],
        help="a ContinuousEstimator option instead of its default, e.g. long_window_s=2 (repeatable)",
    )
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    if args.tune is not None:
        rep = tune(tuple(args.tune) or ("rls", "ukf"))
        if args.json:
            args.json.write_text(json.dumps(rep, indent=1, default=float))
        return
    for item in args.set:
        key, _, value = item.partition("=")
        try:
            OPTIONS[key] = float(value)
        except ValueError:
            ap.error(f"--set {item}: expected OPTION=NUMBER, e.g. long_window_s=2")
    snrs = [None if s == "none" else float(s) for s in args.snr]
    t_start = time.perf_counter()
    results = {
        "config": {
            "fs_hz": FS,
            "duration_s": DURATION,
            "seeds": args.seeds,
            "snr_db": args.snr,
            "band_hz": 20.0,
            "continuous_defaults": algid.estimator.continuous.config_dict(
                algid.estimator.continuous.ContinuousConfig()
            ),
            "continuous_options": dict(OPTIONS),
            "baselines": TUNED,
            "ukf_seconds": args.ukf_seconds,
            "ukf_snr": args.ukf_snr,
            "ukf_decimation": 4,
        },
        "constant": {},
        "tracking": {},
    }
    for sname, chain in systems().items():
        n = chain.n
        fam = families(n)
        th = C.params_of(chain)
        print(f"\n=== {sname} (n = {n}), constant parameters, {args.seeds} seeds ===", flush=True)
        recs = [C.simulate(chain, DURATION, seed=s) for s in range(args.seeds)]
        bounds40 = []
        for rec in recs:
            b = C.crlb(rec, 40.0, TIMES)
            bounds40.append(np.stack([b[t] for t in TIMES]))
        results["constant"][sname] = {
            "crlb_40db_accel": {
                f: {f"{t:g}s": float(np.median(np.stack(bounds40)[:, i, c])) for i, t in enumerate(TIMES)}
                for f, c in fam.items()
            }
        }
        print(
            "CRLB at 40 dB on the accelerations (median over seeds and family) [%]: "
            + "  ".join(
                f"{f}: "
                + "/".join(fmt(results["constant"][sname]["crlb_40db_accel"][f][f"{t:g}s"], width=0) for t in TIMES)
                for f in fam
            )
        )
        for config in ("accel", "accel+force"):
            for snr in snrs:
                key = f"{config}@{'none' if snr is None else f'{snr:g}dB'}"
                per = {}  # estimator -> dict of lists
                t_block = time.perf_counter()
                for s, rec in enumerate(recs):
                    a, u = rec.noisy(snr, noise_channels(config), seed=noise_seed(s, snr, config))
                    hists = {}
                    sig = []
                    h, events, cost = run_continuous(a, u, n, sig)
                    hists["continuous"] = (h, cost)
                    per.setdefault("continuous", {}).setdefault("events", []).append(len(events))
                    if snr is not None:  # |error| / reported sigma at 10 and 60 s (calibration)
                        r10, r60 = int(round(10.0 * FS / GRID)) - 1, int(round(60.0 * FS / GRID)) - 1
                        per["continuous"].setdefault("z", []).append(
                            [np.abs(h[r] - th) / sig[0][r] for r in (r10, r60)]
                        )
                    for k, v in run_rls(a, u, n, {k: TUNED[k] for k in ("rls-inf", "rls-fair")}).items():
                        hists[k] = v
                    run_u = not args.no_ukf and snr is not None and config == "accel" and snr in args.ukf_snr
                    if run_u:
                        est, div, cost = run_ukf(
                            a, u, chain, rec.a, rec.u, snr, config, args.ukf_seconds, TUNED["ukf"]["q_param"], seed=s
                        )
                        hists["ukf"] = (est, cost)
                        per.setdefault("ukf", {}).setdefault("diverged", []).append(bool(div))
                    for k, (hist, cost) in hists.items():
                        d = per.setdefault(k, {})
                        d.setdefault("errs", []).append(np.stack([errors_at(hist, th, t) for t in TIMES]))
                        d.setdefault("t1", []).append({f: first_within(hist, th, c) for f, c in fam.items()})
                        d.setdefault("cost", []).append(cost)
                        if snr is not None and config == "accel":
                            d.setdefault("bounds", []).append(bounds40[s] * 10 ** (-(snr - 40.0) / 20))
                block = {}
                for k, d in per.items():
                    entry = {
                        "summary": summarise(d["errs"], fam),
                        "t_within_1pct_s": {f: float(np.median([x[f] for x in d["t1"]])) for f in fam},
                        "per_seed_errors": [e.tolist() for e in d["errs"]],
                        "us_per_sample": float(1e6 * np.median(d["cost"])),
                    }
                    if "bounds" in d:
                        entry["x_crlb"] = crlb_multiple(d["errs"], d["bounds"], fam)
                        entry["three_seed_share_within_2x"] = subset_share_within(d["errs"], d["bounds"], fam)
                    if "events" in d:
                        entry["events_per_run"] = d["events"]
                    if "z" in d:  # median |error| / sigma; 0.67 for a calibrated, unbiased Gaussian
                        Z = np.array(d["z"])  # seeds x 2 x P
                        entry["median_abs_z"] = {
                            f: {"10s": float(np.median(Z[:, 0, c])), "60s": float(np.median(Z[:, 1, c]))}
                            for f, c in fam.items()
                        }
                    if "diverged" in d:
                        entry["diverged"] = d["diverged"]
                    block[k] = entry
                block["_elapsed_s"] = time.perf_counter() - t_block
                results["constant"][sname][key] = block
                print_block(sname, key, block, fam)
        # tracking
        js, jd = tracking_params(sname, n)
        names = algid.model.chain.parameter_names(n)
        print(
            f"\n--- {sname}: tracking ({names[js]} -20 % at {STEP_AT:g} s, {names[jd]} -10 % over 60 s), "
            f"noise on accelerations and forces ---",
            flush=True,
        )
        trecs = [
            C.simulate(chain, DURATION, seed=100 + s, schedule=schedule_for(chain, sname)) for s in range(args.seeds)
        ]
        results["tracking"][sname] = {"step_param": names[js], "drift_param": names[jd]}
        for snr in snrs:
            key = f"accel+force@{'none' if snr is None else f'{snr:g}dB'}"
            per = {}
            for s, rec in enumerate(trecs):
                a, u = rec.noisy(snr, ("accel", "force"), seed=noise_seed(100 + s, snr, "accel+force"))
                truth_g = rec.truth[read_index(rec.t.size)]
                hists = {}
                h, events, _ = run_continuous(a, u, n)
                hists["continuous"] = h
                for k, v in run_rls(a, u, n, {k: TUNED[k] for k in ("rls-inf", "rls-fair")}).items():
                    hists[k] = v[0]
                if not args.no_ukf and snr == 40.0 and s < args.ukf_track_seeds:
                    est, div, _ = run_ukf(
                        a,
                        u,
                        chain,
                        rec.a,
                        rec.u,
                        snr,
                        "accel+force",
                        STEP_AT + 3.0,
                        TUNED["ukf"]["q_param"],
                        seed=100 + s,
                    )
                    hists["ukf"] = est
                for k, hist in hists.items():
                    d = per.setdefault(k, {"step_delay": [], "drift_max": [], "drift_within": []})
                    d["step_delay"].append(settle_delay(hist, truth_g, js, STEP_AT))
                    rows = np.arange(hist.shape[0])
                    t = (rows + 1) * GRID * DT
                    win = (t >= 10.0) & (t <= min(DURATION, t[-1]))
                    rel = np.abs(hist[win, jd] / truth_g[: hist.shape[0]][win, jd] - 1.0)
                    d["drift_max"].append(float(np.nanmax(rel)) if rel.size else None)
                    d["drift_within"].append(float(np.mean(rel <= 0.02)) if rel.size else None)
                    if k == "continuous":
                        d.setdefault("false_alarms", []).append(sum(1 for e in events if e.param not in (js, jd)))
                        d.setdefault("step_events", []).append(
                            [round(e.time_s, 3) for e in events if e.param == js and e.time_s >= STEP_AT][:1]
                        )
                        d.setdefault("drift_events", []).append(sum(1 for e in events if e.param == jd))
            results["tracking"][sname][key] = per
            print_tracking(key, per)
    results["runtime_s"] = time.perf_counter() - t_start
    print(f"\nruntime {results['runtime_s']:.0f} s")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(results, indent=1, default=_json_default))
        print(f"wrote {args.json}")


def _json_default(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(type(x))


def print_block(sname, key, block, fam):
    print(
        f"\n{sname} | noise {key} | median / p95 relative error [%] at 1, 10, 60 s; t1%: first time "
        f"within 1 % [s]; xCRLB at 1/10/60 s",
        flush=True,
    )
    for k, e in block.items():
        if k.startswith("_"):
            continue
        line = f"  {k:<10}"
        for f in fam:
            s = e["summary"][f]
            line += f" | {f}: " + " ".join(f"{fmt(s[f'{t:g}s']['median'])}/{fmt(s[f'{t:g}s']['p95'])}" for t in TIMES)
            line += f" t1% {e['t_within_1pct_s'][f]:5.2f}"
        if "x_crlb" in e:
            line += " | xCRLB " + " ".join(
                f"{f}:" + "/".join(fmt(e["x_crlb"][f][f"{t:g}s"], pct=False, width=0) for t in TIMES) for f in fam
            )
        if e.get("three_seed_share_within_2x") is not None:
            line += f" | 3-seed subsets all within 2x: {100 * e['three_seed_share_within_2x']:.0f} %"
        if "events_per_run" in e:
            line += f" | events {e['events_per_run']}"
        if "median_abs_z" in e:
            line += " | med|err|/sigma 10/60 s " + " ".join(
                f"{f}:{e['median_abs_z'][f]['10s']:.2f}/{e['median_abs_z'][f]['60s']:.2f}" for f in fam
            )
        if e.get("diverged") and any(e["diverged"]):
            line += f" | diverged {e['diverged']}"
        print(line)


def print_tracking(key, per):
    print(f"  noise {key}")
    for k, d in per.items():
        line = (
            f"    {k:<10} step within 2 % after {', '.join(f'{x:.2f}' for x in d['step_delay'])} s | drift: worst "
            f"{', '.join(fmt(x, width=0) for x in d['drift_max'])} %, within 2 % "
            f"{', '.join(f'{100 * x:.0f}' for x in d['drift_within'])} % of 10-60 s"
        )
        if "false_alarms" in d:
            line += (
                f" | step event at {d['step_events']} | drift events {d['drift_events']} | false alarms "
                f"{d['false_alarms']}"
            )
        print(line, flush=True)


if __name__ == "__main__":
    main()
