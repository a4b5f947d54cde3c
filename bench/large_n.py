"""``algid identify`` on chains of any size: wall time and accuracy on noise-free records.

Each chain has random parameters (m 0.5-2 kg, c 1-5 N s/m, k 500-2000 N/m, seeded by n) and
a closed-form motion: x_i(t) = sum of six sines (1-40 Hz, log-spaced, random amplitudes and
phases), so v and a are exact and u = M a + C v + K x is eq. 1 exactly. The record
(0.5 s at 1 kHz by default) is written as an npz and identified by the command line
(``--estimator window``: the paper's single window), timed end to end as a user runs it.

The default sizes (3, 10, 11, 30, 200) take under a minute here; n = 1000 alone takes more
than 5 minutes and several GB of memory, so it is an option:

    python bench/large_n.py                                  # n = 3, 10, 11, 30, 200
    python bench/large_n.py --sizes 3,10,11,30,200,1000      # and n = 1000
    python bench/large_n.py [--sizes LIST] [--seconds 0.5] [--replicates 2] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from algid.model.chain import stiffness_matrix  # noqa: E402

TONES_HZ = np.geomspace(1.0, 40.0, 6)


def closed_form_record(n: int, seconds: float, dt: float = 1e-3) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Columns t, u1..un, a1..an of a noise-free record, and the true m, c, k packed."""
    rng = np.random.default_rng(n)
    m, c, k = rng.uniform(0.5, 2.0, n), rng.uniform(1.0, 5.0, n), rng.uniform(500.0, 2000.0, n + 1)
    t = np.arange(int(round(seconds / dt)) + 1) * dt
    w = 2 * np.pi * TONES_HZ
    amp = rng.normal(0.0, 1e-3, (n, w.size))  # [m]
    phase = rng.uniform(0.0, 2 * np.pi, (n, w.size))
    arg = w[None, :, None] * t[None, None, :] + phase[:, :, None]
    x = np.einsum("iq,iqt->ti", amp, np.sin(arg))
    v = np.einsum("iq,iqt->ti", amp * w, np.cos(arg))
    a = np.einsum("iq,iqt->ti", -amp * w**2, np.sin(arg))
    u = a * m + v * c + x @ stiffness_matrix(k)  # eq. 1 [N]
    columns = {"t": t} | {f"u{i + 1}": u[:, i] for i in range(n)} | {f"a{i + 1}": a[:, i] for i in range(n)}
    return columns, np.concatenate([m, c, k])


def identify(n: int, seconds: float, replicates: int, folder: Path) -> dict:
    columns, truth = closed_form_record(n, seconds)
    record, result = folder / f"chain{n}.npz", folder / f"chain{n}.json"
    np.savez(record, **columns)
    cmd = ["algid", "identify", str(record), "--json", str(result), "--quiet", "--estimator", "window"]
    cmd += ["--replicates", str(replicates)]
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"n = {n}: {' '.join(cmd)} failed ({proc.returncode}): {proc.stderr[-2000:]}")
    out = json.loads(result.read_text())
    error = np.abs(np.concatenate([out["mass"], out["damping"], out["stiffness"]]) / truth - 1.0)
    families = {"m": error[:n], "c": error[n : 2 * n], "k": error[2 * n :]}
    return {
        "n": n,
        "wall_s": wall,
        "max_rel_error": {f: float(e.max()) for f, e in families.items()},
        "valid_dof": int(sum(out["valid_dof"])),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="3,10,11,30,200", help="comma-separated chain sizes (default: 3,10,11,30,200)")
    ap.add_argument("--seconds", type=float, default=0.5, help="record length [s]")
    ap.add_argument("--replicates", type=int, default=2, help="identify's bootstrap replicates")
    ap.add_argument("--json", type=Path, help="write the rows as JSON")
    args = ap.parse_args()
    rows = []
    print("| n | identify wall time [s] | max rel. error m / c / k | valid DOF |\n|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(s) for s in args.sizes.split(",")):
            row = identify(n, args.seconds, args.replicates, Path(tmp))
            e = row["max_rel_error"]
            print(
                f"| {n} | {row['wall_s']:.1f} | {e['m']:.1e} / {e['c']:.1e} / {e['k']:.1e} | {row['valid_dof']}/{n} |"
            )
            rows.append(row)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
