"""Issue 36 figures: the chain's m, c, k from FRFs (``algid identify frf.npz``,
``algid.identification.frf_fit``).

Cases, each on 2,000 lines evenly spaced from 0.1 to 2 times the highest natural frequency:

* Table 1, noise-free accelerances, all three columns and each single column: the largest
  relative error over the 10 parameters (target 1e-6);
* Table 1 at 40 dB: complex Gaussian noise of rms 1 % of ``|H|`` on every line (relative to
  each line's own magnitude, not to the FRF's RMS), over ``--seeds`` seeds, all columns and
  the force on DOF 1 only: the largest relative error of the masses and springs (target
  1 %), of the dampings, and ``|error| / sigma`` over every parameter and seed (rms and
  largest: calibrated sigmas give an rms near 1), the fit check's residual / noise ratio, and
  the calibration (:func:`calibration`: per parameter the estimates' scatter over the seeds
  against the reported sigma, with its sampling error and z-score; 20 seeds resolve the ratio
  to about 16 %, so a further one-force case over ``--calibration-seeds`` (200: 5 %) gives it);
* random 5-DOF chains (``Chain.random``), force on DOF 1 only: noise-free and at 40 dB.

Writes bench/results/frf_fit.json (``--json PATH`` elsewhere); runs in about 2.5 minutes here:

    python bench/frf_fit.py [--seeds 20] [--calibration-seeds 200] [--json bench/results/frf_fit.json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from algid import FrfData
from algid.identification.frf_fit import identify_frf
from algid.model.chain import TABLE1, Chain

LINES = 2000
NOISE = 0.01  # rms of the complex noise relative to |H| on every line: 40 dB


def accelerances(chain: Chain, forces: list[int]) -> FrfData:
    """Noise-free accelerances of ``chain`` with forces on ``forces`` (1-based)."""
    f = np.linspace(0.1, 2.0, LINES) * chain.natural_frequencies_hz().max()
    H = np.moveaxis(chain.frf(f, "acceleration"), 0, 2)[:, np.array(forces) - 1]
    return FrfData(f, H, "accelerance", np.arange(1, chain.n + 1), np.array(forces))


def with_noise(data: FrfData, seed: int) -> FrfData:
    rng = np.random.default_rng(seed)
    e = (rng.standard_normal(data.H.shape) + 1j * rng.standard_normal(data.H.shape)) / np.sqrt(2)
    return FrfData(
        data.frequency_hz, data.H + NOISE * np.abs(data.H) * e, data.quantity, data.response_dof, data.force_dof
    )


def errors(chain: Chain, data: FrfData) -> dict:
    """Relative errors and ``|error| / sigma`` of one fit."""
    res = identify_frf(data, chain.boundary)
    truth = chain.identifiable()
    est = np.isfinite(truth)
    rel = np.abs(res.theta / truth - 1)[est]
    n = chain.n
    fam = np.array(list("m" * n + "c" * n + "k" * (n + 1)))[est]
    return {
        "mass_spring": float(rel[fam != "c"].max()),
        "damping": float(rel[fam == "c"].max()),
        "theta": res.theta[est],
        "sigma": res.sigma[est],
        "z": ((res.theta - truth) / res.sigma)[est],
        "ratio": res.model_fit["ratio"],
        "valid": res.valid,
    }


def calibration(runs: list[dict]) -> dict:
    """Per parameter, the scatter of the estimates over the seeds against the sigma the fit
    reports (rms over the seeds): ``std_over_sigma`` is 1 for calibrated sigmas, within its
    sampling error ``1 / sqrt(2 (seeds - 1))`` (``z`` = its distance from 1 in those errors),
    and ``bias_z`` the mean error in units of its standard error ``std / sqrt(seeds)``."""
    theta, sigma, err = (np.array([r[k] for r in runs]) for k in ("theta", "sigma", "z"))
    N = theta.shape[0]
    ratio = theta.std(axis=0, ddof=1) / np.sqrt(np.mean(sigma**2, axis=0))
    se = 1 / np.sqrt(2 * (N - 1))
    error = err * sigma  # estimate minus truth
    bias_z = error.mean(axis=0) / (theta.std(axis=0, ddof=1) / np.sqrt(N))
    return {
        "std_over_sigma": ratio.tolist(),
        "sampling_error": se,
        "z": ((ratio - 1) / se).tolist(),
        "mean_std_over_sigma": float(ratio.mean()),
        "bias_z": bias_z.tolist(),
    }


def noisy_case(chain: Chain, forces: list[int], seeds: int) -> dict:
    clean = accelerances(chain, forces)
    runs = [errors(chain, with_noise(clean, seed)) for seed in range(seeds)]
    z = np.concatenate([r["z"] for r in runs])
    return {
        "calibration": calibration(runs),
        "forces": forces,
        "seeds": seeds,
        "max_rel_error_mass_spring": max(r["mass_spring"] for r in runs),
        "max_rel_error_damping": max(r["damping"] for r in runs),
        "z_rms": float(np.sqrt(np.mean(z**2))),
        "z_max": float(np.abs(z).max()),
        "z_within_3": float(np.mean(np.abs(z) <= 3)),
        "residual_over_noise": [float(min(r["ratio"] for r in runs)), float(max(r["ratio"] for r in runs))],
        "valid_share": float(np.mean([r["valid"] for r in runs])),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=20, help="noise seeds per noisy case")
    ap.add_argument(
        "--calibration-seeds",
        type=int,
        default=200,
        help="seeds of the Table 1 one-force case the sigmas' calibration is read from (0: none; 200: about a minute)",
    )
    ap.add_argument("--json", type=Path, default=Path(__file__).parent / "results" / "frf_fit.json")
    args = ap.parse_args()
    start = time.perf_counter()
    out = {"lines": LINES, "band": "0.1-2 x the highest natural frequency", "noise": "complex Gaussian, rms 1 % of |H|"}
    out["table1_noise_free"] = {
        str(cols): errors(TABLE1, accelerances(TABLE1, cols))["mass_spring"] for cols in ([1, 2, 3], [1], [2], [3])
    }
    out["table1_noise_free_damping"] = {
        str(cols): errors(TABLE1, accelerances(TABLE1, cols))["damping"] for cols in ([1, 2, 3], [1], [2], [3])
    }
    out["table1_40db"] = [noisy_case(TABLE1, cols, args.seeds) for cols in ([1, 2, 3], [1])]
    chains = [Chain.random(5, np.random.default_rng(seed)) for seed in range(3)]
    out["random5_noise_free"] = [
        max(errors(c, accelerances(c, [1]))[k] for k in ("mass_spring", "damping")) for c in chains
    ]
    out["random5_40db"] = noisy_case(chains[0], [1], args.seeds)
    if args.calibration_seeds:
        out["table1_40db_one_force_calibration"] = noisy_case(TABLE1, [1], args.calibration_seeds)
    out["seconds"] = time.perf_counter() - start
    print(json.dumps(out, indent=2))
    args.json.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
