"""Bit-identity of the continuous estimator across builds: the same records through the
algid package in DIR (an earlier build, ``--baseline DIR``) and the algid importable here,
and the largest absolute difference of every output history of ``ContinuousEstimator.run()``.

Records (8 s at 1 kHz, multisine forcing, a chain of n = 1, 3, 10 DOF simulated exactly by a
zero-order-hold discretisation): 40 dB noise; noise and a 20 % step of k_1 at 5 s; noise, a
stuck acceleration for 0.3 s and a non-finite sample. Each through the weak-form and the
algebraic windows. A NaN must sit where the other build has a NaN (counted otherwise).

    python bench/continuous_identity.py --baseline DIR   # about 1 minute here
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.linalg import expm

DT = 1e-3
SAMPLES = 8000


def chain_matrices(m, c, k):
    """M, C, K of eq. 1 with walls at both ends (k has n + 1 springs)."""
    K = np.diag(k[:-1] + k[1:]) - np.diag(k[1:-1], 1) - np.diag(k[1:-1], -1)
    return np.diag(m), np.diag(c), K


def simulate(m, c, k, u, k_after=None, step_at=None):
    """Accelerations (T, n) of the chain under forces u (T, n), zero-order hold; the springs
    switch to ``k_after`` at sample ``step_at``."""
    n = m.size
    x = np.zeros(2 * n)
    a = np.zeros_like(u)
    systems = {}
    for t in range(u.shape[0]):
        springs = k_after if step_at is not None and t >= step_at else k
        key = id(springs)
        if key not in systems:
            M, C, K = chain_matrices(m, c, springs)
            Minv = np.linalg.inv(M)
            A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])
            B = np.vstack([np.zeros((n, n)), Minv])
            big = expm(np.block([[A, B], [np.zeros((n, 3 * n))]]) * DT)
            systems[key] = (big[: 2 * n, : 2 * n], big[: 2 * n, 2 * n :], Minv, C, K)
        Ad, Bd, Minv, C, K = systems[key]
        a[t] = Minv @ (u[t] - C @ x[n:] - K @ x[:n])
        x = Ad @ x + Bd @ u[t]
    return a


def record(n: int, scenario: str):
    """Accelerations and forces (T, n) of one record."""
    rng = np.random.default_rng(100 * n + len(scenario))
    m, c, k = rng.uniform(1, 3, n), rng.uniform(2, 8, n), rng.uniform(500, 1500, n + 1)
    t = np.arange(SAMPLES) * DT
    f = np.array([1.3, 3.7, 7.1, 11.3, 17.9, 23.5, 31.0])
    u = 4 * np.sin(2 * np.pi * f[None, None, :] * t[:, None, None] + rng.uniform(0, 2 * np.pi, (n, f.size))).sum(-1)
    k_after = k * np.r_[0.8, np.ones(n)] if scenario == "step" else None
    a = simulate(m, c, k, u, k_after, SAMPLES * 5 // 8 if scenario == "step" else None)
    a += 0.01 * a.std(axis=0) * rng.standard_normal(a.shape)
    u += 0.01 * u.std(axis=0) * rng.standard_normal(u.shape)
    if scenario == "dropout":
        a[3000:3300, 0] = a[3000, 0]
        a[4500, n - 1] = np.nan
    return a, u


def dump(path: str) -> None:
    """Every output history of every case into the npz file at ``path``."""
    import algid

    out = {}
    for n in (1, 3, 10):
        for scenario in ("noise", "step", "dropout"):
            a, u = record(n, scenario)
            for method in ("weak_form", "algebraic"):
                result = algid.ContinuousEstimator(n, DT, method=method).run(a, u)
                for key, value in result.items():
                    value = np.asarray(value)
                    if value.dtype.kind in "biuf":  # the histories, not the parameter names
                        out[f"{method}/n{n}/{scenario}/{key}"] = value.astype(float)
    np.savez(path, **out)


def differences(old: dict, new: dict) -> list[tuple[str, float, int]]:
    """(name, max |new - old| over the finite pairs, NaN or shape mismatches) per history."""
    rows = []
    for name in sorted(set(old) | set(new)):
        if name not in old or name not in new or old[name].shape != new[name].shape:
            rows.append((name, np.inf, -1))
            continue
        o, w = old[name], new[name]
        both = np.isfinite(o) & np.isfinite(w)
        mismatch = int((np.isnan(o) != np.isnan(w)).sum() + (np.isinf(o) & (o != w)).sum())
        rows.append((name, float(np.abs(o[both] - w[both]).max(initial=0.0)), mismatch))
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--baseline", help="folder holding the earlier algid package")
    p.add_argument("--dump", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.dump:
        dump(args.dump)
        return 0
    if not args.baseline:
        p.error("--baseline DIR is required")
    with tempfile.TemporaryDirectory() as tmp:
        files = {}
        for label, path in (("old", args.baseline), ("new", None)):
            env = dict(os.environ)
            if path:
                env["PYTHONPATH"] = os.pathsep.join([path] + [x for x in [env.get("PYTHONPATH")] if x])
            files[label] = os.path.join(tmp, f"{label}.npz")
            subprocess.run([sys.executable, __file__, "--dump", files[label]], env=env, check=True)
        old, new = (dict(np.load(files[k])) for k in ("old", "new"))
    rows = differences(old, new)
    worst = max(r[1] for r in rows)
    bad = sum(r[2] != 0 for r in rows)
    for name, diff, mismatch in rows:
        if diff != 0 or mismatch != 0:
            print(f"{name}: max |diff| {diff:.3e}, NaN mismatches {mismatch}")
    print(f"{len(rows)} histories compared: max |diff| {worst:.3e}, {bad} with NaN or shape mismatches")
    return 0 if worst == 0 and bad == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
