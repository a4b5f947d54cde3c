"""Margin of ``algid identify``'s outlier screen (:mod:`algid.identification.screen`) on
clean records of every suite.

Per record and channel: ``d / R``, the largest deviation from the median over the robust
range (the fifth-largest deviation); the screen takes out samples beyond
``OUTLIER_RANGE`` (30) R, so a clean record must stay well below it. And ``1e3 RMS / R``:
how many robust ranges an outlier of 1e3 times the channel's RMS is (above 30: screened).
Reported per family: records, worst ``d / R``, records with anything screened, smallest
``1e3 RMS / R``.

The default draws 10 seeds of the blind and realistic suites (fewer records of every family);
the published table (docs/reliability.md) draws 40:

    python bench/outlier_screen.py                      # 10 seeds
    python bench/outlier_screen.py --seeds 40 --json bench/results/outlier_screen.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
import blind_diagnosis as B  # noqa: E402
import identify as I  # noqa: E402
import realistic_blind as RB  # noqa: E402

from algid.identification.screen import OUTLIER_RANGE, RANGE_RANK, screen  # noqa: E402
from algid.model.chain import TABLE1  # noqa: E402
from algid.recording import Recording  # noqa: E402
from algid.recording.datasets import f16_chain_recording, silverbox_recording  # noqa: E402
from algid.simulator import simulate  # noqa: E402
from algid.simulator.scenarios import impact_test, positioning_axis  # noqa: E402

DATA = HERE.parents[1] / "shared" / "data"


def margins(rec: Recording) -> tuple[float, float, int]:
    """Worst ``d / R``, smallest ``1e3 RMS / R`` over the channels, and samples screened."""
    worst, smallest = 0.0, np.inf
    for arr in (rec.u, rec.a, rec.v, rec.x):
        if arr is None:
            continue
        for y in arr.T:
            d = np.abs(y - np.median(y))
            r = np.sort(d)[::-1][RANGE_RANK]
            if r > 0:
                worst = max(worst, float(d.max() / r))
                smallest = min(smallest, float(1e3 * np.sqrt(np.mean(y**2)) / r))
    return worst, smallest, screen(rec)[1].count


def families(seeds: int):
    """(family, label, Recording) of every clean record."""
    for s in range(seeds):
        case = B.draw_case(s, 10.0, 1000.0)
        lab = case["label"]
        r = simulate(
            case["chain"],
            case["u"],
            10.0,
            1000.0,
            noise_db=lab["snr_db"],
            noise_on=("accel", "force"),
            effects=case["effects"],
            seed=s,
        )
        yield "blind diagnosis (10 s, 40-60 dB, hidden effects)", f"seed {s}", Recording(t=r.t, u=r.u, a=r.a)
    for s in range(seeds):
        rec, lab = RB.draw(s)
        yield "realistic rigs (shaker, axis, device)", f"seed {s} {lab['rig']}", rec
    for s in range(min(seeds, 4)):
        yield "identify calibration and multisine", f"multisine {s}", I.multisine_record(TABLE1, s)
    for name, snr, chans, seed, _chain, rec in I.calibration_records(1, 10.0):
        yield "identify calibration and multisine", f"{name} {snr} dB {chans} {seed}", rec
    for s in range(min(seeds, 5)):
        yield "positioning axis (encoder)", f"seed {s}", positioning_axis(seed=s, duration_s=20.0).recording
    for hits in (1, 2, 4):
        for s in range(min(seeds, 6)):
            yield "impact hammer, 1-4 hits", f"{hits} hits seed {s}", impact_test(seed=s, hits=hits).recording
    if DATA.is_dir():
        yield "measured: Silverbox, F-16", "Silverbox SNLS80mV", silverbox_recording(DATA, "all")
        for level in range(1, 8):
            yield "measured: Silverbox, F-16", f"F-16 FullMSine level {level}", f16_chain_recording(DATA, level)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=10, help="seeds per suite (default: 10; the docs: 40)")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    out: dict[str, dict] = {}
    for fam, label, rec in families(args.seeds):
        worst, smallest, count = margins(rec)
        row = out.setdefault(fam, {"records": 0, "worst_ratio": 0.0, "worst_record": "", "screened_records": 0})
        row["records"] += 1
        row["screened_records"] += int(count > 0)
        row["smallest_1e3_rms_over_range"] = min(row.get("smallest_1e3_rms_over_range", np.inf), smallest)
        if worst > row["worst_ratio"]:
            row["worst_ratio"], row["worst_record"] = worst, label
    for fam, row in out.items():
        print(
            f"{fam:>50}: {row['records']:3d} records, worst d/R {row['worst_ratio']:.2f} ({row['worst_record']}), "
            f"screened {row['screened_records']}, 1e3 RMS >= {row['smallest_1e3_rms_over_range']:.0f} R",
            flush=True,
        )
    if args.json:
        doc = {"outlier_range": OUTLIER_RANGE, "range_rank": RANGE_RANK, "families": out}
        doc["command"] = "python bench/outlier_screen.py " + " ".join(sys.argv[1:] if argv is None else argv)
        args.json.write_text(json.dumps(doc, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
