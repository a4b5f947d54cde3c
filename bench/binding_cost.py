"""Per-sample cost of the estimators as Python calls them: ``ChainEstimator.run`` and
``ContinuousEstimator.run`` (the C++ loops with the GIL released) at n = 3, 5 and 32, through
the installed algid and, with ``--baseline DIR``, through the algid package in DIR (an
earlier build, say), the two timed in alternating rounds so that both see the same machine.

Signals: a random chain of n DOF (``Chain.random(n, default_rng(n))``, Table 1 for n = 3)
under a multisine on every DOF, 1 kHz, 40 dB on forces and accelerations; 20 s for n <= 5,
5 s for n = 32. Per estimator and n: median, p99 and worst over the rounds of the wall time
per sample [us], and with a baseline the ratio of the medians (this build / baseline).

    python bench/binding_cost.py                                   # about a minute
    python bench/binding_cost.py --baseline /path/to/site-packages --json bench/results/binding_cost.json
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

SIZES = (3, 5, 32)
KINDS = ("ChainEstimator", "ContinuousEstimator")

#: One round in a fresh interpreter: every (kind, n) once, per-sample wall time [us] as JSON.
ROUND = """
import json, sys, time
import numpy as np
import algid
from algid.model.chain import TABLE1, Chain
from algid.simulator import simulate
out = {}
for n in %(sizes)r:
    chain = TABLE1 if n == 3 else Chain.random(n, np.random.default_rng(n))
    duration = 20.0 if n <= 5 else 5.0
    t = np.arange(int(duration * 1000)) / 1000.0
    f = np.array([1.3, 2.9, 4.4, 7.1, 11.3, 17.9, 31.0])
    phase = np.random.default_rng(n).uniform(0, 2 * np.pi, (n, f.size))
    u = 4.0 * np.sin(2 * np.pi * f * t[:, None, None] + phase).sum(axis=-1)
    r = simulate(chain, u, duration, 1000.0, noise_db=40.0, noise_on=("accel", "force"), seed=n)
    a, u = np.ascontiguousarray(r.a), np.ascontiguousarray(r.u)
    for kind in %(kinds)r:
        est = getattr(algid, kind)(n, 1e-3)
        est.run(a[:2000], u[:2000])  # warm-up
        est = getattr(algid, kind)(n, 1e-3)
        t0 = time.perf_counter()
        est.run(a, u)
        out[f"{kind}/{n}"] = (time.perf_counter() - t0) / a.shape[0] * 1e6
print(json.dumps(out))
"""


def one_round(pythonpath: str | None) -> dict[str, float]:
    env = dict(os.environ)
    if pythonpath is not None:
        env["PYTHONPATH"] = pythonpath
    code = ROUND % {"sizes": SIZES, "kinds": KINDS}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr[-3000:])
    return json.loads(proc.stdout.strip().splitlines()[-1])


def stats(values: list[float]) -> dict[str, float]:
    v = np.sort(np.asarray(values))
    return {"median_us": float(np.median(v)), "p99_us": float(np.quantile(v, 0.99)), "worst_us": float(v[-1])}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=5, metavar="N", help="rounds per build (default: 5)")
    ap.add_argument("--baseline", type=Path, metavar="DIR", help="a folder holding the algid package to compare with")
    ap.add_argument("--json", type=Path, metavar="PATH", help="write the figures there")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    builds = {"this": None} | ({"baseline": str(args.baseline)} if args.baseline else {})
    samples: dict[str, dict[str, list[float]]] = {b: {} for b in builds}
    for r in range(args.rounds):
        for build, path in builds.items():  # alternating: both builds see the same machine
            for key, us in one_round(path).items():
                samples[build].setdefault(key, []).append(us)
        print(f"round {r + 1}/{args.rounds} done", file=sys.stderr, flush=True)
    out = {"rounds": args.rounds, "baseline": builds.get("baseline"), "figures": {}}
    print(
        f"{'estimator':22s} {'n':>3s} {'median':>9s} {'p99':>9s} {'worst':>9s}"
        + ("   baseline   ratio" if args.baseline else "")
    )
    for key in samples["this"]:
        kind, n = key.split("/")
        row = {"this": stats(samples["this"][key])}
        line = f"{kind:22s} {n:>3s} " + " ".join(f"{row['this'][k]:8.3f}u" for k in ("median_us", "p99_us", "worst_us"))
        if args.baseline:
            row["baseline"] = stats(samples["baseline"][key])
            row["ratio"] = row["this"]["median_us"] / row["baseline"]["median_us"]
            line += f"   {row['baseline']['median_us']:8.3f}u  {row['ratio']:.3f}"
        out["figures"][key] = row
        print(line)
    out["wall_s"] = time.perf_counter() - t0
    if args.json:
        args.json.write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
