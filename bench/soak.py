"""Soak test of ``ContinuousEstimator``: hours of simulated 1 kHz data, hour by hour.

A constant chain (Table 1 for n = 3, ``Chain.random(10, default_rng(10))`` for n = 10) under
20 Hz band-limited random forcing on every DOF, simulated exactly and chunk by chunk (the
plant and force filters of ``bench/crlb.py`` in modal form: every mode of the discretised
system is a first-order recursion run by ``scipy.signal.lfilter`` with its state carried
from chunk to chunk), white noise at the given SNR on the accelerations. The estimator runs
with its defaults, one ``run()`` per chunk (a minute by default). Per simulated hour it
reports the resident memory of the process, the cost per sample (median and worst over the
hour's chunks, so a chunk's mean), the largest relative error of the running estimates at
the end of the hour and the change events raised (on a constant chain: false alarms).

With ``--dropouts`` every chunk carries one sensor dropout on a random accelerometer, in turn:
a run of NaN (0.2-2 s), the channel frozen at its last reading (0.2-2 s), or the channel
clipped for the whole chunk at a range of 0.6-0.9 of the chunk's largest reading; the hourly
rows add the dropout runs the estimator reported, its ``BAD_INPUT`` samples and the runs
injected. None of them may raise a change event.

The default soaks one simulated hour of n = 3 and of n = 10 at 40 dB (every figure, hour 1
only). The published soaks (docs/reliability.md, "Long runs") are 24 h per configuration
and 3 h with dropouts:

    python bench/soak.py                     # 1 h of n = 3 and n = 10 at 40 dB
    python bench/soak.py --hours 24 --n 3 --snr 40 --json bench/results/soak24_n3_40db.json
    python bench/soak.py --hours 24 --n 3 --snr 20 --json bench/results/soak24_n3_20db.json
    python bench/soak.py --hours 24 --n 10 --snr 20 --json bench/results/soak24_n10_20db.json
    python bench/soak.py --hours 24 --n 10 --snr 40 --json bench/results/soak24_n10_40db.json
    python bench/soak.py --hours 3 --n 3 --snr 40 20 --dropouts --json bench/results/soak_dropouts.json

    python bench/soak.py [--hours 1] [--n 3 10] [--snr 40] [--dropouts] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import resource
import time
from pathlib import Path

import numpy as np
from scipy.signal import lfilter

import algid  # noqa: E402
from algid.identification import crlb  # noqa: E402
from algid.model.chain import TABLE1, Chain  # noqa: E402

FS_HZ = 1000.0


class ModalPlant:
    """The exact discretisation z+ = Phi z + Gam w of force filters and chain, diagonalised:
    y = V^-1 z, y+ = lam y + V^-1 Gam w, so every mode is one first-order filter."""

    def __init__(self, chain: Chain, seed: int, band_hz: float = 20.0, force_rms: float = 10.0):
        n, h = chain.n, 1.0 / FS_HZ
        Af, Bf, Cf = crlb.force_filter(n, band_hz)
        Phi, Gam = crlb._plant(crlb.params_of(chain), n, Af, Bf, Cf, h)
        self.lam, self.V = np.linalg.eig(Phi)
        self.G = np.linalg.solve(self.V, Gam)
        self.n, self.nf, self.Cf, self.chain = n, Af.shape[0], Cf, chain
        self.gain = crlb._filter_gain(band_hz, h, force_rms)
        self.y = np.zeros(self.lam.size, complex)
        self.rng = np.random.default_rng(seed)
        self.chunk(int(3 * FS_HZ))  # burn-in: a stationary state at t = 0

    def chunk(self, T: int) -> tuple[np.ndarray, np.ndarray]:
        """The next T samples: clean accelerations [m/s^2] and forces [N], (T, n) each."""
        drive = (self.rng.standard_normal((T, self.n)) * self.gain) @ self.G.T  # (T, modes)
        Y = np.empty((T, self.lam.size), complex)
        for j, lam in enumerate(self.lam):
            # out_k = y_k, the state before input k; zf = y_T, the state after the chunk
            Y[:, j], zf = lfilter([0.0, 1.0], [1.0, -lam], drive[:, j], zi=[self.y[j]])
            self.y[j] = zf[0]
        Z = (Y @ self.V.T).real
        n, nf = self.n, self.nf
        u = Z[:, :nf] @ self.Cf.T
        x, v = Z[:, nf : nf + n], Z[:, nf + n :]
        A = crlb.chain_blocks(self.chain.mass, self.chain.damping, self.chain.stiffness)[0]
        a = x @ A[n:, :n].T + v @ A[n:, n:].T + u / self.chain.mass  # eq. 1 solved for a
        return a, u


def rss_mb() -> float:
    """Resident memory of this process now [MB] (Linux /proc; the peak elsewhere)."""
    try:
        return int(Path("/proc/self/statm").read_text().split()[1]) * resource.getpagesize() / 2**20
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def inject_dropout(a: np.ndarray, k: int, rng) -> np.ndarray:
    """Chunk ``k``'s dropout (module docstring) on a random channel of ``a`` (T, n), in place."""
    T, n = a.shape
    ch = int(rng.integers(n))
    length = int(rng.integers(200, 2000))
    start = int(rng.integers(1, T - length))
    kind = k % 3
    if kind == 0:
        a[start : start + length, ch] = np.nan
    elif kind == 1:
        a[start : start + length, ch] = a[start - 1, ch]
    else:
        limit = rng.uniform(0.6, 0.9) * np.abs(a[:, ch]).max()
        a[:, ch] = np.clip(a[:, ch], -limit, limit)
    return a


def soak(
    n: int, snr_db: float, hours: float, chunk_s: float, seed: int = 0, progress=print, dropouts: bool = False
) -> list[dict]:
    """Run the soak of one configuration; one row per simulated hour."""
    chain = TABLE1 if n == 3 else Chain.random(n, np.random.default_rng(n))
    plant = ModalPlant(chain, seed)
    est = algid.ContinuousEstimator(n, 1.0 / FS_HZ)
    truth = crlb.params_of(chain)
    known = np.isfinite(truth) & (truth != 0)
    rng = np.random.default_rng(seed + 1)
    T = int(round(chunk_s * FS_HZ))
    chunks_per_hour = int(round(3600.0 / chunk_s))
    sigma = None
    rows = []
    runs0 = 0
    for hour in range(int(np.ceil(hours))):
        costs, events, bad = [], 0, 0
        for k in range(chunks_per_hour):
            a, u = plant.chunk(T)
            if sigma is None:
                sigma = crlb.rms(a) * 10 ** (-snr_db / 20)
            a = a + sigma * rng.standard_normal(a.shape)
            if dropouts:
                inject_dropout(a, k, rng)
            start = time.perf_counter()
            out = est.run(a, u, stride=T)
            costs.append((time.perf_counter() - start) / T)
            events += len(out["events"])
            bad += int(np.count_nonzero(out["status"] == int(algid.Status.BAD_INPUT)))
        err = np.abs(est.estimate[known] / truth[known] - 1)
        rows.append(
            {
                "n": n,
                "snr_db": snr_db,
                "hour": hour + 1,
                "rss_mb": rss_mb(),
                "us_per_sample_median": 1e6 * float(np.median(costs)),
                "us_per_sample_worst_chunk": 1e6 * float(np.max(costs)),
                "max_rel_error_pct": 100 * float(np.max(err)),
                "false_alarms": events,
                "dropouts_injected": chunks_per_hour if dropouts else 0,
                "dropout_runs_reported": est.dropouts["runs"] - runs0,
                "bad_input_samples": bad,
            }
        )
        runs0 = est.dropouts["runs"]
        progress(_row(rows[-1]))
    return rows


def _row(r: dict) -> str:
    return (
        f"| {r['n']} | {r['snr_db']:g} dB | {r['hour']} | {r['rss_mb']:.1f} | {r['us_per_sample_median']:.2f} / "
        f"{r['us_per_sample_worst_chunk']:.2f} | {r['max_rel_error_pct']:.3f} | {r['false_alarms']} | "
        f"{r['dropouts_injected']} / {r['dropout_runs_reported']} / {r['bad_input_samples']} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "--hours", type=float, default=1.0, help="simulated hours per configuration (default: 1; the docs: 24)"
    )
    ap.add_argument("--n", type=int, nargs="+", default=[3, 10], help="chain sizes")
    ap.add_argument(
        "--snr",
        type=float,
        nargs="+",
        default=[40.0],
        help="SNR on the accelerations [dB] (default: 40; the docs: 40, 20)",
    )
    ap.add_argument("--chunk-s", type=float, default=60.0, help="samples per run() call [s]")
    ap.add_argument("--dropouts", action="store_true", help="a sensor dropout in every chunk (module docstring)")
    ap.add_argument("--json", type=Path, help="write the rows as JSON")
    args = ap.parse_args()
    print(
        "| n | noise | hour | RSS [MB] | us per sample, median / worst chunk | max error [%] | change events "
        "| dropouts injected / stuck-clipped runs reported / NaN samples |"
    )
    print("|---|---|---|---|---|---|---|---|")
    rows = [
        r for n in args.n for snr in args.snr for r in soak(n, snr, args.hours, args.chunk_s, dropouts=args.dropouts)
    ]
    total = {}
    for r in rows:
        key = (r["n"], r["snr_db"])
        total[key] = total.get(key, 0) + r["false_alarms"]
    for (n, snr), count in total.items():
        hours = sum(1 for r in rows if (r["n"], r["snr_db"]) == (n, snr))
        print(f"n = {n}, {snr:g} dB: {count} change events in {hours} h ({24 * count / hours:.2f} per 24 h)")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
