"""The result of identifying the chain from measured FRFs (:func:`.frf_fit.identify_frf`):
the table, JSON and modes of :class:`~.result.Identification`, with the FRFs in place of
the recording."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..messages.display import Displayed, number, parameter_rows
from ..recording.frf_file import FrfData
from ..recording.units import parameter_unit_labels
from .result import PackedEstimates, _num

ESTIMATOR_REASON = "FRFs given: eq. 1 fitted in frequency (equation error, then output error)"


@dataclass
class FrfIdentification(PackedEstimates):
    """Estimates of an n-DOF chain from FRFs.

    Attributes
    ----------
    n, boundary : the chain; data : the FRFs (:class:`~algid.recording.frf_file.FrfData`).
    theta, sigma : (3n+1,) estimates ``m1..mn, c1..cn, k1..k{n+1}`` [kg, N s/m, N/m] and one
        standard deviation each; covariance : (3n+1, 3n+1) theirs (zero rows for known ones).
    equation_error : the linear equation-error estimate the output-error fit starts from.
    verdicts : one :class:`~.verdicts.Verdict` per parameter; shares : per parameter, the
        share of its equations' largest term a unit of it stands for.
    iterations : Gauss-Newton iterations; model_fit : the fit check
        (:func:`.frf_fit.fit_check`).
    """

    n: int
    boundary: str
    data: FrfData
    theta: np.ndarray
    sigma: np.ndarray
    covariance: np.ndarray
    equation_error: np.ndarray
    verdicts: list
    shares: np.ndarray
    iterations: int
    model_fit: dict = field(default_factory=dict)

    @property
    def units(self) -> dict:
        """Unit labels of m, c, k (kg, N s/m, N/m for SI FRFs)."""
        return parameter_unit_labels(self.data.units, self.data.motion)

    @property
    def valid(self) -> bool:
        """Every DOF valid."""
        return bool(np.all(self.valid_dof))

    @property
    def identified_any(self) -> bool:
        """At least one parameter the FRFs determine (valid or not)."""
        return any(v.status in ("ok", "negligible", "inadmissible", "model_misfit") for v in self.verdicts)

    @property
    def reasons(self) -> list[str]:
        """One line per parameter that is not ``ok`` (``"k3: ..."``)."""
        return [f"{v.name}: {v.reason}" for v in self.verdicts if v.status != "ok" and v.reason]

    def chain(self):
        """The estimated :class:`algid.Chain` (:meth:`algid.Chain.from_packed`)."""
        from ..model.chain import Chain

        return Chain.from_packed(self.theta, self.n, self.boundary)

    def _display_fields(self) -> dict:
        f = self.data.frequency_hz
        return {
            "n": self.n,
            "boundary": repr(self.boundary),
            "quantity": self.data.quantity,
            "lines": f.size,
            "band_hz": f"{number(f[0], 4)}-{number(f[-1], 4)}",
            "valid": f"{sum(v.valid for v in self.verdicts)}/{len(self.verdicts)} parameters",
        }

    def _display_parameters(self) -> list[tuple]:
        return parameter_rows(self.names, self.theta, self.sigma, self.units)

    __repr__ = Displayed.__repr__
    _repr_html_ = Displayed._repr_html_

    def to_json(self) -> dict:
        """The JSON document of ``algid identify`` on FRFs: the keys of
        :meth:`~.result.Identification.to_json` that apply, and ``frf`` (what was fitted)."""
        d = self.data
        params = [
            {**self.parameter_entry(p, v), "equation_error": _num(self.equation_error[p])}
            for p, v in enumerate(self.verdicts)
        ]
        return {
            **self.parameters_json(),
            "parameters": params,
            "estimator": "frf",
            "estimator_reason": ESTIMATOR_REASON,
            "frf": {
                "quantity": d.quantity,
                "unit": d.unit,
                "lines": int(d.frequency_hz.size),
                "band_hz": [float(d.frequency_hz[0]), float(d.frequency_hz[-1])],
                "response_dof": d.response_dof.tolist(),
                "force_dof": d.force_dof.tolist(),
                "coherence": d.coherence is not None,
                "iterations": self.iterations,
            },
            "units": dict(self.units),
            "recording_notes": list(d.notes),
            "model_fit": {k: (_num(v) if isinstance(v, float) else v) for k, v in self.model_fit.items()},
            **self.modes_json(),
        }

    def summary(self) -> str:
        """The table ``algid identify`` prints."""
        d, fit = self.data, self.model_fit
        f = d.frequency_hz
        lines = [
            f"n = {self.n}, FRF fit ({d.quantity}, {f.size} lines {f[0]:.4g}-{f[-1]:.4g} Hz, "
            f"forces at DOF {', '.join(map(str, d.force_dof))})"
        ]
        if fit:
            ratio = fit["ratio"]
            lines.append(
                f"  residual / noise of the FRFs = {ratio:.3g}" if math.isfinite(ratio) else "  residual / noise: n/a"
            )
        lines += self.parameter_lines()
        lines.append(f"valid: {self.valid} (DOF: {', '.join(str(bool(x)) for x in self.valid_dof)})")
        return "\n".join(lines + self.modal_lines())
