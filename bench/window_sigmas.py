"""Are the weak form's per-window sigmas calibrated, and what do they do to the step test?

The soak's constant chain (``bench/soak.py``: 20 Hz band-limited random forcing on every DOF,
white noise on the accelerations) through ``ContinuousEstimator`` with its defaults; every
window result and its GLS variance kept. Per parameter:

* calibration: median |result - truth| / sigma of the window results, over 0.6745 (1 when the
  sigmas are right for Gaussian errors);
* the step test replayed offline against the truth: the largest |median of 9 consecutive z| with
  z = error / max(spread, 1 % |truth|) (the spread: 1.4826 MAD of the 64 results before) and
  with z = error / max(spread, 1 % |truth|, the window's sigma); the test alarms above 6;
* the window misfits (median, largest over median).

The default simulates 15 minutes (every figure, fewer windows); the published figures
(docs/reliability.md, "Long runs") take 150:

    python bench/window_sigmas.py                   # n = 10, 20 dB, 15 simulated minutes
    python bench/window_sigmas.py --n 10 --snr 20 --minutes 150 --seed 1
"""

from __future__ import annotations

import argparse

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from soak import FS_HZ, ModalPlant  # noqa: E402

import algid  # noqa: E402
from algid.identification import crlb  # noqa: E402
from algid.model.chain import TABLE1, Chain  # noqa: E402


def record(n: int, snr_db: float, minutes: int, seed: int):
    """Window results, their variances and misfits over ``minutes`` simulated minutes."""
    chain = TABLE1 if n == 3 else Chain.random(n, np.random.default_rng(n))
    plant, est = ModalPlant(chain, seed), algid.ContinuousEstimator(n, 1.0 / FS_HZ)
    rng, sigma, parts = np.random.default_rng(seed + 1), None, []
    for _ in range(minutes):
        a, u = plant.chunk(int(60 * FS_HZ))
        sigma = crlb.rms(a) * 10 ** (-snr_db / 20) if sigma is None else sigma
        out = est.run(a + sigma * rng.standard_normal(a.shape), u, stride=60000)
        parts.append((out["windows"], out["window_variance"], out["window_misfit"]))
    windows, variance, misfit = (np.concatenate(p) for p in zip(*parts))
    return est, crlb.params_of(chain), windows, variance, misfit


def largest_median_z(error: np.ndarray, scale: np.ndarray, confirm: int = 9) -> float:
    z = np.nan_to_num(error / scale)
    return float(np.abs(np.median(sliding_window_view(z, confirm), axis=1)).max())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--snr", type=float, default=20.0, help="SNR on the accelerations [dB]")
    ap.add_argument("--minutes", type=int, default=15, help="simulated minutes (default: 15; the docs: 150)")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    est, truth, windows, variance, misfit = record(args.n, args.snr, args.minutes, args.seed)
    print(
        f"{len(windows)} windows; misfit median {np.nanmedian(misfit):.3f}, largest / median "
        f"{np.nanmax(misfit) / np.nanmedian(misfit):.2f}; {est.screened_windows} screened"
    )
    print("| parameter | truth | spread / truth | calibration | max median-9 z, spread | with window sigma |")
    print("|---|---|---|---|---|---|")
    for j in np.flatnonzero(np.isfinite(truth) & (truth != 0)):
        x = np.where(np.isfinite(windows[:, j]), windows[:, j], truth[j])
        error, sd = x - truth[j], np.sqrt(variance[:, j])
        ok = np.isfinite(sd)
        calibration = np.median(np.abs(error[ok]) / sd[ok]) / 0.6745
        ring = sliding_window_view(x, 64)[:-1]
        spread = 1.4826 * np.median(np.abs(ring - np.median(ring, axis=1)[:, None]), axis=1)
        floor = np.maximum(spread, 0.01 * abs(truth[j]))
        e = error[64:]
        print(
            f"| {est.names[j]} | {truth[j]:.4g} | {np.median(spread) / abs(truth[j]):.3f} | {calibration:.2f} | "
            f"{largest_median_z(e, floor):.2f} | {largest_median_z(e, np.fmax(floor, sd[64:])):.2f} |"
        )


if __name__ == "__main__":
    main()
