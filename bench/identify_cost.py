"""Wall time of :func:`algid.identify` and :func:`algid.diagnose` in a warm process, and of the
``algid identify`` / ``algid diagnose`` commands end to end, against the record's length and
its forcing spectrum.

Records: Table 1 (3 DOF) at 1 kHz, 40 dB white noise on forces and accelerations, simulated by
:func:`algid.simulator.simulate` under five forcings on every DOF: ``multisine`` (7 lines,
1.3-31 Hz, as bench/identify.py), ``band`` (white noise low-passed at 20 Hz), ``white`` (white up
to the Nyquist rate, a common shaker drive), ``chirp`` (0.5-40 Hz, 5 s sweeps) and ``hits``
(2 ms half-sine pulses, one every 0.5 s at a random DOF and height); durations 10, 20 and 60 s.

Figures per record (median of ``--reps`` runs after one warm-up, in this process):

* ``identify_s``: ``algid.identify(rec)``; ``one_pass_s``: one pass of the estimator its plan
  ran (``ContinuousEstimator.run`` with the plan's settings) over the same record, the
  baseline measured in the same run: ``identify_s / one_pass_s`` is what the rest costs;
* ``diagnose_s``: ``algid.diagnose(rec)`` on the 20 s records;
* ``identify_per_s``: seconds per second of record (linear cost: the same at 10, 20 and 60 s).

The commands (``--cli``, on by default): ``algid identify FILE --quiet --json OUT`` and
``algid diagnose FILE --quiet --json OUT`` on the 20 s multisine record written as CSV, each
in a fresh process (imports included), median of ``--reps``.

``--baseline DIR`` times the same records again through the algid installed in ``DIR`` (a
folder holding an ``algid`` package, e.g. an earlier build), in a subprocess, side by side.

    python bench/identify_cost.py                      # about 2 minutes
    python bench/identify_cost.py --json bench/results/identify_cost.json
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import algid
from algid.diagnosis import diagnose
from algid.model.chain import TABLE1
from algid.recording import Recording, save_recording
from algid.simulator import simulate

FS = 1000.0
SNR_DB = 40.0
FORCINGS = ("multisine", "band", "white", "chirp", "hits")
DURATIONS = (10.0, 20.0, 60.0)


def forcing(kind: str, duration_s: float, n: int, seed: int) -> np.ndarray:
    """Force samples (T, n) [N] of ``kind`` (module docstring), about 10 N RMS."""
    from scipy.signal import butter, chirp, sosfiltfilt

    rng = np.random.default_rng(seed)
    T = int(round(duration_s * FS))
    t = np.arange(T) / FS
    if kind == "multisine":
        f = np.array([1.3, 2.9, 4.4, 7.1, 11.3, 17.9, 31.0])
        phase = rng.uniform(0, 2 * np.pi, (n, f.size))
        return 4.0 * np.sin(2 * np.pi * f * t[:, None, None] + phase).sum(axis=-1) + 2.0
    if kind in ("band", "white"):
        w = rng.standard_normal((T, n))
        if kind == "band":
            w = sosfiltfilt(butter(4, 20.0, fs=FS, output="sos"), w, axis=0)
        return 10.0 * w / w.std(axis=0)
    if kind == "chirp":
        sweep = chirp(t % 5.0, 0.5, 5.0, 40.0)
        return 10.0 * np.stack([np.roll(sweep, 1000 * i) for i in range(n)], axis=1)
    u = np.zeros((T, n))
    pulse = np.sin(np.pi * np.arange(int(0.002 * FS) + 1) / (0.002 * FS))
    for start in range(int(0.25 * FS), T - pulse.size, int(0.5 * FS)):
        u[start : start + pulse.size, rng.integers(n)] += rng.uniform(50.0, 150.0) * pulse
    return u


def record(kind: str, duration_s: float, seed: int = 0) -> Recording:
    r = simulate(TABLE1, forcing(kind, duration_s, TABLE1.n, seed), duration_s, FS, noise_db=SNR_DB,
                 noise_on=("accel", "force"), seed=seed)  # fmt: skip
    return Recording(t=r.t, u=r.u, a=r.a)


def median_time(fn, reps: int) -> float:
    fn()  # warm-up
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def one_pass(rec: Recording, plan) -> None:
    """One pass of the continuous estimator with the plan's settings (the single window: one
    ChainEstimator pass)."""
    from algid.identification.runner import run_plan

    run_plan(rec.a, rec.u, float(rec.dt), "fixed", plan, history=False)


def warm(reps: int, durations, forcings) -> list[dict]:
    rows = []
    for kind in forcings:
        for duration in durations:
            rec = record(kind, duration)
            res = algid.identify(rec)
            row = {
                "forcing": kind,
                "duration_s": duration,
                "estimator": res.plan.estimator,
                "method": res.plan.method,
                "window_s": res.plan.window_s,
                "valid": bool(res.valid),
                "identify_s": median_time(lambda rec=rec: algid.identify(rec), reps),
                "one_pass_s": median_time(lambda rec=rec, p=res.plan: one_pass(rec, p), reps),
            }
            row["identify_per_s"] = row["identify_s"] / duration
            if duration == 20.0:
                row["diagnose_s"] = median_time(lambda rec=rec: diagnose(rec), max(1, reps // 2))
            rows.append(row)
            print(
                f"{kind:9s} {duration:4.0f} s  identify {row['identify_s']:6.3f} s  one pass {row['one_pass_s']:6.3f} s"
                f"  ({row['identify_s'] / row['one_pass_s']:.2f}x)"
                + (f"  diagnose {row['diagnose_s']:6.3f} s" if "diagnose_s" in row else ""),
                flush=True,
            )
    return rows


def commands(reps: int, folder: Path, python: str = sys.executable, env: dict | None = None) -> dict:
    """Wall time [s] of each command in a fresh process, median of ``reps``."""
    path = folder / "table1_multisine_20s.csv"
    if not path.exists():
        save_recording(path, record("multisine", 20.0))
    out = {}
    for command in ("identify", "diagnose"):
        cmd = [python, "-m", "algid.cli", command, str(path), "--quiet", "--json", str(folder / f"{command}.json")]
        times = []
        for _ in range(reps):
            t0 = time.perf_counter()
            proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
            times.append(time.perf_counter() - t0)
            if proc.returncode not in (0, 3):
                raise RuntimeError(f"{' '.join(cmd)}: {proc.stderr[-2000:]}")
        out[command] = statistics.median(times)
        print(f"algid {command:8s} end to end {out[command]:.3f} s", flush=True)
    return out


_BASELINE_SCRIPT = """
import json, statistics, sys, time
import identify_cost as C
import algid
rows = []
for kind, duration in {cases!r}:
    rec = C.record(kind, duration)
    rows.append({{"forcing": kind, "duration_s": duration,
                  "identify_s": C.median_time(lambda: algid.identify(rec), {reps})}})
print(json.dumps(rows))
"""


def baseline(folder: Path, cases: list, reps: int, work: Path) -> dict:
    """The warm identify times and the commands' of the algid in ``folder``."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(folder), str(Path(__file__).parent)])}
    script = _BASELINE_SCRIPT.format(cases=cases, reps=reps)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env)
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr[-3000:])
    rows = json.loads(proc.stdout.strip().splitlines()[-1])
    for r in rows:
        print(f"baseline {r['forcing']:9s} {r['duration_s']:4.0f} s  identify {r['identify_s']:6.3f} s", flush=True)
    return {"warm": rows, "commands": commands(reps, work, env=env)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reps", type=int, default=3, metavar="N", help="timed runs per figure (default: 3)")
    ap.add_argument("--durations", type=float, nargs="+", default=list(DURATIONS), metavar="S",
                    help="record lengths [s] (default: 10 20 60)")  # fmt: skip
    ap.add_argument("--forcings", nargs="+", default=list(FORCINGS), choices=FORCINGS, metavar="KIND",
                    help=f"forcings (default: all of {', '.join(FORCINGS)})")  # fmt: skip
    ap.add_argument("--no-cli", action="store_true", help="leave out the commands' end-to-end times")
    ap.add_argument("--baseline", type=Path, metavar="DIR", help="also time the algid package found in DIR")
    ap.add_argument("--baseline-forcings", nargs="+", default=["multisine"], choices=FORCINGS, metavar="KIND",
                    help="the forcings timed on the baseline (default: multisine; an earlier build may take "
                    "minutes per white-noise record)")  # fmt: skip
    ap.add_argument("--json", type=Path, metavar="PATH", help="write the figures there")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    out = {"fs_hz": FS, "snr_db": SNR_DB, "reps": args.reps, "isa": algid.ISA}
    out["warm"] = warm(args.reps, args.durations, args.forcings)
    with tempfile.TemporaryDirectory() as tmp:
        if not args.no_cli:
            out["commands"] = commands(args.reps, Path(tmp))
        if args.baseline is not None:
            cases = [(r["forcing"], r["duration_s"]) for r in out["warm"] if r["forcing"] in args.baseline_forcings]
            out["baseline"] = {"path": str(args.baseline), **baseline(args.baseline, cases, args.reps, Path(tmp))}
    out["wall_s"] = time.perf_counter() - t0
    if args.json:
        args.json.write_text(json.dumps(out, indent=1) + "\n")
    print(f"{out['wall_s']:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
