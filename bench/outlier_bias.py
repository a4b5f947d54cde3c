"""Bias of ``ContinuousEstimator`` from one finite acceleration outlier: Table 1's chain under a
multisine (``tests/signals.py``, noise-free, 30 s at 1 kHz), one sample of a1 replaced by a value
of 73 to 1e6 m/s^2 (a1's RMS is 5.4), at 1 s or as the very first sample, with the defaults,
a tighter ``outlier_ratio`` and without the weak form's bias compensation. Prints the worst
relative error of the running estimates at the end (nan: no estimate), whether the estimator
is ready, the change events, the status of the outlier sample, the accelerations' noise RMS the
weak form estimated, the windows the misfit screen kept out of the joint estimate and the
largest reported relative sigma (docs/reliability.md, findings 9 and 11).

    python bench/outlier_bias.py                                         # prints the table
    python bench/outlier_bias.py --json bench/results/outlier_bias.json  # the published rows
"""

import argparse
import json
from pathlib import Path

import numpy as np

import algid  # noqa: E402
from algid.model.chain import TABLE1  # noqa: E402
from algid.simulator.exact import multisine, simulate_chain  # noqa: E402

CONFIGS = {
    "defaults": {},
    "outlier_ratio=100": {"outlier_ratio": 100.0},
    "no bias compensation": {"bias_compensation": False},
}


def row(a, u, truth, config: str, at: int, value) -> dict:
    """One run: the outlier ``value`` (None: clean) in a1 at sample ``at``, the estimator's state at the end."""
    bad = a.copy()
    if value is not None:
        bad[at, 0] = value
    est = algid.ContinuousEstimator(3, 1e-3, **CONFIGS[config])
    out = est.run(bad, u, stride=100)
    return {
        "configuration": config,
        "a1": value,
        "at_s": at / 1000,
        "worst_rel_error": float(np.abs(est.estimate / truth - 1).max()),
        "ready": bool(est.ready),
        "events": len(out["events"]),
        "status": algid.Status(out["status"][at]).name,
        "accel_noise_rms": float(np.max(est.noise_rms[:3])),
        "screened_windows": int(est.screened_windows),
        "largest_rel_sigma": float(np.max(est.sigma / np.abs(est.estimate))),
    }


def line(r: dict) -> str:
    where = "first sample" if r["at_s"] == 0 else f"{r['at_s']:g} s"
    return (
        f"| {r['configuration']} | {r['a1']} at {where} | {r['worst_rel_error']:.2g} | {r['ready']} | {r['events']} "
        f"| {r['status']} | {r['accel_noise_rms']:.2g} | {r['screened_windows']} | {r['largest_rel_sigma']:.2g} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", type=Path, default=None, help="write the rows here")
    args = ap.parse_args()
    t, a, u, _ = simulate_chain(TABLE1, multisine(3, seed=4), 30.0, 1000.0)
    truth = TABLE1.identifiable()
    rms, peak = float(np.sqrt(np.mean(a[:, 0] ** 2))), float(np.abs(a[:, 0]).max())
    print(f"a1: RMS {rms:.3g} m/s^2, peak {peak:.3g}")
    print(
        "| configuration | a1 [m/s^2] | worst relative error at 30 s | ready | change events "
        "| status of the sample | accel noise RMS estimate [m/s^2] | windows screened | largest sigma/estimate |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    rows = []
    for config in CONFIGS:
        rows.append(row(a, u, truth, config, 1000, None))
        print(line(rows[-1]))
        for at in (1000, 0):
            for value in (73.0, 1e3, 1e6):
                rows.append(row(a, u, truth, config, at, value))
                print(line(rows[-1]), flush=True)
    if args.json:
        args.json.write_text(json.dumps({"a1_rms": rms, "a1_peak": peak, "rows": rows}, indent=1))
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
