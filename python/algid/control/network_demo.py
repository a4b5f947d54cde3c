"""``algid demo --topology NET.json``: the demo's motion on a spring network, open loop.

The demo's closed loop (eqs. 8-10 with the on-line estimates substituted) is the chain's: its
controller and its on-line estimators are written for eq. 1. On a network the demo runs what
carries over, and says so in its first line:

1. **The force.** The exact inverse dynamics of the true network along the demo's references
   (:meth:`algid.control.trajectories.BezierReference.paper`: rest to the targets
   ``(+5, +5, -5) mm`` repeated over the DOFs in the first 40 % of the record, back to rest from
   50 % to 90 %), ``u = M x_ref'' + C x_ref' + K x_ref``: the force the chain demo's controller
   applies once its estimates are exact. Along these references every DOF moves with the same
   time function, so the springs on one DOF could not be told apart; the demo's probe multisine
   (:class:`~.trajectories.Multisine`, ``--excitation`` N per line, default
   :data:`EXCITATION_N`) is added to every DOF's force. Its lines span the network's modes
   (:func:`probe_lines`): the chain demo's six lines stop at 15.7 Hz, below a stiff network's
   upper modes, which a record must carry for its springs to be told apart.
2. **The record.** The simulator samples the network at 1 kHz open loop, with ``--noise-db`` of
   white noise on the accelerations (forces exact, as the chain demo's).
3. **The estimates.** :func:`algid.identify` with ``topology=`` the network (the joint fit and
   its output-error refinement of ``algid identify --topology``), printed against the truth: value,
   one standard deviation, relative error and ``z = (estimate - truth) / sigma``.

The network's values come from the file when it holds them (a
:meth:`~algid.model.network.NetworkModel.from_json` document: an identify result, a diagnosis's
model, or ``{"n", "springs", "mass", "damping", "stiffness"}``). A topology-only file
``{"n", "springs"}`` gets the values of ``algid demo --n`` (:func:`default_values`): Table 1's
masses, dampings and stiffnesses, each list cycled to ``n`` masses and ``S`` springs.
"""

from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np

from ..model.chain import TABLE1
from ..model.network import Network, NetworkModel, json_document

#: The demo options of the chain's closed loop and their defaults: ``--topology`` refuses
#: any other value (``args`` attribute -> (flag, default)).
CHAIN_ONLY = {
    "mode": ("--mode", "continuous"),
    "estimator": ("--estimator", "auto"),
    "actuator_lag_ms": ("--actuator-lag-ms", 0.0),
    "velocity_pole": ("--velocity-pole", None),
    "n": ("--n", 3),
}

#: The probe's default amplitude per line [N]: ten times the chain demo's
#: (:data:`~.demo.DEFAULT_EXCITATION_N`), which a closed loop keeps small by its feedback; open
#: loop nothing does, and the probe is what tells the springs apart (docs/networks.md).
EXCITATION_N = 0.5

#: The probe's lines per DOF of the network (at least :data:`MIN_LINES`), and how far below the
#: lowest and above the highest natural frequency they reach.
LINES_PER_DOF = 2
MIN_LINES = 6
BELOW, ABOVE = 0.5, 1.5

#: The first line of the report: what this demo is and is not.
OPEN_LOOP = (
    "open loop: the closed loop of eqs. 8-10 is the chain's; the network gets the force that "
    "tracks the demo's references exactly plus the probe multisine"
)


def default_values(net: Network) -> NetworkModel:
    """``net`` with Table 1's masses [kg], dampings [N s/m] and stiffnesses [N/m], each
    list cycled to the network's ``n`` masses and ``S`` springs (as ``algid demo --n``)."""
    return NetworkModel(
        net, np.resize(TABLE1.mass, net.n), np.resize(TABLE1.damping, net.n), np.resize(TABLE1.stiffness, net.size)
    )


def read_network(path) -> tuple[NetworkModel, str]:
    """The network model of a ``--topology`` file (or its dict) and where its values come from:
    the file's own, or :func:`default_values` for a topology without values."""
    doc = json_document(path)
    if isinstance(doc, dict) and {"mass", "damping", "stiffness"} & set(doc):
        return NetworkModel.from_json(doc), "values from the file"
    return default_values(Network.from_json(doc)), "no values in the file: Table 1's cycled over masses and springs"


def probe_lines(model: NetworkModel) -> np.ndarray:
    """The probe's frequencies [Hz]: :data:`LINES_PER_DOF` lines per DOF, log-spaced from
    :data:`BELOW` times the lowest natural frequency of ``model`` (a rigid-body mode's zero
    left out) to :data:`ABOVE` times the highest."""
    f_hz = model.natural_frequencies_hz()
    elastic = f_hz[f_hz > 1e-3 * f_hz.max()]
    return np.geomspace(BELOW * elastic.min(), ABOVE * elastic.max(), max(MIN_LINES, LINES_PER_DOF * model.n))


def demo_force(model: NetworkModel, duration_s: float, excitation_n: float) -> Callable[[float], np.ndarray]:
    """``u(t)`` [N] (n,): the inverse dynamics of ``model`` along the demo's references plus
    the probe multisine of ``excitation_n`` N per line (module docstring)."""
    from .trajectories import BezierReference, Multisine

    ref = BezierReference.paper(model.n, t_out=(0.0, 0.4 * duration_s), t_back=(0.5 * duration_s, 0.9 * duration_s))
    probe = Multisine(model.n, excitation_n, freqs_hz=probe_lines(model))
    M, C, K = model.matrices()

    def force(t: float) -> np.ndarray:
        x, v, a = ref.evaluate(t)
        return M @ a + C @ v + K @ x + probe(t)

    return force


def run_network(
    model: NetworkModel,
    duration_s: float = 5.0,
    noise_db: float | None = None,
    seed: int = 0,
    excitation_n: float | None = None,
    progress: Callable[[str, float | None], None] | None = None,
) -> tuple[Any, Any, dict[str, Any]]:
    """Simulate ``model`` under :func:`demo_force` and identify it; returns the simulation,
    the :class:`algid.Identification` and the summary (:func:`summarize`). ``excitation_n``:
    the probe per line [N] (None: :data:`EXCITATION_N`); ``progress(stage, fraction)``."""
    from ..identification import identify
    from ..recording import Recording
    from ..simulator import simulate

    excitation_n = EXCITATION_N if excitation_n is None else float(excitation_n)
    clock = time.perf_counter()
    force = demo_force(model, duration_s, excitation_n)
    simulating = None if progress is None else (lambda fraction: progress("simulating network", fraction))
    sim = simulate(model, force, duration_s, 1000.0, noise_db=noise_db, seed=seed, progress=simulating)
    result = identify(Recording(t=sim.t, u=sim.u, a=sim.a), topology=model.network, progress=progress)
    s = summarize(model, result, time.perf_counter() - clock)
    s.update(duration_s=float(duration_s), noise_db=noise_db, excitation_n=excitation_n, seed=int(seed))
    s["probe_hz"] = probe_lines(model).tolist()
    return sim, result, s


def summarize(model: NetworkModel, result: Any, wall_s: float = float("nan")) -> dict[str, Any]:
    """The estimates of ``result`` against the truth ``model``: per parameter ``name, true,
    estimate, sigma, rel_err, z, status, reason``; the largest relative error of the ``ok`` ones
    (and their RMS z) and of every one with an estimate."""
    true = model.packed()
    rows = []
    for name, t, e, sg, v in zip(model.network.parameter_names(), true, result.theta, result.sigma, result.verdicts):
        with np.errstate(divide="ignore", invalid="ignore"):
            rel, z = e / t - 1.0 if t else np.nan, (e - t) / sg
        rows.append(
            {"name": name, "true": float(t), "estimate": float(e), "sigma": float(sg), "rel_err": float(rel)}
            | {"z": float(z), "status": v.status, "reason": v.reason or None}
        )
    ok = [r for r in rows if r["status"] == "ok" and np.isfinite(r["rel_err"])]
    estimated = [abs(r["rel_err"]) for r in rows if np.isfinite(r["rel_err"])]
    return {
        "n": model.n,
        "springs": [list(p) for p in model.network.springs],
        "parameters": rows,
        "ok_parameters": len(ok),
        "max_rel_err_ok": max((abs(r["rel_err"]) for r in ok), default=float("nan")),
        "rms_z_ok": float(np.sqrt(np.mean([r["z"] ** 2 for r in ok]))) if ok else float("nan"),
        "estimated_parameters": len(estimated),
        "max_rel_err_estimated": max(estimated, default=float("nan")),
        "estimator": result.plan.estimator,
        "wall_s": wall_s,
    }


def format_summary(s: dict[str, Any], source: str) -> str:
    """The report: what ran, one row per parameter, the largest error."""
    noise = "noise-free" if s["noise_db"] is None else f"{s['noise_db']:g} dB SNR"
    lines = [
        f"algid demo --topology: n = {s['n']}, {len(s['springs'])} springs ({source}), fs = 1000 Hz, "
        f"{s['duration_s']:g} s, accelerometers {noise}, probe {s['excitation_n']:g} N per line "
        f"({len(s['probe_hz'])} lines, {min(s['probe_hz']):.3g}-{max(s['probe_hz']):.3g} Hz)",
        OPEN_LOOP,
        f"estimates: algid.identify(record, topology=network), estimator {s['estimator']}",
        "",
        f"{'param':>6} {'true':>10} {'estimate':>12} {'sigma':>9} {'rel err':>9} {'z':>6}  status",
    ]
    for r in s["parameters"]:
        lines.append(
            f"{r['name']:>6} {r['true']:>10.4g} {r['estimate']:>12.6g} {r['sigma']:>9.2g} "
            f"{r['rel_err']:>9.1e} {r['z']:>6.2f}  {r['status']}"
        )
    total = len(s["parameters"])
    lines += [
        "",
        f"{s['ok_parameters']} of {total} parameters ok"
        + (
            f" (largest relative error {100 * s['max_rel_err_ok']:.3g} %, RMS z {s['rms_z_ok']:.2f})"
            if s["ok_parameters"]
            else ""
        )
        + f"; {s['estimated_parameters']} estimated, largest relative error "
        + (f"{100 * s['max_rel_err_estimated']:.3g} %" if s["estimated_parameters"] else "n/a"),
        f"simulated and identified in {s['wall_s']:.1f} s",
    ]
    return "\n".join(lines + _reasons(s["parameters"]))


def _reasons(rows: list[dict[str, Any]]) -> list[str]:
    """One line per distinct reason of the parameters that are not ``ok``, naming them all."""
    named: dict[str, list[str]] = {}
    for r in rows:
        if r["status"] != "ok" and r["reason"]:
            named.setdefault(r["reason"], []).append(r["name"])
    return [f"{', '.join(names)}: {reason}" for reason, names in named.items()]


def chain_options_given(args: Any) -> list[str]:
    """The chain-only options (:data:`CHAIN_ONLY`) given other values than their defaults."""
    return [flag for attr, (flag, default) in CHAIN_ONLY.items() if getattr(args, attr, default) != default]
