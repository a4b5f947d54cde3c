"""Issue 2 figures: accuracy and convergence time of the on-line estimator, noise-free, 1 kHz.

Scenarios: Table 1 under an open-loop multisine-plus-offset force and under a step force
from rest (the estimator starts at t0 = 0 with the chain at rest; the force steps at
t0 + 12 ms — at t0 itself a constant force gives B = 0 and only parameter ratios are
identifiable), both as an ideal jump sampled at its midpoint and band-limited (Gaussian
edge, 5 ms rise: an ideal jump between samples leaves a bias floor of about 1e-3, the
interpolation error of any sampled quadrature across a discontinuity); random chains with n = 1, 2, 5, 10; a free right end. For each: the maximum
relative error over all identified parameters (interior springs fused) at t0 + 0.02, 0.05,
0.1, 0.5 s, and the first time after which it stays below 1 % and below 1e-6. Also the
quadrature comparison of the numpy reference (P = 2 trapezoid-like ... 8).

The default run is the published one (docs/theory.md, "Accuracy"); it writes
bench/results/accuracy.json (``--json /tmp/accuracy.json`` to keep that file):

    python bench/accuracy.py [--json bench/results/accuracy.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.special import erf

HERE = Path(__file__).resolve().parent
import algid  # noqa: E402
from algid.estimator import reference  # noqa: E402
from algid.model.chain import TABLE1, Chain  # noqa: E402
from algid.simulator.exact import multisine, relative_errors, simulate_chain  # noqa: E402

FS = 1000.0
CHECK_TIMES = (0.02, 0.05, 0.1, 0.5)


def step_force(n: int, at_s: float = 0.012, edge_s: float = 0.0, seed: int = 0):
    """Force steps from 0 to a random level per DOF [N] at ``at_s`` [s].

    ``edge_s = 0``: an ideal jump (sampled at its midpoint). ``edge_s > 0``: a band-limited
    step, level * Phi((t - at_s) / edge_s) (Gaussian edge, 10-90 % rise 2.56 edge_s), as a
    shaker or actuator with finite bandwidth produces; at t0 = 0 it is 6 edges away (rest).
    """
    level = np.random.default_rng(seed).uniform(-10, 10, n)

    def force(t):
        if edge_s > 0:
            return level * 0.5 * (1.0 + erf((t - at_s) / (np.sqrt(2.0) * edge_s)))
        return level * float(t >= at_s)

    return force, ([at_s] if edge_s == 0 else [])


def error_history(chain: Chain, out: dict) -> np.ndarray:
    """Max relative error per row (inf where not all DOF are valid)."""
    T = out["mass"].shape[0]
    err = np.full(T, np.inf)
    for k in range(T):
        if out["valid"][k].all():
            err[k] = relative_errors(chain, out["mass"][k], out["damping"][k], out["stiffness"][k]).max()
    return err


def first_time_below(err: np.ndarray, threshold: float, t_window: np.ndarray) -> float | None:
    bad = np.nonzero(~(err < threshold))[0]
    if bad.size == 0:
        return float(t_window[0])
    if bad[-1] + 1 >= err.size:
        return None
    return float(t_window[bad[-1] + 1])


def scenario(name: str, chain: Chain, force, breaks=(), duration_s: float = 0.5) -> dict:
    est = algid.ChainEstimator(chain.n, 1 / FS, boundary=chain.boundary)
    d = est.delay_samples
    t, a, u, _ = simulate_chain(chain, force, duration_s + d / FS, FS, breaks=breaks)
    t_start = time.perf_counter()
    out = est.run(a, u)
    elapsed = time.perf_counter() - t_start
    err = error_history(chain, out)
    t_window = t - d / FS  # the window end each row describes
    row = {
        "scenario": name,
        "n": chain.n,
        "boundary": chain.boundary,
        "parameters": int(np.isfinite(chain.identifiable()).sum() - (chain.boundary == "free")),
    }
    for tc in CHECK_TIMES:
        k = int(round(tc * FS)) + d
        row[f"max_rel_error_at_{tc:g}s"] = float(err[k]) if k < err.size else None
    row["time_to_1pct_s"] = first_time_below(err, 1e-2, t_window)
    row["time_to_1e-6_s"] = first_time_below(err, 1e-6, t_window)
    row["run_seconds"] = elapsed
    return row


def quadrature_comparison() -> list[dict]:
    t, a, u, _ = simulate_chain(TABLE1, multisine(3), 0.5)
    rows = []
    for points in (2, 4, 6, 8):
        r = reference.estimate(a, u, 1 / FS, points=points)
        th = r["theta_ratio"]
        err = np.full(t.size, np.inf)
        for k in range(t.size):
            m, c = th[k, :, 0], th[k, :, 1]
            k_fused = np.array(
                [th[k, 0, 2], 0.5 * (th[k, 0, 3] + th[k, 1, 2]), 0.5 * (th[k, 1, 3] + th[k, 2, 2]), th[k, 2, 3]]
            )
            e = relative_errors(TABLE1, m, c, k_fused)
            if np.all(np.isfinite(e)):
                err[k] = e.max()
        rows.append(
            {
                "points": points,
                "order": points,
                "delay_samples": max(points - 2, 0),
                "time_to_1pct_s": first_time_below(err, 1e-2, t),
                "time_to_1e-6_s": first_time_below(err, 1e-6, t),
                "max_rel_error_at_0.1s": float(err[100]),
                "max_rel_error_at_0.5s": float(err[-1]),
            }
        )
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", type=Path, default=HERE / "results" / "accuracy.json")
    p.add_argument("--seed", type=int, default=1, help="seed of the random chains and phases")
    args = p.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    rows = []
    rows.append(scenario("table1_multisine", TABLE1, multisine(3, args.seed)))
    f, br = step_force(3, seed=args.seed)
    rows.append(scenario("table1_step_ideal", TABLE1, f, br))
    f, br = step_force(3, edge_s=0.002, seed=args.seed)
    rows.append(scenario("table1_step_bandlimited", TABLE1, f, br))
    for n in (1, 2, 5, 10):
        chain = Chain.random(n, rng)
        rows.append(scenario(f"random_n{n}_multisine", chain, multisine(n, args.seed + n)))
        f, br = step_force(n, edge_s=0.002, seed=args.seed + n)
        rows.append(scenario(f"random_n{n}_step_bandlimited", chain, f, br))
    for n in (1, 3, 5):
        chain = Chain.random(n, rng, boundary="free")
        rows.append(scenario(f"free_end_n{n}_multisine", chain, multisine(n, args.seed + 10 * n)))
    quad = quadrature_comparison()

    print(
        f"{'scenario':28s} {'n':>3s} {'err@0.02s':>10s} {'err@0.05s':>10s} {'err@0.1s':>10s} {'err@0.5s':>10s} "
        f"{'t(1%) s':>8s} {'t(1e-6) s':>9s}"
    )
    fmt = lambda v: f"{v:10.2e}" if v is not None else f"{'-':>10s}"  # noqa: E731
    ft = lambda v: f"{v:8.3f}" if v is not None else f"{'never':>8s}"  # noqa: E731
    for r in rows:
        print(
            f"{r['scenario']:28s} {r['n']:3d} "
            + " ".join(fmt(r[f"max_rel_error_at_{tc:g}s"]) for tc in CHECK_TIMES)
            + f" {ft(r['time_to_1pct_s'])} {ft(r['time_to_1e-6_s']):>9s}"
        )
    print("\nquadrature (numpy reference, Table 1 multisine):")
    for q in quad:
        print(
            f"  P = {q['points']}: time to 1 % {ft(q['time_to_1pct_s'])} s, to 1e-6 {ft(q['time_to_1e-6_s'])} s, "
            f"error at 0.1 s {q['max_rel_error_at_0.1s']:.2e}"
        )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"fs_hz": FS, "seed": args.seed, "scenarios": rows, "quadrature": quad}, indent=2))
    print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
