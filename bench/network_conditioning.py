"""Conditioning of the algebraic system of a network DOF against its number of unknowns
M = 2 + deg(i) (issue 39): for every DOF of the example networks (half-car, torsion frame,
3x3 lattice; :data:`algid.simulator.scenarios.NETWORKS`), noise-free at 1 kHz under the tests'
multisine, the 2-norm condition number of the time-scaled system after column equilibration
and the relative error of the instantaneous (eq. 5) and eq. 7 estimates of the numpy reference
(:mod:`algid.estimator.network_reference`) at a few instants, with the square system (rows
q = 0..M-1) and with least squares on extra rows; beside them the first ``--stack-rows`` rows
(default 4, the chain's q = 0..3) of every sample in [t/2, t] stacked into one least-squares
problem (a design candidate: what a running M x M normal matrix would solve); then the median
over DOFs of equal M. It decides the
C++ design (Cramer or least squares, how many rows).

    python bench/network_conditioning.py                  # prints the table (about 10 s)
    python bench/network_conditioning.py --json bench/results/network_conditioning.json
    python bench/network_conditioning.py --points 12      # the 12-point quadrature rule
    python bench/network_conditioning.py --snr 40 --seconds 5 --times 1 5 --extra 0  # 40 dB noise
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from algid.estimator import network_reference as nr
from algid.simulator.exact import multisine, simulate_chain
from algid.simulator.scenarios import NETWORKS, network_model


def record(model, args) -> tuple[np.ndarray, np.ndarray]:
    """Accelerations and forces (T, n) under the tests' multisine, with white noise of
    ``args.snr`` dB (RMS ratio per channel) on both if given."""
    _, a, u, _ = simulate_chain(model, multisine(model.n), args.seconds)
    if args.snr is not None:
        rng = np.random.default_rng(args.seed)
        ratio = 10.0 ** (-args.snr / 20.0)
        a = a + ratio * np.sqrt(np.mean(a**2, axis=0)) * rng.standard_normal(a.shape)
        u = u + ratio * np.sqrt(np.mean(u**2, axis=0)) * rng.standard_normal(u.shape)
    return a, u


def dof_rows(name: str, args, times: list[float]) -> list[dict]:
    """One row per DOF and row count: M, condition number and errors at ``times`` [s]."""
    model = network_model(name)
    net, truth, names = model.network, model.packed(), model.network.parameter_names()
    a, u = record(model, args)
    points, extra, stack = args.points, args.extra, args.stack_rows
    top = 2 + max(len(net.columns(i)) for i in range(1, net.n + 1)) + max(extra)
    Gy, Gu, tau = nr.moments_of(a, u, 1e-3, top, points)
    at = [int(round(t * 1000)) for t in times]
    out = []
    for i in range(1, net.n + 1):
        cols = net.columns(i)
        M = 2 + len(cols)
        exact = truth[[names.index(p) for p in [f"m{i}", f"c{i}"] + [f"k{s}" for s, _ in cols]]]
        for e in extra:
            S, b = nr.dof_system(net, i, Gy, Gu[i - 1], tau, M + e)
            theta, logw = nr.solve(S, b, tau)
            fused = nr.ratio(theta, np.where(np.arange(tau.size) + points - 1 >= 16, logw, -np.inf), 1e-3)
            cond = nr.condition(S[at])
            err = np.max(np.abs(theta[at] / exact - 1), axis=1)
            err7 = np.max(np.abs(fused[at] / exact - 1), axis=1)
            st = [stacked(S[:, :stack], b[:, :stack], tau, k) for k in at]
            row = {"network": name, "dof": i, "M": M, "rows": M + e, "condition": cond.tolist()}
            row |= {"error_inst": err.tolist(), "error_eq7": err7.tolist()}
            row |= {"condition_stacked": [c for c, _ in st]}
            row |= {"error_stacked": [float(np.max(np.abs(th / exact - 1))) for _, th in st]}
            out.append(row)
    return out


def stacked(S: np.ndarray, b: np.ndarray, tau: np.ndarray, k: int) -> tuple[float, np.ndarray]:
    """Condition number and solution of the rows of samples ``k//2 .. k`` stacked into one
    least-squares problem in the units of theta (columns equilibrated)."""
    ks = np.arange(k // 2, k + 1)
    M = S.shape[2]
    scale = tau[ks, None] ** -np.minimum(np.arange(M), 2)[None, :]  # theta = phi * scale
    A = (S[ks] / scale[:, None, :]).reshape(-1, M)
    col = np.linalg.norm(A, axis=0)
    theta = np.linalg.lstsq(A / col, b[ks].reshape(-1), rcond=None)[0] / col
    return float(np.linalg.cond(A / col)), theta


def summary(rows: list[dict], times: list[float]) -> None:
    """Median over the DOFs of equal (M, rows) of each figure, one line each."""
    keys = ("condition", "error_inst", "error_eq7", "condition_stacked", "error_stacked")
    heads = ("cond", "err5", "err7", "cond_st", "err_st")
    for k, t in enumerate(times):
        print(f"t = {t:g} s: median over the DOFs of equal M and rows")
        print(f"{'M':>3} {'rows':>4} {'DOFs':>4} " + " ".join(f"{h:>9}" for h in heads))
        for M, R in sorted({(r["M"], r["rows"]) for r in rows}):
            sel = [r for r in rows if r["M"] == M and r["rows"] == R]
            cells = [np.median([r[key][k] for r in sel]) for key in keys]
            print(f"{M:3d} {R:4d} {len(sel):4d} " + " ".join(f"{v:9.1e}" for v in cells))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=1.0, help="record length [s]")
    ap.add_argument("--times", type=float, nargs="+", default=[0.05, 0.1, 0.2, 1.0], help="instants [s]")
    ap.add_argument("--points", type=int, default=8, help="quadrature points (the core's default 8)")
    ap.add_argument("--extra", type=int, nargs="+", default=[0, 2, 4], help="rows beyond M (0: square)")
    ap.add_argument("--snr", type=float, help="white noise on accelerations and forces [dB] (default none)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the noise")
    ap.add_argument("--stack-rows", type=int, default=4, help="rows per sample in the stacked problem")
    ap.add_argument("--json", type=Path, help="write the rows and settings here")
    args = ap.parse_args()
    times = [t for t in args.times if t <= args.seconds]
    rows = [r for name in NETWORKS for r in dof_rows(name, args, times)]
    summary(rows, times)
    if args.json is not None:
        settings = {"seconds": args.seconds, "times": times, "points": args.points, "stack_rows": args.stack_rows}
        settings |= {"fs_hz": 1000.0, "snr_db": args.snr, "seed": args.seed}
        args.json.write_text(json.dumps({"settings": settings, "rows": rows}, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
