"""The result of :func:`algid.identify`: estimates, uncertainties, verdicts, history."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..diagnosis.report import location_text
from ..diagnosis.timing import timing_lines
from ..estimator.continuous import PackedParameters, unpack
from ..messages.display import Displayed, number, parameter_rows
from ..model.chain import parameter_names
from ..model.network import Network
from ..recording.noise import NoiseModel
from .impact_fit import fit_line
from .plan import Plan
from .screen import Screened
from .verdicts import Verdict, dof_validity


def _num(v: float):
    return float(v) if math.isfinite(v) else None


class PackedEstimates(PackedParameters):
    """Views shared by every whole-record estimate of the chain (:class:`Identification`, and
    :class:`~.frf_result.FrfIdentification` from FRFs): ``n``, ``boundary``, ``theta``,
    ``sigma`` (3n+1,) and ``verdicts`` are the subclass's fields."""

    @property
    def network(self) -> Network | None:
        """The spring network identified (``boundary`` a Network), None for the chain."""
        return self.boundary if isinstance(self.boundary, Network) else None

    @property
    def names(self) -> list[str]:
        """``m1..mn, c1..cn, k1..k{n+1}`` (a network's ``k1..kS``)."""
        return self.network.parameter_names() if self.network else parameter_names(self.n)

    @property
    def estimate(self) -> np.ndarray:
        """The packed estimates (``theta``), as the estimators name them."""
        return self.theta

    @property
    def sigma_mass(self) -> np.ndarray:
        """One standard deviation of the masses [kg] (n,)."""
        return unpack(self.sigma, self.n)[0]

    @property
    def sigma_damping(self) -> np.ndarray:
        """One standard deviation of the dampings [N s/m] (n,)."""
        return unpack(self.sigma, self.n)[1]

    @property
    def sigma_stiffness(self) -> np.ndarray:
        """One standard deviation of the springs [N/m] (n+1,)."""
        return unpack(self.sigma, self.n)[2]

    @property
    def valid_dof(self) -> np.ndarray:
        """(n,) DOF whose mass, damping and springs are all valid."""
        return dof_validity(self.verdicts, self.n, self.network)

    def modes(self):
        """``(ModalAnalysis, "")`` of the estimated chain with uncertainties from ``sigma``
        (:func:`algid.model.modal.modal_analysis`), or ``(None, reason)`` when a parameter has no
        admissible estimate."""
        from ..model.modal import identification_modes

        key = (self.theta.tobytes(), self.sigma.tobytes())  # computed once for the table and the JSON
        cached = self.__dict__.get("_modes")
        if cached is None or cached[0] != key:
            self.__dict__["_modes"] = cached = (key, identification_modes(self))
        return cached[1]

    def verdict(self, name: str) -> Verdict:
        """The verdict of parameter ``name`` (``"m1"``, ``"k2"``, ...)."""
        return next(v for v in self.verdicts if v.name == name)

    def parameter_lines(self) -> list[str]:
        """The table's line of every parameter: value, one standard deviation, unit and the
        status where it is not ``ok``."""
        lines = []
        for p, v in enumerate(self.verdicts):
            val, sg = self.theta[p], self.sigma[p]
            txt = "       n/a" if not math.isfinite(val) else f"{val:10.5g}"
            sd = "" if not math.isfinite(sg) else f" +- {sg:.2g}"
            flag = "" if v.status == "ok" else f"  [{v.status}]"
            lines.append(f"  {v.name:>4} = {txt}{sd} {self.units[v.name[0]]}{flag}")
        return lines

    def modal_lines(self) -> list[str]:
        """The table's last lines: the modes of the estimates (:meth:`modes`)."""
        modal, why = self.modes()
        if modal is None:
            return [f"modes: n/a ({why})"]
        caveat = [] if self.valid else ["modes of the estimates as they are (not every estimate is valid):"]
        return caveat + [modal.table()]

    def parameters_json(self) -> dict:
        """The JSON keys of the estimates: ``n``, ``boundary``, ``mass`` ... ``sigma_stiffness``,
        ``valid``, ``valid_dof``, ``reasons`` (what :meth:`algid.Chain.from_json` reads; a network's
        ``springs`` in place of ``boundary``, what :meth:`algid.NetworkModel.from_json` reads)."""
        where = {"springs": [list(p) for p in self.network.springs]} if self.network else {"boundary": self.boundary}
        return {
            "n": self.n,
            **where,
            "mass": [_num(v) for v in self.mass],
            "damping": [_num(v) for v in self.damping],
            "stiffness": [_num(v) for v in self.stiffness],
            "sigma_mass": [_num(v) for v in self.sigma_mass],
            "sigma_damping": [_num(v) for v in self.sigma_damping],
            "sigma_stiffness": [_num(v) for v in self.sigma_stiffness],
            "valid": self.valid,
            "valid_dof": [bool(v) for v in self.valid_dof],
            "reasons": self.reasons,
        }

    def parameter_entry(self, p: int, v) -> dict:
        """The JSON entry of packed parameter ``p`` with its verdict ``v``."""
        return {
            "name": v.name,
            "value": _num(self.theta[p]),
            "sigma": _num(self.sigma[p]),
            "status": v.status,
            "valid": v.valid,
            "reason": v.reason or None,
            "force_share": _num(v.share),
            "sigma_force_share": _num(v.sigma_share),
        }

    def modes_json(self) -> dict:
        """``modes`` (one object per mode, or None) and, without modes, ``modes_reason``."""
        modal, why = self.modes()
        return {"modes": modal.to_json()} if modal is not None else {"modes": None, "modes_reason": why}


@dataclass
class Identification(PackedEstimates):
    """Estimates of an n-DOF chain from a whole recording.

    Attributes
    ----------
    n, boundary, dt [s], samples : the recording and the chain.
    plan : the estimator used, its settings and why (:class:`~.plan.Plan`).
    noise : noise model and signal band of the recording (:class:`algid.recording.noise.NoiseModel`).
    theta, sigma : (3n+1,) estimates ``m1..mn, c1..cn, k1..k{n+1}`` [kg, N s/m, N/m] and
        one standard deviation each.
    raw : the estimates before the bias correction; bias : the correction taken off;
    method_bias : the estimator's own error on a noise-free surrogate of the record (in sigma).
    verdicts : one :class:`~.verdicts.Verdict` per parameter.
    time_s, history, history_sigma : estimate history (R rows) and its standard deviation.
    windows : continuous window results aggregated (0 for the single window).
    replicates : bootstrap replicates; motion : "acceleration", or "velocity" or
        "displacement" (accelerations derived from them).
    """

    n: int
    boundary: str
    dt: float
    samples: int
    plan: Plan
    noise: NoiseModel
    theta: np.ndarray
    sigma: np.ndarray
    raw: np.ndarray
    bias: np.ndarray
    method_bias: np.ndarray
    verdicts: list
    time_s: np.ndarray
    history: np.ndarray
    history_sigma: np.ndarray
    windows: int
    replicates: int
    motion: str
    path: Path | None = None
    hum_hz: tuple = ()  #: mains lines notched out of every channel [Hz]
    #: the channels' skew found, and whether it was undone (:meth:`algid.diagnosis.timing.Timing.to_json`)
    channel_timing: dict | None = None
    #: unit labels of m, c, k (:func:`algid.recording.parameter_units`: V/V where the data are volts)
    units: dict = field(default_factory=lambda: {"m": "kg", "c": "N s/m", "k": "N/m"})
    recording_notes: tuple = ()  #: what the reader did (columns ignored, units converted)
    #: samples taken out as far outside their channel's range (:mod:`.screen`)
    screened: Screened = field(default_factory=Screened)
    #: effects estimated with eq. 1 (:mod:`.augmented`): ``effect, location, params, params_std, units, valid, reason``
    effects: list = field(default_factory=list)
    #: the fit check (``gap``, ``noise_floor``, ``explains_record``) and where effects came from (``source``)
    model_fit: dict = field(default_factory=dict)
    #: an impact record's hits, band and residual modes (:class:`algid.recording.transient.Transient`)
    transient: object = None
    #: the diagnosis that fitted the effects (its figures), None without effects
    diagnosis: object = field(default=None, repr=False, compare=False)
    #: why the record gives the chain only up to a common scale ("" when it has one): a
    #: base-excited record without force (:mod:`.base`); theta then holds the chain scaled to k1 = 1
    scale: str = ""
    #: without scale, what the record determines: ``{"k1/m1": {"value", "sigma", "valid"}, ...}``
    ratios: dict = field(default_factory=dict)

    @property
    def valid(self) -> bool:
        """Every DOF and every effect estimated with them valid."""
        return bool(np.all(self.valid_dof)) and all(e["valid"] for e in self.effects)

    @property
    def identified_any(self) -> bool:
        """At least one parameter the record determines (valid or not: an inadmissible or
        misfitting estimate is determined, just not by eq. 1); without scale, a valid ratio."""
        if self.scale:
            return any(r["valid"] for r in self.ratios.values())
        return any(v.status in ("ok", "negligible", "inadmissible", "model_misfit") for v in self.verdicts)

    @property
    def reasons(self) -> list[str]:
        """One line per parameter that is not ``ok`` (``"k3: ..."``); without scale, that line
        and one per ratio that is not valid."""
        if self.scale:
            return [f"{self.scale}: masses, dampings and springs not identifiable"] + [
                f"{name}: not valid" for name, r in self.ratios.items() if not r["valid"]
            ]
        lines = [f"{v.name}: {v.reason}" for v in self.verdicts if v.status != "ok" and v.reason]
        return lines + [f"{e['effect']}: {e['reason']}" for e in self.effects if e["reason"]]

    # ---- display: one-line repr, notebook table (algid.messages.display) -------------------------
    def _display_fields(self) -> dict:
        return {
            "n": self.n,
            "boundary": repr(self.boundary),
            "estimator": repr(self.plan.estimator),
            "samples": self.samples,
            "dt_s": number(self.dt),
            "valid": f"{sum(v.valid for v in self.verdicts)}/{len(self.verdicts)} parameters",
        }

    def _display_parameters(self) -> list[tuple]:
        return parameter_rows(self.names, self.theta, self.sigma, getattr(self, "units", None))

    __repr__ = Displayed.__repr__
    _repr_html_ = Displayed._repr_html_

    # ---- output ------------------------------------------------------------------------
    def to_json(self) -> dict:
        """The JSON document of ``algid identify``."""
        n = self.n
        params = [
            {
                **self.parameter_entry(p, v),
                "bias_corrected": _num(self.bias[p]),
                "method_bias": _num(self.method_bias[p]),
            }
            for p, v in enumerate(self.verdicts)
        ]
        doc = {
            **self.parameters_json(),
            "parameters": params,
            "estimator": self.plan.estimator,
            "estimator_reason": self.plan.reason,
            "plan": self.plan.to_json(),
            "window_results": self.windows,
            "bootstrap_replicates": self.replicates,
            "samples": self.samples,
            "dt_s": self.dt,
            "duration_s": self.samples * self.dt,
            "motion": self.motion,
            "noise_model": self.noise.to_json(),
            "mains_hum_removed_hz": list(self.hum_hz),
            "channel_timing": self.channel_timing,
            "units": dict(self.units),
            "recording_notes": list(self.recording_notes),
            "screened": self.screened.to_json(),
            "effects": [{k: v for k, v in e.items()} for e in self.effects],
            "transient": self.transient.to_json() if self.transient is not None else None,
        }
        if self.model_fit:
            doc["model_fit"] = dict(self.model_fit)
        if self.scale:
            for key in ("mass", "damping", "stiffness", "sigma_mass", "sigma_damping", "sigma_stiffness"):
                doc[key] = [None] * len(doc[key])
            for p in params:
                p["value"] = p["sigma"] = None
            doc["scale"] = self.scale
            doc["ratios"] = {name: dict(r) for name, r in self.ratios.items()}
        doc.update(self.modes_json())
        if n == 1 and self.boundary == "fixed" and self.verdicts[-1].status == "not_separable":
            doc["note"] = "n = 1 with walls: only k1 + k2 is identifiable; it is reported as stiffness[0]"
        if self.motion != "acceleration":
            doc["note_accel"] = f"accelerations derived from {self.motion}s by 5-point differentiation"
        return doc

    def to_frame(self):
        """The estimates as a :class:`pandas.DataFrame`, one row per parameter (index
        ``m1..``): ``value``, ``sigma``, ``unit``, ``status``, ``valid``, ``reason``."""
        from ..recording.core import require

        pd = require("pandas", "pandas", "DataFrames")
        rows = {
            "value": self.theta,
            "sigma": self.sigma,
            "unit": [self.units[v.name[0]] for v in self.verdicts],
            "status": [v.status for v in self.verdicts],
            "valid": [v.valid for v in self.verdicts],
            "reason": [v.reason or "" for v in self.verdicts],
        }
        return pd.DataFrame(rows, index=pd.Index([v.name for v in self.verdicts], name="parameter"))

    def write_trace(self, path: Path) -> None:
        """History CSV ``t,m1..,c1..,k1..,sigma_m1..,sigma_c1..,sigma_k1..,valid``: one row per
        history instant (every sample for the single window; window-result instants for the
        continuous estimator), ``t`` the end of the data described [s]."""
        names = self.names
        header = ["t"] + names + [f"sigma_{k}" for k in names] + ["valid"]
        rows = min(self.history.shape[0], self.history_sigma.shape[0])
        H, S, t = self.history[-rows:], self.history_sigma[-rows:], self.time_s[-rows:]
        valid_now = np.all(np.isfinite(H[:, : 2 * self.n]), axis=1)
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(",".join(header) + "\n")
            for r in range(rows):
                vals = [t[r]] + list(H[r]) + list(S[r])
                fields = ["" if not math.isfinite(v) else repr(float(v)) for v in vals]
                fields.append(str(int(valid_now[r] and (r < rows - 1 or self.valid))))
                fh.write(",".join(fields) + "\n")

    def summary(self) -> str:
        """The table ``algid identify`` prints."""
        lines = [f"n = {self.n}, {self.plan.estimator} estimator ({self.plan.reason})"]
        if self.plan.estimator == "continuous":
            lines.append(
                f"  windows of {self.plan.window_s:.3g} s ({self.plan.window_basis}), prefilter "
                + (f"{self.plan.prefilter_hz:.3g} Hz" if self.plan.prefilter_hz > 0 else "off")
                + f", {self.windows} window results"
            )
        if self.screened.count:
            lines.append(f"  {self.screened.line()}")
        lines += timing_lines(self.channel_timing)
        if self.transient is not None:
            lines.append(f"  {self.transient.line()}")
            if self.model_fit.get("check") == "output error":
                lines.append(f"  {fit_line(self.model_fit)}")
        lines += self.ratio_lines() if self.scale else self.parameter_lines()
        lines += effect_lines(self.effects, self.model_fit.get("source", ""))
        lines.append(f"valid: {self.valid} (DOF: {', '.join(str(bool(x)) for x in self.valid_dof)})")
        return "\n".join(lines + self.modal_lines())

    def ratio_lines(self) -> list[str]:
        """Without a scale (a base-excited record without force): the line of every ratio."""
        lines = [f"  {self.scale}:"]
        for name, r in self.ratios.items():
            flag = "" if r["valid"] else "  [not valid]"
            unit = "1/s" if name[0] == "c" else "1/s^2"
            lines.append(f"  {name:>7} = {r['value']:10.5g} +- {r['sigma']:.2g} {unit}{flag}")
        return lines

    def modal_lines(self) -> list[str]:
        """The modes; without a scale they depend on the ratios alone."""
        modal, _ = self.modes()
        if modal is None or not self.scale:
            return super().modal_lines()
        ok = all(r["valid"] for r in self.ratios.values())
        say = "every ratio valid" if ok else "not every ratio is valid"
        return [f"modes (they depend on the ratios alone; {say}):", modal.table()]


def effect_lines(effects: list[dict], source: str) -> list[str]:
    """The table lines of the effects estimated with the chain, after where they came from."""
    lines = [f"  {source}"] if source else []
    for e in effects:
        where = location_text(e["location"])
        for k, value in e["params"].items():
            sd = e["params_std"].get(k, math.nan)
            flag = "" if e["valid"] else "  [not valid]"
            txt = f"{value:10.5g}" + (f" +- {sd:.2g}" if math.isfinite(sd) else "")
            lines.append(f"  {e['effect']} ({where}) {k} = {txt} {e['units'].get(k, '')}{flag}")
    return lines
