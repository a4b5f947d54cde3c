"""One finite acceleration outlier against ``ContinuousEstimator``'s outlier screen: Table 1's
chain under a multisine (``tests/signals.py``, noise-free, 30 s at 1 kHz), a1 at 1 s replaced
by a value of 73 to 1e6 m/s^2 (a1's RMS is 5.4), for several ``outlier_ratio``; prints the
worst relative error of the running estimates at the end, the change events, the status of
the outlier sample and the largest reported relative sigma (docs/reliability.md, finding 9).

    python bench/fuzz/outlier_bias.py
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
import algid  # noqa: E402
from algid.chain import TABLE1  # noqa: E402
from signals import multisine, simulate_chain  # noqa: E402

t, a, u, _ = simulate_chain(TABLE1, multisine(3, seed=4), 30.0, 1000.0)
truth = TABLE1.identifiable()
print(f"a1: RMS {np.sqrt(np.mean(a[:, 0] ** 2)):.3g} m/s^2, peak {np.abs(a[:, 0]).max():.3g}")
print(
    "| outlier_ratio | a1 at 1 s [m/s^2] | worst relative error at 30 s | change events | status of the sample | largest sigma/estimate |"
)
print("|---|---|---|---|---|---|")
for ratio in (1e8, 100.0, 10.0):
    for value in (None, 73.0, 1e3, 1e6):
        bad = a.copy()
        if value is not None:
            bad[1000, 0] = value
        est = algid.ContinuousEstimator(3, 1e-3, outlier_ratio=ratio)
        out = est.run(bad, u, stride=100)
        worst = np.abs(est.estimate / truth - 1).max()
        status = algid.Status(out["status"][1000]).name
        rel_sigma = np.max(est.sigma / np.abs(est.estimate))
        print(f"| {ratio:g} | {value} | {worst:.2g} | {len(out['events'])} | {status} | {rel_sigma:.2g} |")
