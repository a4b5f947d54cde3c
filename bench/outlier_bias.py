"""Bias of ``ContinuousEstimator`` from one finite acceleration outlier: Table 1's chain under a
multisine (``tests/signals.py``, noise-free, 30 s at 1 kHz), one sample of a1 replaced by a value
of 73 to 1e6 m/s^2 (a1's RMS is 5.4), at 1 s or as the very first sample, with the defaults,
a tighter ``outlier_ratio`` and without the weak form's bias compensation. Prints the worst
relative error of the running estimates at the end (nan: no estimate), whether the estimator
is ready, the change events, the status of the outlier sample, the accelerations' noise RMS the
weak form estimated and the largest reported relative sigma (docs/reliability.md, findings 9
and 11).

    python bench/outlier_bias.py
"""

import numpy as np

import algid  # noqa: E402
from algid.model.chain import TABLE1  # noqa: E402
from algid.simulator.exact import multisine, simulate_chain  # noqa: E402

CONFIGS = {
    "defaults": {},
    "outlier_ratio=100": {"outlier_ratio": 100.0},
    "no bias compensation": {"bias_compensation": False},
}


def row(a, u, truth, config: str, at: int, value) -> str:
    bad = a.copy()
    if value is not None:
        bad[at, 0] = value
    est = algid.ContinuousEstimator(3, 1e-3, **CONFIGS[config])
    out = est.run(bad, u, stride=100)
    worst = np.abs(est.estimate / truth - 1).max()
    status = algid.Status(out["status"][at]).name
    rel_sigma = np.max(est.sigma / np.abs(est.estimate))
    noise = np.max(est.noise_rms[:3])
    where = "first sample" if at == 0 else f"{at / 1000:g} s"
    return (
        f"| {config} | {value} at {where} | {worst:.2g} | {est.ready} | {len(out['events'])} | {status} "
        f"| {noise:.2g} | {rel_sigma:.2g} |"
    )


def main() -> None:
    t, a, u, _ = simulate_chain(TABLE1, multisine(3, seed=4), 30.0, 1000.0)
    truth = TABLE1.identifiable()
    print(f"a1: RMS {np.sqrt(np.mean(a[:, 0] ** 2)):.3g} m/s^2, peak {np.abs(a[:, 0]).max():.3g}")
    print(
        "| configuration | a1 [m/s^2] | worst relative error at 30 s | ready | change events "
        "| status of the sample | accel noise RMS estimate [m/s^2] | largest sigma/estimate |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for config in CONFIGS:
        print(row(a, u, truth, config, 1000, None))
        for at in (1000, 0):
            for value in (73.0, 1e3, 1e6):
                print(row(a, u, truth, config, at, value))


if __name__ == "__main__":
    main()
