"""Python face of the continuous estimator: ``ContinuousEstimator(n, dt, ...)``.

Continuous operation of the algebraic estimator for long, noisy records (the per-sample work
runs in ``cpp/include/algid/continuous_estimator.hpp`` and ``weak_form.hpp``):

* K staggered windows of length L (``stagger``, ``window_s``): a window result every L/K.
  By default (``method="weak_form"``) each window is the generalised least-squares solution
  of all its weak-form rows (eq. 1 against sin^4-tapered tones up to ``band_hz``, no initial
  conditions), weighted by their noise covariance and corrected for the bias that noise in
  the regressors causes (noise level estimated from the signals, or given); with
  ``method="algebraic"`` each window is a ChainEstimator behind the same Butterworth
  low-pass on accelerations and forces (default fs/20);
* the running estimate: the sum of the weak-form windows' normal equations (the windows
  combined by their information), or per parameter the mean of block medians of the window
  results (algebraic windows, ``joint=False``), with a one-sigma uncertainty;
* a change detector (step test on the median robust z-score of the last 2K+1 window
  results; drift test, a CUSUM of block medians) that restarts the aggregation of the
  parameter that changed and reports a change event.

``run()`` takes whole signals (GIL released); ``update()`` one sample.
"""

from __future__ import annotations

import operator
from dataclasses import dataclass

import numpy as np

from .. import _core
from ..messages.display import Displayed, number, parameter_rows, validity
from ..model.chain import parameter_names, spring_columns
from . import Status, as_record, as_sample, config_fields, dofs, estimator_class, make_config, spring_index

ChangeKind = _core.ChangeKind
#: Configuration of a :class:`ContinuousEstimator` (the C++ ``ContinuousConfig``; its defaults,
#: benchmarked in bench/continuous.py, are C++'s).
ContinuousConfig = _core.ContinuousConfig


def config_dict(config) -> dict:
    """The fields of a configuration struct as a dict (``config_dict(ContinuousConfig())``: the
    defaults)."""
    return {name: getattr(config, name) for name in config_fields(config)}


@dataclass(frozen=True)
class ChangeEvent:
    """The aggregation of one parameter restarted because its window results changed level."""

    sample: int  #: index of the sample whose update raised it (0-based, since construction/reset)
    time_s: float  #: ``sample * dt`` [s]
    param: int  #: index into :attr:`ContinuousEstimator.names`
    name: str  #: ``"m1"``, ``"c2"``, ``"k3"``, ...
    kind: str  #: ``"step"`` or ``"drift"``
    before: float  #: running estimate before [kg, N s/m or N/m]
    after: float  #: running estimate right after


def unpack(vec: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass, damping and spring views ``(n,), (n,), (n+1,)`` of a packed vector
    ``m1..mn, c1..cn, k1..k{n+1}`` (the order of :func:`parameter_names`)."""
    return vec[:n], vec[n : 2 * n], vec[2 * n :]


def finite_dofs(vec: np.ndarray, n: int, boundary: str) -> np.ndarray:
    """(n,) per DOF: the mass, the damping and every spring its equation identifies (see
    :func:`algid.model.chain.spring_columns`) are finite in the packed vector ``vec``."""
    m, c, k = unpack(vec, n)
    return np.array(
        [
            np.isfinite(m[e]) and np.isfinite(c[e]) and all(np.isfinite(k[j - 1]) for j, _ in cols)
            for e, cols in enumerate(spring_columns(n, boundary))
        ]
    )


class PackedParameters:
    """Mass, damping and stiffness views of a packed ``estimate`` vector
    ``m1..mn, c1..cn, k1..k{n+1}`` (the order of :func:`parameter_names`)."""

    n: int

    @property
    def mass(self) -> np.ndarray:
        """Masses m_i [kg] (n,)."""
        return unpack(self.estimate, self.n)[0]

    @property
    def damping(self) -> np.ndarray:
        """Dampings c_i [N s/m] (n,)."""
        return unpack(self.estimate, self.n)[1]

    @property
    def stiffness(self) -> np.ndarray:
        """Springs k_1..k_{n+1} [N/m] (n+1,)."""
        return unpack(self.estimate, self.n)[2]

    def spring(self, j: int) -> float:
        """Spring ``k_j`` [N/m], ``j`` 1-based (1..n+1) as in :attr:`names` and the JSON."""
        return float(self.stiffness[spring_index(j, self.n)])


class _ScheduleView:
    """Read-only views of a C++ continuous estimator's schedule and sensor checks (``_impl``)."""

    _impl: object

    @property
    def dropouts(self) -> dict:
        """Acceleration dropouts seen so far (stuck or clipped channels, whose samples were
        discarded: status ``DROPOUT``): ``samples``, ``runs``, the ``last`` run's kind
        (``"stuck"``, ``"clipped"`` or ``None``) and its ``channel`` (1-based DOF, or None)."""
        kind = self._impl.last_dropout.name.lower()
        channel = int(self._impl.dropout_channel)
        return {
            "samples": int(self._impl.dropout_samples),
            "runs": int(self._impl.dropout_runs),
            "last": None if kind == "none" else kind,
            "channel": None if channel < 0 else channel + 1,
        }

    @property
    def hop_samples(self) -> int:
        """Samples between two window results."""
        return int(self._impl.hop_samples)

    @property
    def noise_rms(self) -> np.ndarray:
        """Noise RMS per channel used by the weak-form windows (accelerations then forces,
        (2n,); estimated unless given; -1 with algebraic windows)."""
        return np.asarray(self._impl.noise_rms)

    @property
    def settle_samples(self) -> int:
        """Samples skipped after a (re)start while the prefilter settles."""
        return int(self._impl.settle_samples)

    @property
    def prefilter_hz(self) -> float:
        """Prefilter cut-off in force [Hz] (0: off)."""
        return float(self._impl.prefilter_hz)

    @property
    def window_samples(self) -> int:
        """Window length M [samples]."""
        return int(self._impl.window_samples)


class ContinuousEstimator(Displayed, _ScheduleView, PackedParameters):
    """Continuous algebraic estimator of an n-DOF chain: restarted staggered windows, a running
    estimate with uncertainty per parameter, change events.

    Names as :class:`algid.ChainEstimator`'s (``reset``, ``valid`` per DOF, ``ready``, ``sample``,
    ``time_s``); positions 0-based, parameter names (``k2``) and :meth:`spring` 1-based.

    Parameters
    ----------
    n : int
        Number of DOF, any n >= 1.
    dt : float
        Sample period [s].
    boundary : {"fixed", "free"}, optional
        Right end: a wall (k_{n+1} identified, the default) or free (k_{n+1} = 0 known).
    config : ContinuousConfig, optional
        A whole configuration; ``dt``, ``boundary`` and ``options`` override its fields.
    **options
        Fields of :class:`ContinuousConfig` (defaults: ``ContinuousConfig()``), listed below.

    Other Parameters
    ----------------
    method : {"weak_form", "algebraic"}
        Window results: GLS over all weak-form rows with bias compensation (default), or the
        paper's exactly determined algebraic windows behind the prefilter.
    window_s : float
        Window length L [s]; -1 (default): 0.5 (weak form), 0.3 (algebraic).
    stagger : int
        Windows in flight K (1..4), started L/K apart (default 4).
    block : int
        Window results per block median (default 16, at most 64).
    confirm : int
        Window results in the step test; 0 = 2K+1 (default).
    step_threshold : float
        Step test threshold on the median robust z-score (default 6).
    cusum_reference, cusum_threshold, cusum_clip : float
        Drift test: CUSUM reference k, alarm level h and clip, in block-median sigmas
        (defaults 0.75, 5, 4).
    min_relative_spread : float
        Floor of the per-window spread relative to the estimate (default 0.01: the step test
        needs a change of at least ``step_threshold`` x 1 %; at high SNR a weakly excited
        stretch of signal biases a few consecutive windows by a few percent, which must not
        count as a change).
    min_windows : int
        Window results since a restart before the tests are armed (default 8).
    overlap_efficiency : float
        Independent fraction of the staggered window results in the per-parameter track (its
        uncertainty, the drift test's scale); -1 (default): 0.25 weak form, 0.5 algebraic.
    joint_efficiency : float
        Weak form: sigma = sqrt(diag(N^-1) / joint_efficiency) (default 0.3).
    long_window_s : float
        Weak form: length [s] of a second, longer set of windows with a joint sum of its own;
        each parameter is reported from the joint sum (short or long windows) with the smaller
        uncertainty; -1 (default): three times ``window_s``; 0: none.
    horizon_s : float
        Forgetting time constant of the block mean [s]; 0 = none (default).
    band_hz : float
        Weak form: highest test-function frequency [Hz]; -1 = fs/20 (default).
    accel_noise, force_noise : float
        Weak form: RMS of the white noise on the accelerations [m/s^2] and forces [N]; -1 =
        estimated from the fourth differences of the signals (default).
    bias_compensation : bool
        Weak form: subtract the regressor-noise term from the normal equations (default True).
    gls : bool
        Weak form: weight the rows by their noise covariance at the running estimate (True).
    joint : bool
        Weak form: report the solution of the summed window normal equations (True), else the
        mean of block medians.
    prefilter_hz : float
        Algebraic windows: Butterworth low-pass applied alike to accelerations and forces [Hz];
        -1 = fs/20 (default), 0 = off. Eq. 1 is LTI, so the filtered signals obey it with the
        same parameters while the out-of-band noise (the cause of the noise bias) is removed.
        Set it just above the band of the response for the best accuracy.
    prefilter_order : int
        2 or 4 (default).
    detect : bool
        Run the change detector (default True).
    amortize : bool
        Spread the per-parameter aggregation over the samples between window results.
    min_samples : int
        Samples since a window's start before its solution is trusted.
    min_hadamard : float
        Lowest equilibrated Hadamard ratio trusted (each window's validity rule).
    stuck_samples, clip_samples : int
        An acceleration that has moved, then repeats one value for ``stuck_samples`` samples
        (default 16), or its largest or smallest value so far for ``clip_samples`` (default 3),
        is a dropout: discarded like a NaN (:attr:`dropouts`); 0 = off.

    Notes
    -----
    Threads: one estimator serves one thread at a time; a call on an object whose ``run()``
    is in progress in another thread raises ``RuntimeError``.
    """

    def __init__(
        self,
        n: int,
        dt: float | None = None,
        boundary: str | None = None,
        config: ContinuousConfig | None = None,
        **options,
    ) -> None:
        n = dofs(n)
        if dt is None and config is None:
            raise TypeError("ContinuousEstimator needs dt (or a config)")
        cfg = make_config(config if config is not None else ContinuousConfig(), dt, boundary, options)
        self._impl = estimator_class("Continuous", n)(cfg, n)
        self.n, self.dt, self.boundary = n, float(cfg.dt), str(cfg.boundary)
        #: the configuration in force, as a dict
        self.options = config_dict(cfg)
        #: parameter names in estimate order
        self.names = parameter_names(n)

    # -- per sample ---------------------------------------------------------------------------
    def update(self, accel, force) -> Status:
        """Consume one simultaneous sample: accelerations [m/s^2] and forces [N], shape (n,).
        Change events raised by this sample are in :meth:`events`."""
        a, u = as_sample(accel, force, self.n)
        return Status(self._impl.update(a, u))

    def events(self) -> list[ChangeEvent]:
        """Change events raised by the last :meth:`update`."""
        return [self._event(*e) for e in self._impl.events()]

    def reset(self) -> None:
        """Forget everything; the next sample starts a new schedule."""
        self._impl.reset()

    @property
    def estimate(self) -> np.ndarray:
        """Running estimates (3n+1,) in :attr:`names` order [kg, N s/m, N/m] (NaN before the
        first window result)."""
        return self._impl.estimate

    @property
    def sigma(self) -> np.ndarray:
        """One-sigma statistical uncertainty of :attr:`estimate` (noise-induced bias excluded)."""
        return self._impl.sigma

    @property
    def valid(self) -> np.ndarray:
        """(n,) per DOF: every parameter of its equation has a finite running estimate."""
        return finite_dofs(self.estimate, self.n, self.boundary)

    @property
    def ready(self) -> bool:
        """Every DOF :attr:`valid`: every identified parameter has an estimate."""
        return bool(self._impl.ready)

    @property
    def last_window(self) -> np.ndarray:
        """The latest window result (3n+1,)."""
        return self._impl.last_window

    @property
    def window_results(self) -> int:
        """Window results harvested so far."""
        return int(self._impl.window_results)

    def since_restart(self, param: int) -> int:
        """Window results aggregated into parameter ``param`` since its last restart."""
        return int(self._impl.since_restart(int(param)))

    @property
    def screened_windows(self) -> int:
        """Window results kept out of the joint estimate by ``misfit_ratio`` so far (weak form)."""
        return int(self._impl.screened_windows)

    def window_spread(self, param: int) -> float:
        """Per-window spread (1.4826 MAD) of parameter ``param`` [its units]."""
        return float(self._impl.window_spread(int(param)))

    # -- whole records ------------------------------------------------------------------------
    def run(self, accel, force, stride: int = 1) -> dict:
        """Feed a whole record through the C++ loop (GIL released).

        Parameters
        ----------
        accel, force : array_like, shape (T, n)
            Accelerations [m/s^2] and forces [N] sampled simultaneously every ``dt``.
        stride : int
            Keep every ``stride``-th row of the estimate histories (memory; events and window
            results are never decimated).

        Returns
        -------
        dict with
            ``status`` (T,); ``sample`` (R,) sample index of each history row, ``time_s`` (R,);
            ``estimate``, ``sigma`` (R, 3n+1) running estimates and uncertainties;
            ``mass``, ``damping`` (R, n), ``stiffness`` (R, n+1) views of ``estimate``;
            ``events``: list of :class:`ChangeEvent`; ``event_sample``, ``event_param``,
            ``event_kind`` (1 step, 2 drift), ``event_before``, ``event_after`` as arrays;
            ``windows`` (W, 3n+1) every window result, ``window_variance`` (W, 3n+1) its
            variance (weak form with GLS weights, else NaN), ``window_sample`` (W,) the sample
            at which it was harvested and ``window_misfit`` (W,) its weighted residual per
            degree of freedom (weak form; about 1 where the chain describes the window, NaN
            for an unweighted window); ``names``.
        """
        a, u = as_record(accel, force, self.n)
        stride = operator.index(stride)
        if stride < 1:
            raise ValueError(f"stride must be an integer >= 1, got {stride}")
        out = dict(self._impl.run(a, u, stride))
        n = self.n
        est = out["estimate"]
        out["mass"], out["damping"], out["stiffness"] = est[:, :n], est[:, n : 2 * n], est[:, 2 * n :]
        out["time_s"] = out["sample"] * self.dt
        out["events"] = [
            self._event(s, p, k, b, a_)
            for s, p, k, b, a_ in zip(
                out["event_sample"], out["event_param"], out["event_kind"], out["event_before"], out["event_after"]
            )
        ]
        out["names"] = list(self.names)
        return out

    def _event(self, sample, param, kind, before, after) -> ChangeEvent:
        return ChangeEvent(
            sample=int(sample),
            time_s=float(sample) * self.dt,
            param=int(param),
            name=self.names[int(param)],
            kind={1: "step", 2: "drift"}.get(int(kind), "none"),
            before=float(before),
            after=float(after),
        )

    def _display_fields(self) -> dict:
        return {
            "n": self.n,
            "dt": number(self.dt),
            "boundary": repr(self.boundary),
            "method": repr(str(self.options["method"])),
            "window_s": number(self.window_samples * self.dt),
            "window_results": self.window_results,
            "valid": validity(self.valid),
        }

    def _display_parameters(self) -> list[tuple]:
        return parameter_rows(self.names, self.estimate, self.sigma)
