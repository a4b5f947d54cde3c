"""Figures of ``algid batch`` (issue 22): a generated fleet identified on Dask with 1 and 2
worker processes.

The fleet: ``--count`` recordings of 3-DOF chains (``--machines`` folders, machine i's chain
``Chain.random(3, default_rng(i))``), ``--duration`` s at 1 kHz under the tests' multisine,
cycling through no effect, a cubic spring and dry friction, and SNRs of 60, 40 and 30 dB
(:func:`algid.simulator.scenarios.write_fleet_recording`); generated once on the same Dask cluster into ``--data``.

For each worker count W (a ``LocalCluster`` of W single-threaded processes, started and warmed
up by one recording per worker before the clock starts), :func:`algid.batch` over the fleet
into a fresh output folder:

* throughput [recordings/s] = count / wall time of the batch;
* scaling efficiency of W workers = throughput(W) / (W throughput(1));
* work per recording = the mean of the rows' ``task_s`` (hash, load, identify, on the worker);
  CPU share = sum of ``cpu_s`` / sum of ``task_s``: 1 when every worker had a core of its own,
  lower when the workers waited for one (a machine shared with other jobs);
* Dask overhead per recording = (W wall - sum of task_s) / count: scheduling, transfers, the
  client's Parquet writes and the workers' idle time, in the same seconds as the work;
* memory per worker: each worker's resident memory after its recordings (``rss_mb``), median
  over its first and its last 10 % of recordings, and the difference.

The default is a 10-recording fleet (every figure, few recordings: a quick look, about a
minute). The published figures (docs/fleet.md) come from 1,000 recordings at both worker
counts in one run (about 5 minutes, after 11 minutes generating the fleet the first time):

    python bench/fleet.py                                # 10 recordings, 1 and 2 workers
    python bench/fleet.py --count 1000 --workers 1 2 --json bench/results/fleet1000.json
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import time
from pathlib import Path

import algid
from algid.fleet.engine import local_cluster
from algid.fleet.task import Options, run_one
from algid.simulator.scenarios import write_fleet_recording


def generate(client, data: Path, count: int, machines: int, duration_s: float) -> list[Path]:
    """The fleet in ``data`` (kept between runs: only missing recordings are simulated)."""
    per = -(-count // machines)
    jobs = [(i, j) for i in range(machines) for j in range(per)][:count]
    missing = [(i, j) for i, j in jobs if not (data / f"m{i:02d}" / f"rec{j:04d}.npz").exists()]
    futures = client.map(lambda ij: write_fleet_recording(data, ij[0], ij[1], 3, duration_s), missing, pure=False)
    client.gather(futures)
    return [data / f"m{i:02d}" / f"rec{j:04d}.npz" for i, j in jobs]


def memory(table) -> dict:
    """Per worker: resident memory [MiB] over its first and last 10 % of recordings."""
    out = {}
    for pid, rows in table.sort_values("finished_at").groupby("worker_pid"):
        tenth = max(1, len(rows) // 10)
        first, last = float(rows["rss_mb"].iloc[:tenth].median()), float(rows["rss_mb"].iloc[-tenth:].median())
        out[str(pid)] = {"recordings": len(rows), "first_mb": first, "last_mb": last, "growth_mb": last - first}
    return out


def measure(paths: list[Path], workers: int, scratch: Path) -> dict:
    from distributed import Client

    out = scratch / f"out-{workers}"
    shutil.rmtree(out, ignore_errors=True)
    with local_cluster(workers) as cluster, Client(cluster) as client:
        warm = client.map(run_one, [str(p) for p in paths[:workers]], options=Options(), pure=False)
        client.gather(warm)  # imports and first-call costs paid before the clock starts
        load = os.getloadavg()[0]
        clock = time.perf_counter()
        table = algid.batch(paths, out, client)
        wall = time.perf_counter() - clock
    n = len(table)
    work = float(table["task_s"].mean())
    overhead = (workers * wall - float(table["task_s"].sum())) / n
    return {
        "workers": workers,
        "recordings": n,
        "counts": table.attrs["counts"],
        "wall_s": wall,
        "throughput_per_s": n / wall,
        "work_per_recording_s": work,
        "cpu_share": float(table["cpu_s"].sum() / table["task_s"].sum()),
        "identify_median_s": float(table["identify_s"].median()),
        "overhead_per_recording_s": overhead,
        "overhead_share": overhead / work,
        "memory": memory(table),
        "loadavg_1min_at_start": load,
        "cpus": os.cpu_count(),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--count", type=int, default=10, help="recordings (default: 10; the issue's fleet: 1000)")
    ap.add_argument("--machines", type=int, default=0, help="folders (default: count / 25)")
    ap.add_argument("--duration", type=float, default=20.0, help="record length [s]")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--data", type=Path, default=None, help="fleet folder (default /tmp/algid-fleet-COUNT)")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    from distributed import Client

    data = args.data or Path(f"/tmp/algid-fleet-{args.count}")
    machines = args.machines or max(1, args.count // 25)
    clock = time.perf_counter()
    with local_cluster(max(args.workers)) as cluster, Client(cluster) as client:
        paths = generate(client, data, args.count, machines, args.duration)
    print(f"fleet: {len(paths)} recordings in {machines} folders of {data} ({time.perf_counter() - clock:.0f} s)")
    runs = [measure(paths, w, data.parent / f"{data.name}-out") for w in args.workers]
    base = next((r["throughput_per_s"] for r in runs if r["workers"] == 1), None)
    print(
        "| workers | recordings/s | efficiency | work/rec [s] | CPU share | Dask overhead/rec [s] | overhead/work | RSS first -> last [MiB] |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for r in runs:
        r["efficiency"] = None if base is None else r["throughput_per_s"] / (r["workers"] * base)
        rss = ", ".join(f"{m['first_mb']:.0f} -> {m['last_mb']:.0f}" for m in r["memory"].values())
        eff = "" if r["efficiency"] is None else f"{100 * r['efficiency']:.0f} %"
        print(
            f"| {r['workers']} | {r['throughput_per_s']:.3f} | {eff} | {r['work_per_recording_s']:.3f} | {r['cpu_share']:.2f} | "
            f"{r['overhead_per_recording_s']:.4f} | {100 * r['overhead_share']:.2f} % | {rss} |"
        )
    if args.json:
        doc = {"count": len(paths), "machines": machines, "duration_s": args.duration, "runs": runs}
        args.json.write_text(json.dumps(doc, indent=1, default=float) + "\n")
        print(f"written {args.json}")


if __name__ == "__main__":
    main()
