"""Memory and time of loading, ``algid identify`` and ``algid diagnose`` against the record length.

Records: Table 1 (3 DOF) under 20 Hz band-limited random forcing (``crlb.simulate``, exact),
40 dB on forces and accelerations, written as CSV with 10 significant digits; and one random
20-DOF chain, 2 s. Every step runs in its own Python process under ``/usr/bin/time``: peak
resident memory (``%M``) and wall time. Reported per record: the CSV size, the float64 data
(``8 (2n+1) T`` bytes), each step's peak memory above a process that has imported numpy
and algid and nothing else (the baseline, measured in the same run), that growth per MB of
float64 data and per MB of CSV, and seconds per second of record.

The default measures the 10 s and 100 s records and the 20-DOF one; the published table
(docs/reliability.md, "Memory and time against the record length") adds the 1000 s record,
which alone takes about 15 minutes here:

    python bench/diagnose_cost.py                                       # 10 s, 100 s, n = 20
    python bench/diagnose_cost.py --durations 10 100 1000 --json bench/results/diagnose_cost.json
    python bench/diagnose_cost.py --durations 10 --steps diagnose       # a quicker look
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
from algid.identification import crlb  # noqa: E402
from algid.model.chain import TABLE1, Chain  # noqa: E402
from algid.recording import Recording, save_recording  # noqa: E402

FS = 1000.0
SNR_DB = 40.0
STEPS = ("load", "identify", "diagnose")
#: What each step runs in its process (``{path}``: the CSV).
SCRIPTS = {
    "baseline": "import numpy, algid, algid.cli",
    "load": "import algid.cli; from algid.recording import load_recording; load_recording({path!r})",
    "identify": "import sys; from algid.cli import main; sys.exit(main(['identify', {path!r}, '--quiet', '--json', {out!r}]))",
    "diagnose": "import sys; from algid.cli import main; sys.exit(main(['diagnose', {path!r}, '--quiet', '--json', {out!r}]))",
}


def write_record(chain: Chain, duration_s: float, folder: Path, seed: int = 0) -> tuple[Path, int]:
    """CSV of ``chain`` (``duration_s`` at 1 kHz, 40 dB) and its float64 data size [bytes]."""
    rec = crlb.simulate(chain, duration_s, FS, seed=seed)
    a, u = rec.noisy(SNR_DB, ("accel", "force"), seed)
    path = folder / f"n{chain.n}_{duration_s:g}s.csv"
    save_recording(path, Recording(t=rec.t, u=u, a=a))
    return path, 8 * rec.t.size * (2 * chain.n + 1)


def measure(step: str, path: Path, out: Path) -> dict:
    """Peak resident memory [MB] and wall time [s] of one step in a fresh process."""
    code = SCRIPTS[step].format(path=str(path), out=str(out))
    cmd = ["/usr/bin/time", "-f", "%M %e", sys.executable, "-c", code]
    proc = subprocess.run(cmd, capture_output=True, text=True, env={"PYTHONPATH": str(HERE.parent / "python")})
    rss_kb, wall = proc.stderr.strip().splitlines()[-1].split()
    return {"peak_mb": int(rss_kb) / 1024, "wall_s": float(wall), "exit": proc.returncode}


def run_case(label: str, chain: Chain, duration_s: float, steps, folder: Path, baseline_mb: float) -> dict:
    t0 = time.perf_counter()
    path, data_bytes = write_record(chain, duration_s, folder)
    row = {
        "record": label,
        "n": chain.n,
        "duration_s": duration_s,
        "samples": int(round(duration_s * FS)),
        "csv_mb": path.stat().st_size / 2**20,
        "data_mb": data_bytes / 2**20,
        "generate_s": time.perf_counter() - t0,
    }
    for step in steps:
        m = measure(step, path, folder / "out.json")
        grown = m["peak_mb"] - baseline_mb
        row[step] = {
            **m,
            "grown_mb": grown,
            "per_data_mb": grown / row["data_mb"],
            "per_csv_mb": grown / row["csv_mb"],
            "s_per_record_s": m["wall_s"] / duration_s,
        }
        print(
            f"{label:>14} {step:>8}: peak {m['peak_mb']:8.1f} MB (+{grown:7.1f} MB = {grown / row['data_mb']:5.2f} x data, "
            f"{grown / row['csv_mb']:5.2f} x CSV), {m['wall_s']:7.1f} s (exit {m['exit']})",
            flush=True,
        )
    path.unlink()
    return row


def marginal(rows: list[dict]) -> list[dict]:
    """Growth between consecutive Table 1 records: peak memory per MB of float64 data and of
    CSV, and seconds per second of record (the constant costs of imports and start-up cancel)."""
    table1 = [r for r in rows if r["n"] == 3]
    out = []
    for lo, hi in zip(table1[:-1], table1[1:]):
        row = {"from_s": lo["duration_s"], "to_s": hi["duration_s"]}
        for step in STEPS:
            if step in lo and step in hi:
                dm = hi[step]["peak_mb"] - lo[step]["peak_mb"]
                row[step] = {
                    "mb_per_data_mb": dm / (hi["data_mb"] - lo["data_mb"]),
                    "mb_per_csv_mb": dm / (hi["csv_mb"] - lo["csv_mb"]),
                    "s_per_record_s": (hi[step]["wall_s"] - lo[step]["wall_s"]) / (hi["duration_s"] - lo["duration_s"]),
                }
        out.append(row)
        for step in STEPS:
            if step in row:
                m = row[step]
                print(
                    f"{lo['duration_s']:g} -> {hi['duration_s']:g} s {step:>8}: {m['mb_per_data_mb']:6.2f} MB per MB of "
                    f"data ({m['mb_per_csv_mb']:5.2f} per MB of CSV), {m['s_per_record_s']:.3f} s per s of record",
                    flush=True,
                )
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument(
        "--durations",
        type=float,
        nargs="+",
        default=[10.0, 100.0],
        help="Table 1 record lengths [s] (default: 10 100; the docs: 10 100 1000)",
    )
    ap.add_argument("--steps", nargs="+", choices=STEPS, default=list(STEPS))
    ap.add_argument("--no-large-n", action="store_true", help="skip the 20-DOF, 2 s record")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--summarize", type=Path, help="only print (and add) the growth figures of this JSON")
    args = ap.parse_args(argv)
    if args.summarize:
        doc = json.loads(args.summarize.read_text())
        doc["marginal"] = marginal(doc["rows"])
        args.summarize.write_text(json.dumps(doc, indent=2) + "\n")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        base = measure("baseline", folder / "none.csv", folder / "out.json")
        print(
            f"baseline (python + numpy + algid imported): {base['peak_mb']:.1f} MB, {base['wall_s']:.2f} s", flush=True
        )
        rows = [run_case(f"Table 1, {d:g} s", TABLE1, d, args.steps, folder, base["peak_mb"]) for d in args.durations]
        if not args.no_large_n:
            chain = Chain.random(20, np.random.default_rng(20))
            rows.append(run_case("random n=20, 2 s", chain, 2.0, args.steps, folder, base["peak_mb"]))
    doc = {"fs_hz": FS, "snr_db": SNR_DB, "baseline": base, "rows": rows, "marginal": marginal(rows)}
    doc["command"] = "python bench/diagnose_cost.py " + " ".join(sys.argv[1:] if argv is None else argv)
    if args.json:
        args.json.write_text(json.dumps(doc, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
