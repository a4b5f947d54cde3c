"""JSON and terminal renderings of a :class:`~algid.diagnosis.engine.Diagnosis`."""

from __future__ import annotations

import math

import numpy as np

from ..model.network import Network
from .candidates import MAIN_PARAM
from .core import METRIC, METRIC_FORCE
from .corrected import corrected_model, linear_model
from .timing import timing_lines
from .units import SI


def json_safe(x):
    """JSON-safe floats (NaN/inf -> None)."""
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return x if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


def to_json(d) -> dict:
    """The issue-6 JSON: ``effect, location, params, gap_before, gap_after, metric,
    ranking`` (each ranking entry ``effect, location, params, gap_after``), plus
    ``params_std`` (1-sigma, delete-a-group jackknife over the folds), the significance of
    every ranked candidate, the signal band and the full-band gaps (``*_fullband``), the
    linear model, the location indicators and timings; ``units``, the unit of every number
    by its name (``m``, ``c``, ``k`` of the linear model, the signals, every effect
    parameter: ``k_cubic`` in ``N/m^3``, or ``V/V^3`` for forces and displacements in volts),
    ``recording_units`` (by role, as the recording declares them) and ``recording_notes``;
    ``corrected_model``, the chain refitted with the reported effect (:mod:`.corrected`)."""
    ranking = []
    for s in d.ranking:
        ranking.append(
            {
                "effect": s.fit.effect,
                "location": s.fit.location,
                "params": s.fit.params,
                "gap_after": s.gap_after,
                "gap_after_fullband": s.gap_after_full,
                "params_std": s.fit.params_std,
                "z_noise": s.z,
                "t_stat": s.t_stat,
                "rel_reduction": s.rel_reduction,
                "physical": s.physical,
                "significant": s.significant,
            }
        )
    lin = d.lin
    out = {
        "effect": d.effect,
        "location": d.location,
        "params": d.params,
        "gap_before": d.gap_before,
        "gap_after": d.gap_after,
        "metric": METRIC,
        "gap_before_fullband": d.gap_before_full,
        "gap_after_fullband": d.gap_after_full,
        "gap_before_force": d.extra.get("force", {}).get("gap_before"),
        "gap_after_force": d.extra.get("force", {}).get("gap_after"),
        "metric_force": METRIC_FORCE,
        "model": d.extra["model"].to_json() if "model" in d.extra else None,
        "combination": _combination_json(d.extra.get("combination")),
        "equation_form": d.extra.get("form", "acceleration"),
        "mains_hum_removed_hz": d.extra.get("mains_hz", []),
        "channel_timing": d.extra.get("timing"),
        "band": d.band.to_json()
        | {
            "window_bins_kept": int(d.P.band_mask.sum()),
            "window_bins": int(d.P.band_mask.size),
            "white_noise_fraction": d.P.band_fraction,
        },
        "ranking": ranking,
        "params_std": d.params_std,
        "main_param": MAIN_PARAM.get(d.effect),
        "corrected_model": corrected_model(d),
        "linear_model": {
            **linear_model(d),
            "unforced_dofs": [i + 1 for i, f in enumerate(lin.forced) if not f],
            "natural_frequencies_hz": d.extra.get("natural_hz", []),
        },
        "analysis": {
            "windows": d.P.nw,
            "window_s": d.P.L * d.P.dt,
            "skipped_s": d.P.skip * d.P.dt,
            "folds": d.P.nfolds,
            "noise_floor": d.extra.get("noise_floor"),
            "noise_floor_fullband": d.extra.get("noise_floor_full"),
            "explained_excess": d.extra.get("explained_excess"),
        },
        "where": d.where,
        "timings_s": d.timings,
        "units": dict(d.units),
        "recording_units": dict(d.recording_units),
        "recording_notes": list(d.recording_notes),
    }
    return json_safe(out)


def _combination_json(s) -> dict | None:
    """The reported combination of effects (``None`` if none beats the best single one)."""
    if s is None:
        return None
    parts = [
        {"effect": eff, "location": loc, "params": s.fit.params[eff], "params_std": s.fit.params_std[eff]}
        for eff, loc in zip(s.fit.effect.split("+"), s.fit.location["parts"])
    ]
    return {"effects": parts, "gap_after": s.gap_after, "gap_after_fullband": s.gap_after_full, "z_noise": s.z}


def _chain_lines(cm: dict | None, units: dict, title: str, indent: str = "  ") -> list[str]:
    """A chain model (:mod:`.corrected`) under ``title``, one line per DOF, values +- one sigma."""
    if cm is None:
        return []
    n = cm["n"]

    def val(x, s):
        return "n/a" if x is None else f"{x:.5g}" + ("" if s is None else f" +- {s:.2g}")

    out = [f"{title} (m [{units['m']}], c [{units['c']}], springs [{units['k']}]):"]
    net = Network(n, cm["springs"]) if "springs" in cm else None
    for i in range(n):
        on = [s - 1 for s, _, _ in net.incident(i + 1)] if net else [j for j in (i, i + 1) if j < n or i == n - 1]
        springs = "  ".join(f"k{j + 1}={val(cm['stiffness'][j], cm['sigma_stiffness'][j])}" for j in on)
        m, c = val(cm["mass"][i], cm["sigma_mass"][i]), val(cm["damping"][i], cm["sigma_damping"][i])
        out.append(f"{indent}DOF {i + 1}: m={m}  c={c}  {springs}")
    return out


def _z(z: float) -> str:
    """A candidate's significance, ``   n/a`` where it has none (its fit did not move the gap)."""
    return f"{z:6.1f}" if np.isfinite(z) else "   n/a"


def _fmt_params(params: dict, std: dict | None = None, units: dict = SI) -> str:
    parts = []
    for k, v in params.items():
        s = f"{k} = {v:.4g}" if np.isfinite(v) else f"{k} = n/a"
        if std and std.get(k) is not None and np.isfinite(std[k]):
            s += f" +- {std[k]:.2g}"
        parts.append(s + f" {units.get(k, '')}".rstrip())
    return ", ".join(parts)


def _units_lines(d) -> list[str]:
    """The units the numbers below are in, built from those the recording declares."""
    rec = ", ".join(f"{role} [{unit}]" for role, unit in d.recording_units.items() if role != "time")
    names = {"m": "m", "c": "c", "k": "springs", "displacement": "x", "velocity": "v", "acceleration": "a"}
    return [
        f"Units (the recording's: {rec or 'SI'}):",
        "  " + "   ".join(f"{label} [{d.units[key]}]" for key, label in names.items()),
    ]


def location_text(loc) -> str:
    """``DOF 1`` or ``spring 2`` of an effect's location (``""`` without one)."""
    if not loc:
        return ""
    ((k, v),) = loc.items()
    return f"{'DOF' if k == 'dof' else 'spring'} {v}"


def to_text(d, source: str = "") -> str:
    """Human-readable report for the terminal."""
    P, lin = d.P, d.lin
    L = []
    L.append(f"algid diagnose{': ' + source if source else ''}")
    ends = f"{P.boundary} right end" if P.chain else f"a network of {P.network.size} springs"
    L.append(
        f"  {P.n} DOF, {P.a_full.shape[0]} samples at {1 / P.dt:g} Hz ({P.duration:.3g} s), "
        f"{ends}; {P.nw} windows of {P.L * P.dt:.3g} s in {P.nfolds} folds"
    )
    L.append("")
    L.extend(_units_lines(d))
    L.extend(timing_lines(d.extra.get("timing")))
    L.append("")
    kind = "chain" if P.chain else "network"
    L.extend(_chain_lines(linear_model(d), d.units, f"Linear {kind}, the windowed equation-error fit", "  "))
    if d.effect != "none":
        L.append(f"  (`algid identify` reports this fit, every value model_misfit: the record is not a linear {kind})")
    if not lin.forced.all():
        L.append("  a DOF without force: no scale in this fit (n/a); `algid identify` carries it along the springs")
    nat = d.extra.get("natural_hz", [])
    if nat:
        L.append("  natural frequencies [Hz]: " + ", ".join(f"{f:.3g}" for f in nat))
    model = d.extra.get("model")
    if model is not None:
        L.append(
            f"  model: {model.verdict}"
            + (f" (the linear {kind} is a model of the record)" if model.verdict == "chain" else "")
        )
        for r in model.reasons:
            L.append(f"    {r}")
    L.append("")
    shrink = d.gap_before / d.gap_after if d.gap_after > 0 else float("inf")
    b = d.band
    L.append(
        f"Gap (normalised RMS acceleration equation error on withheld windows, in the signal band "
        f"0-{b.f_hi:.4g} Hz of 0-{b.nyquist:.4g}; full band in brackets):"
    )
    exc = f"{b.f_exc:.3g} Hz" if np.isfinite(b.f_exc) else "none found"
    modes = f", highest natural frequency {b.f_modes:.3g} Hz" if np.isfinite(b.f_modes) else ""
    L.append(f"  band: signal up to {exc} ({b.source}){modes}; {P.band_fraction:.0%} of the white sensor noise")
    L.append(f"  linear model        {d.gap_before:.4g}  [{d.gap_before_full:.4g}]")
    fg = d.extra.get("force", {})
    if fg.get("gap_before") is not None and np.isfinite(fg["gap_before"]):
        L.append(
            f"  force-domain gap    {fg['gap_before']:.4g} -> {fg['gap_after']:.4g} "
            "(RMS force-equation error / RMS force, withheld, in band)"
        )
    nf = d.extra.get("noise_floor")
    if nf is not None:
        L.append(f"  sensor-noise floor  {nf:.4g}  [{d.extra.get('noise_floor_full', float('nan')):.4g}]")
    if d.effect in ("none", "unknown"):
        L.append(
            f"  diagnosis: {d.effect.upper()}"
            + (
                " - the linear model explains the data within noise"
                if d.effect == "none"
                else " - the gap is real but no candidate effect explains it"
            )
        )
    else:
        shrink_f = d.gap_before_full / d.gap_after_full if d.gap_after_full > 0 else float("inf")
        L.append(
            f"  with {d.effect} at {location_text(d.location)}: {d.gap_after:.4g} ({shrink:.3g}x smaller)  "
            f"[{d.gap_after_full:.4g}, {shrink_f:.3g}x]"
        )
        L.append(f"  fitted: {_fmt_params(d.params, d.params_std, d.units)}")
        L.extend(_chain_lines(corrected_model(d), d.units, "  chain with the effect", "    "))
        combo = d.extra.get("combination")
        if combo is not None:
            parts = " + ".join(
                f"{eff} at {location_text(loc)} ({_fmt_params(combo.fit.params[eff], units=d.units)})"
                for eff, loc in zip(combo.fit.effect.split("+"), combo.fit.location["parts"])
            )
            sh = d.gap_before / combo.gap_after if combo.gap_after > 0 else float("inf")
            L.append(f"  together: {parts}: {combo.gap_after:.4g} ({sh:.3g}x smaller)")
    L.append("")
    w = d.where
    if w:
        L.append("Where the linear model fails:")
        L.append(
            "  per DOF equation (withheld NRMS / noise floor): "
            + ", ".join(f"{p['dof']}: {p['gap']:.3g}/{p['noise_floor']:.2g}" for p in w["per_dof"])
        )
        ti = w["time"]
        L.append(
            f"  in time: window gap max/min {ti['max_over_min']:.3g}, trend over the record {ti['relative_trend']:+.0%}"
        )
        fr = w["frequency"]
        if fr.get("peak_hz") is not None:
            L.append(
                f"  in frequency: excess over the noise floor peaks at {fr['peak_hz']:.3g} Hz "
                f"(80 % of it in {fr['band_80pct_hz'][0]:.3g}-{fr['band_80pct_hz'][1]:.3g} Hz)"
            )
        am = w["amplitude"]
        sp = max(am["springs"], key=lambda s: s["explained"])
        ms = max(am["masses"], key=lambda s: s["explained"])
        L.append(
            f"  against amplitude: deformation of spring {sp['spring']} explains {sp['explained']:.0%} of "
            f"the error, velocity of DOF {ms['dof']} {ms['explained']:.0%}"
        )
        L.append("")
    L.append("Candidates (withheld gap; * = beyond noise):")
    for s in d.ranking[:10]:
        mark = "*" if s.significant else " "
        L.append(
            f"  {mark} {s.fit.effect:<18s} {location_text(s.fit.location):<9s} {s.gap_after:.4g}  "
            f"z={_z(s.z)}  {_fmt_params(s.fit.params, units=d.units)}"
        )
    if len(d.ranking) > 10:
        L.append(f"  ... {len(d.ranking) - 10} more in the JSON")
    L.append(f"({d.timings.get('total', float('nan')):.2f} s)")
    return "\n".join(L)
