"""The Cramer-Rao lower bound of every Table 1 parameter at 1, 10 and 60 s (40 dB on the
accelerations): the "CRLB" rows of docs/continuous.md. The simulator and the bound are
:mod:`algid.identification.crlb`.

    python bench/crlb.py [--snr 40] [--seconds 1 10 60]   # prints the bound for Table 1
    python bench/crlb.py --forced 1                       # with a force on DOF 1 only
"""

from __future__ import annotations

import argparse

from algid.identification.crlb import crlb, simulate
from algid.model.chain import TABLE1


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--snr", type=float, default=40.0)
    ap.add_argument("--seconds", type=float, nargs="+", default=[1.0, 10.0, 60.0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--forced", type=int, nargs="+", metavar="DOF", help="1-based DOFs with a force (default: all)")
    args = ap.parse_args()
    forced = None if args.forced is None else [d - 1 for d in args.forced]
    rec = simulate(TABLE1, max(args.seconds), seed=args.seed, forced=forced)
    bound = crlb(rec, args.snr, args.seconds)
    n = rec.n
    names = [f"m{i + 1}" for i in range(n)] + [f"c{i + 1}" for i in range(n)] + [f"k{i + 1}" for i in range(n + 1)]
    where = "every DOF" if forced is None else "DOF " + ", ".join(str(d) for d in args.forced)
    print(f"Table 1, force on {where}, {args.snr:g} dB on the accelerations, relative CRLB [%]")
    print("   t [s] " + " ".join(f"{s:>7}" for s in names))
    for t, rel in bound.items():
        print(f"{t:8.1f} " + " ".join(f"{100 * r:7.4f}" for r in rel))


if __name__ == "__main__":
    main()
