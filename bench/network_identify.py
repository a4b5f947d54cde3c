"""``algid.identify(rec, topology=net)`` on the three example spring networks
(:data:`algid.simulator.scenarios.NETWORKS`: frame, half_car, lattice): the joint windowed
equation-error fit refined by output error (:mod:`algid.identification.network`) against the
Cramer-Rao bound of the same records.

Every record is :func:`algid.identification.crlb.simulate`'s (broadband random force on every
DOF, 1 kHz) with white noise of ``--snr`` dB on the accelerations (the bound's noise model; the
force known). Per network and family (masses, dampers, springs): the RMS relative error over
the parameters and seeds, the RMS relative Cramer-Rao bound (:func:`algid.identification.crlb.crlb`)
of the first seed's record (the others are records of the same process and length; the bound
of a 9-DOF network's 20 s record takes about two minutes), their ratio, and the RMS
z-score ``(estimate - truth) / sigma`` (about 1 when the standard deviations are
calibrated); ``output_error_kept``: on how many of the noisy records identify kept the output
error (else its answer is the joint equation-error fit). Noise-free: the largest relative error
of any parameter on the first seed's record. A drawing of each network goes to ``docs/figures/network_<name>.png`` with
``--figures``.

    python bench/network_identify.py --networks half_car   # 2 seeds of 20 s, prints the table
    python bench/network_identify.py --seeds 3 --networks NAME --json bench/results/network_identify.json \\
        --figures docs/figures    # the published run, once per network (each adds its entry to the JSON)
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import algid
from algid.identification.crlb import crlb, simulate
from algid.recording import Recording
from algid.simulator.scenarios import NETWORKS, network_model


def identified(model, rec, a, u) -> tuple[np.ndarray, np.ndarray, bool]:
    """Estimates and standard deviations of ``identify`` on accelerations ``a``, forces ``u``,
    and whether it kept the output error."""
    r = algid.identify(Recording(t=rec.t, u=u, a=a), topology=model.network)
    return r.theta, r.sigma, bool(r.model_fit.get("output_error", {}).get("kept"))


def one_network(name: str, seconds: float, snr_db: float, seeds: int) -> dict:
    """The figures of network ``name`` (module docstring)."""
    model = network_model(name)
    truth = model.packed()
    names = model.network.parameter_names()
    errors, zs, bounds, clock = [], [], [], time.perf_counter()
    noise_free, kept = None, 0
    for seed in range(seeds):
        rec = simulate(model, seconds, seed=seed)
        if noise_free is None:
            theta, _, _ = identified(model, rec, rec.a, rec.u)
            noise_free = float(np.nanmax(np.abs(theta / truth - 1)))
        a, u = rec.noisy(snr_db, ("accel",), seed)
        theta, sigma, refined = identified(model, rec, a, u)
        kept += refined
        errors.append(theta / truth - 1)
        zs.append((theta - truth) / sigma)
        if not bounds:
            bounds.append(crlb(rec, snr_db, (seconds,))[float(seconds)])
    errors, zs, bounds = np.array(errors), np.array(zs), np.array(bounds)
    families = {}
    for f, label in (("m", "mass"), ("c", "damping"), ("k", "stiffness")):
        sel = np.array([nm[0] == f for nm in names])
        err = float(np.sqrt(np.nanmean(errors[:, sel] ** 2)))
        bnd = float(np.sqrt(np.nanmean(bounds[:, sel] ** 2)))
        families[label] = {
            "rms_rel_error": err,
            "rms_rel_crlb": bnd,
            "ratio": err / bnd,
            "rms_z": float(np.sqrt(np.nanmean(zs[:, sel] ** 2))),
        }
    return {
        "n": model.n,
        "springs": model.network.size,
        "families": families,
        "noise_free_max_rel_error": noise_free,
        "output_error_kept": kept,
        "seconds_per_record": (time.perf_counter() - clock) / (2 * seeds),
    }


#: Where each network's masses are drawn: frame floors upward (x, twist, y of each floor),
#: the half-car body over its wheels, the lattice's rows.
LAYOUT = {
    "frame": {
        3 * f + 1 + d: (x, f + (0.35 if d == 2 else 0.0)) for f in range(3) for d, x in ((0, -1), (1, 1), (2, 0))
    },
    "half_car": {1: (-1.0, 1.0), 2: (1.0, 1.0), 3: (-1.0, 0.0), 4: (1.0, 0.0)},
    "lattice": {3 * r + c + 1: (float(c), -float(r)) for r in range(3) for c in range(3)},
}


def draw(name: str, folder: Path) -> Path:
    """A drawing of network ``name`` (:data:`LAYOUT`): spring ``k_s`` a line, a spring to ground
    a line to a hatched ground mark (below, or away from the centre for the lattice)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    net = network_model(name).network
    pos = {i: np.array(p, dtype=float) for i, p in LAYOUT[name].items()}
    centre = np.mean(list(pos.values()), axis=0)
    fig, ax = plt.subplots(figsize=(4.2, 4.2))
    for s, (a, b) in enumerate(net.springs, start=1):
        if a and b:
            p, q = pos[a], pos[b]
        else:
            p = pos[a or b]
            out = p - centre if name == "lattice" else np.array([0.0, -1.0])
            q = p + 0.6 * out / np.linalg.norm(out)
            ax.plot([q[0] - 0.15, q[0] + 0.15], [q[1], q[1]], color="0.3", lw=3)
        ax.plot([p[0], q[0]], [p[1], q[1]], color="tab:blue", lw=1.2, zorder=1)
        mid = 0.7 * p + 0.3 * q  # crossing diagonals get their labels apart
        ax.annotate(f"k{s}", mid, fontsize=7, color="tab:blue", xytext=(2, 2), textcoords="offset points")
    for i, (x, y) in pos.items():
        ax.scatter([x], [y], s=260, color="tab:orange", zorder=2)
        ax.annotate(str(i), (x, y), ha="center", va="center", fontsize=8, zorder=3)
    ax.set_title(f"{name}: {net.n} masses, {net.size} springs", fontsize=9)
    ax.set_aspect("equal")
    ax.axis("off")
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / f"network_{name}.png"
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--snr", type=float, default=40.0)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--networks", nargs="+", choices=sorted(NETWORKS), default=sorted(NETWORKS))
    ap.add_argument("--json", type=Path, help="write the figures as JSON")
    ap.add_argument("--figures", type=Path, help="folder of the network drawings")
    args = ap.parse_args()
    settings = {"seconds": args.seconds, "snr_db": args.snr, "seeds": args.seeds, "forces": "every DOF"}
    out = {**settings, "networks": {}}
    if args.json is not None and args.json.exists():  # one network per run: keep the others of the same settings
        known = json.loads(args.json.read_text(encoding="utf-8"))
        if all(known.get(k) == v for k, v in settings.items()):
            out["networks"] = known["networks"]
    print(f"{args.seconds:g} s, {args.snr:g} dB on the accelerations, {args.seeds} seeds, force on every DOF")
    print(f"{'network':>10} {'family':>9} {'RMS err %':>10} {'CRLB %':>8} {'ratio':>6} {'RMS z':>6}")
    for name in args.networks:
        res = out["networks"][name] = one_network(name, args.seconds, args.snr, args.seeds)
        for fam, f in res["families"].items():
            print(
                f"{name:>10} {fam:>9} {100 * f['rms_rel_error']:10.4f} {100 * f['rms_rel_crlb']:8.4f} "
                f"{f['ratio']:6.2f} {f['rms_z']:6.2f}"
            )
        print(f"{name:>10} noise-free: largest relative error {res['noise_free_max_rel_error']:.2g}")
        if args.figures is not None:
            draw(name, args.figures)
    if args.json is not None:
        args.json.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
