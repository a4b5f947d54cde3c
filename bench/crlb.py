"""The Cramer-Rao lower bound of every Table 1 parameter at 1, 10 and 60 s (40 dB on the
accelerations): the "CRLB" rows of docs/continuous.md; with ``--network NAME`` the bound of one
of the example spring networks (:data:`algid.simulator.scenarios.NETWORKS`), per family of
parameters (masses, dampers, springs: smallest, median and largest). The simulator and the
bound are :mod:`algid.identification.crlb`.

    python bench/crlb.py [--snr 40] [--seconds 1 10 60]   # prints the bound for Table 1
    python bench/crlb.py --forced 1                       # with a force on DOF 1 only
    python bench/crlb.py --network lattice --seconds 1 20 # a network, per family
"""

from __future__ import annotations

import argparse

import numpy as np

from algid.identification.crlb import crlb, simulate
from algid.model.chain import TABLE1
from algid.simulator.scenarios import NETWORKS, network_model


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--snr", type=float, default=40.0)
    ap.add_argument("--seconds", type=float, nargs="+", default=[1.0, 10.0, 60.0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--forced", type=int, nargs="+", metavar="DOF", help="1-based DOFs with a force (default: all)")
    ap.add_argument("--network", choices=sorted(NETWORKS), help="an example spring network instead of Table 1")
    args = ap.parse_args()
    forced = None if args.forced is None else [d - 1 for d in args.forced]
    model = TABLE1 if args.network is None else network_model(args.network)
    rec = simulate(model, max(args.seconds), seed=args.seed, forced=forced)
    bound = crlb(rec, args.snr, args.seconds)
    where = "every DOF" if forced is None else "DOF " + ", ".join(str(d) for d in args.forced)
    name = "Table 1" if args.network is None else f"network {args.network!r}"
    print(f"{name}, force on {where}, {args.snr:g} dB on the accelerations, relative CRLB [%]")
    if args.network is None:
        per_parameter(bound, rec.n)
    else:
        per_family(bound, model.network.parameter_names())


def per_parameter(bound: dict, n: int) -> None:
    """One column per parameter of the chain."""
    names = [f"m{i + 1}" for i in range(n)] + [f"c{i + 1}" for i in range(n)] + [f"k{i + 1}" for i in range(n + 1)]
    print("   t [s] " + " ".join(f"{s:>7}" for s in names))
    for t, rel in bound.items():
        print(f"{t:8.1f} " + " ".join(f"{100 * r:7.4f}" for r in rel))


def per_family(bound: dict, names: list[str]) -> None:
    """Smallest, median and largest bound of the masses, the dampers and the springs."""
    fams = {f: np.array([nm[0] == f for nm in names]) for f in "mck"}
    print("   t [s] " + " ".join(f"{f + ' ' + q:>9}" for f in "mck" for q in ("min", "med", "max")))
    for t, rel in bound.items():
        cells = [q(100 * rel[fams[f]]) for f in "mck" for q in (np.min, np.median, np.max)]
        print(f"{t:8.1f} " + " ".join(f"{v:9.4f}" for v in cells))


if __name__ == "__main__":
    main()
