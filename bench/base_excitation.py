"""Base excitation (a shake table): ``algid.identify`` on records whose support moves.

Systems: the paper's Table 1 chain and ``Chain.random(5, default_rng(5))``. Each record is
20 s at 1 kHz of :func:`algid.simulator.base.simulate_base`: the support acceleration a
band-limited random signal (0.5-25 Hz, flat, 1 m/s^2 RMS, seed s), white noise at 40 dB on
every measured acceleration (``a0`` included). Cases:

* ``support_only``: no force: the worst relative error of the natural frequencies and of the
  damping ratios of the modal table (targets 0.5 % and 5 %), their largest |error| / sigma,
  the worst relative error of the ratios ``c_i / m_i``, ``k_i / m_i``, ``k_{i+1} / m_i``, and
  the masses' statuses (target: ``not_identifiable``).
* ``with_force``: the same plus a force on DOF 1 (the multisine 1.7, 4.9, 7.3 Hz of 30, 20,
  15 N, noise-free): the worst relative error of every mass, damping and spring (target: a
  few percent), validity.

Default: seeds 0, 1, 2 (about a minute). ``--seeds N`` for more; ``--json PATH`` (default
``bench/results/base_excitation.json``, the published file).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from algid.identification.engine import identify
from algid.model.chain import TABLE1, Chain
from algid.model.modal import modes
from algid.simulator.base import SupportMotion, simulate_base

DURATION_S, FS_HZ, SNR_DB = 20.0, 1000.0, 40.0


def _force(t: float) -> np.ndarray:
    f1 = 30 * np.sin(2 * np.pi * 1.7 * t) + 20 * np.sin(2 * np.pi * 4.9 * t + 1) + 15 * np.sin(2 * np.pi * 7.3 * t)
    return np.array([f1, *([0.0] * (_force.n - 1))])


def _modal_errors(result, chain: Chain) -> dict:
    """Worst relative error of the natural frequencies and damping ratios, and |error| / sigma."""
    est, true = result.modes()[0].modes, modes(chain).modes
    f = np.array([[m.frequency_hz, m.sigma_frequency_hz] for m in est])
    z = np.array([[m.damping_ratio, m.sigma_damping_ratio] for m in est])
    ft = np.array([m.frequency_hz for m in true])
    zt = np.array([m.damping_ratio for m in true])
    return {
        "frequency_rel_error_max": float(np.max(np.abs(f[:, 0] / ft - 1))),
        "damping_ratio_rel_error_max": float(np.max(np.abs(z[:, 0] / zt - 1))),
        "frequency_z_max": float(np.max(np.abs(f[:, 0] - ft) / f[:, 1])),
        "damping_ratio_z_max": float(np.max(np.abs(z[:, 0] - zt) / z[:, 1])),
    }


def _ratio_error(result, chain: Chain) -> float:
    m, c, k = chain.mass, chain.damping, chain.stiffness
    worst = 0.0
    for name, r in result.ratios.items():
        top, bottom = name.split("/")
        i = int(bottom[1:]) - 1
        j = int(top[1:]) - 1
        truth = (c[j] if top[0] == "c" else k[j]) / m[i]
        worst = max(worst, abs(r["value"] / truth - 1))
    return worst


def run_case(chain: Chain, seed: int, with_force: bool) -> dict:
    _force.n = chain.n
    rec = simulate_base(
        chain,
        SupportMotion.random(DURATION_S, seed=seed),
        DURATION_S,
        FS_HZ,
        force=_force if with_force else None,
        noise_db=SNR_DB,
        seed=seed,
    )
    t0 = time.perf_counter()
    r = identify(rec)
    row = {"seed": seed, "identify_s": time.perf_counter() - t0, "estimator": r.plan.estimator, "method": r.plan.method}
    row.update(_modal_errors(r, chain))
    if with_force:
        truth = np.concatenate([chain.mass, chain.damping, chain.stiffness])
        rel = np.abs(r.theta / truth - 1)
        row.update(
            {
                "mass_rel_error_max": float(np.nanmax(rel[: chain.n])),
                "damping_rel_error_max": float(np.nanmax(rel[chain.n : 2 * chain.n])),
                "stiffness_rel_error_max": float(np.nanmax(rel[2 * chain.n :])),
                "valid": r.valid,
            }
        )
    else:
        row.update(
            {
                "ratio_rel_error_max": _ratio_error(r, chain),
                "ratios_valid": all(v["valid"] for v in r.ratios.values()),
                "mass_statuses": sorted({v.status for v in r.verdicts if v.name[0] == "m"}),
                "mass_reason": r.verdict("m1").reason,
            }
        )
    return row


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--json", default="bench/results/base_excitation.json")
    args = ap.parse_args(argv)
    systems = {"table1": TABLE1, "random5": Chain.random(5, np.random.default_rng(5))}
    out = {"duration_s": DURATION_S, "fs_hz": FS_HZ, "snr_db": SNR_DB, "cases": {}}
    for name, chain in systems.items():
        for case in ("support_only", "with_force"):
            rows = [run_case(chain, s, case == "with_force") for s in range(args.seeds)]
            out["cases"][f"{name}/{case}"] = rows
            for row in rows:
                print(name, case, json.dumps({k: v for k, v in row.items() if k != "mass_reason"}))
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
