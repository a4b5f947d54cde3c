"""Python face of the C++ estimator: ``ChainEstimator(n, dt, boundary)``.

The per-sample work runs in the header-only C++ core (``cpp/include/algid``); this module
only picks the instantiation for ``n`` (a fixed-size one for the sizes in :data:`SIZES`, the
run-time sized one for any other n) and the instruction-set build, and converts arguments.
The configuration is the C++ struct itself (:class:`ChainConfig`), defaults included.
``update()`` is one sample (for notebooks and control loops), ``run()`` a whole record with
the GIL released.
"""

from __future__ import annotations

import importlib
import operator
import os

import numpy as np

from .. import _core
from ..messages.deprecation import Histories, renamed_method
from ..messages.display import Displayed, number, parameter_rows, validity
from ..model.chain import parameter_names

#: Chain sizes compiled as fixed-size C++ instantiations; any other n >= 1 runs the run-time
#: sized estimator (the same arithmetic; its cost against the fixed sizes: ``docs/performance.md``).
SIZES: tuple[int, ...] = tuple(_core.SIZES)

Status = _core.Status
#: Configuration of a :class:`ChainEstimator` (the C++ ``ChainConfig``; its defaults are C++'s).
ChainConfig = _core.ChainConfig

#: Instruction-set builds of the chain estimators, widest first: module name and level.
_BUILDS: tuple[tuple[str, str], ...] = (("_core_v4", "x86-64-v4"), ("_core_v3", "x86-64-v3"), ("_core", "x86-64"))


def chain_core(isa: str | None = None):
    """The extension module whose chain estimators this process uses.

    On x86-64 the wheel carries the estimators built three times: for ``x86-64`` (SSE2, any
    x86-64 CPU), ``x86-64-v3`` (AVX2 and FMA, most CPUs since 2013) and ``x86-64-v4``
    (AVX-512). From three DOF on, every DOF of the chain sits in a SIMD lane, 2 per register
    in the ``x86-64`` build and 4 in the wider ones; for one or two DOF the wider builds'
    ``run()`` solves the systems of 8 instants side by side instead (``ChainEstimator`` in
    C++). By default the widest build this CPU runs is used; ``isa`` or the environment
    variable ``ALGID_ISA`` (``x86-64``, ``x86-64-v3``, ``x86-64-v4``) forces one, for
    benchmarks and comparisons. The builds agree to rounding (the wider builds use fused
    multiply-adds); within one build ``run()`` and ``update()`` give the same bits.
    """
    wanted = isa or os.environ.get("ALGID_ISA") or None
    levels = [level for _, level in _BUILDS]
    if wanted is not None and wanted not in levels:
        raise ValueError(f"ALGID_ISA / isa must be one of {levels}, got {wanted!r}")
    for name, level in _BUILDS:
        if wanted is not None and level != wanted:
            continue
        if level != "x86-64" and not _core.cpu_supports(level):
            if wanted is not None:
                raise RuntimeError(f"this CPU cannot run the {level} build of algid")
            continue
        try:
            return importlib.import_module(f"..{name}", __package__)  # the builds sit at the top of algid
        except ImportError:
            if wanted is not None:
                raise RuntimeError(
                    f"the {level} build of algid is not in this installation "
                    "(only x86-64 machines with a recent compiler build it)"
                ) from None
    return _core


_chains = chain_core()

#: Instruction-set level of the chain estimators in use (see :func:`chain_core`).
ISA: str = str(_chains.ISA)


def estimator_class(kind: str, n: int, core=None):
    """The C++ class of a ``kind`` ("Chain" or "Continuous") estimator of n DOF in ``core``
    (default: :func:`chain_core`): the fixed-size one where the module has one (chain
    estimators of the sizes in :data:`SIZES`), else the run-time sized one."""
    core = core or _chains
    return getattr(core, f"{kind}Estimator{n}", None) or getattr(core, f"{kind}EstimatorDynamic")


def config_fields(config) -> list[str]:
    """The settable fields of a configuration struct."""
    return [name for name in dir(config) if not name.startswith("_") and not callable(getattr(config, name))]


def make_config(config, dt, boundary, options: dict):
    """``config`` (a :class:`ChainConfig` or ``ContinuousConfig``, C++ defaults) with ``dt``,
    ``boundary`` and the named ``options`` set; TypeError on an unknown option."""
    unknown = set(options) - set(config_fields(config))
    if unknown:
        raise TypeError(f"unknown option(s) {sorted(unknown)}; known: {config_fields(config)}")
    if dt is not None:
        config.dt = float(dt)
    if boundary is not None:
        config.boundary = boundary
    for name, value in options.items():
        setattr(config, name, value)
    return config


def dofs(n) -> int:
    """The number of DOF as an int >= 1: an integer (not a float, not a bool); TypeError or
    ValueError otherwise."""
    if isinstance(n, (bool, np.bool_)):
        raise TypeError(f"n must be an integer >= 1, got {n!r}")
    try:
        n = operator.index(n)
    except TypeError:
        raise TypeError(f"n must be an integer >= 1, got {n!r} ({type(n).__name__})") from None
    if n < 1:
        raise ValueError(f"n must be an integer >= 1, got {n}")
    return n


def real_signal(x, name: str) -> np.ndarray:
    """``x`` as a contiguous float64 array: real floating point or integer data (converted);
    complex, boolean, masked and object arrays are refused with a TypeError naming them."""
    if isinstance(x, np.ma.MaskedArray):
        raise TypeError(f"{name} is a masked array: fill or drop the masked samples first")
    arr = np.asarray(x)
    if arr.dtype.kind not in "fiu":
        raise TypeError(f"{name} must be real numbers (float or integer), got dtype {arr.dtype}")
    return np.ascontiguousarray(arr, dtype=float)


def as_sample(accel, force, n: int) -> tuple[np.ndarray, np.ndarray]:
    """One simultaneous sample as contiguous float arrays of n entries; ValueError otherwise."""
    a = real_signal(accel, "accel").reshape(-1)
    u = real_signal(force, "force").reshape(-1)
    if a.size != n or u.size != n:
        raise ValueError(f"update() takes accel and force with {n} entries, got {a.size} and {u.size}")
    return a, u


def as_record(accel, force, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A whole record as contiguous float arrays of shape (T, n) (1-D accepted for n = 1)."""
    a = real_signal(accel, "accel")
    u = real_signal(force, "force")
    if a.ndim == 1 and n == 1:
        a, u = a[:, None], u.reshape(-1, 1)
    if a.ndim != 2 or a.shape[1] != n or u.shape != a.shape:
        raise ValueError(f"run() takes accel and force of the same shape (T, {n}); got {a.shape} and {u.shape}")
    return a, u


def spring_index(j: int, n: int) -> int:
    """The 0-based position in ``stiffness`` of spring ``k_j`` (``j`` 1-based, 1..n+1, as in
    the parameter names and the JSON); IndexError otherwise."""
    j = operator.index(j)
    if not 1 <= j <= n + 1:
        raise IndexError(f"springs are numbered k1..k{n + 1} (1-based), got {j}")
    return j - 1


class ChainEstimator(Displayed):
    """On-line algebraic estimator of an n-DOF chain (eqs. 2-7 of the paper).

    Parameters
    ----------
    n : int
        Number of DOF, any n >= 1 (the sizes in :data:`SIZES` are compiled as fixed-size
        instantiations, the others run the run-time sized one).
    dt : float
        Sample period [s].
    boundary : {"fixed", "free"}, optional
        Right end: a wall (k_{n+1} identified, the default) or free (k_{n+1} = 0 known).
    config : ChainConfig, optional
        A whole configuration; ``dt``, ``boundary`` and ``options`` override its fields.
    **options
        Fields of :class:`ChainConfig`: ``min_samples`` (samples since t0 before any
        instantaneous solution is trusted), ``min_hadamard`` (lowest doubly equilibrated
        Hadamard ratio of the system that is trusted: 0 singular, 1 orthogonal; see the
        validity rule in ``algebraic_system.hpp``). Defaults: ``ChainConfig()``.

    Notes
    -----
    Vocabulary shared with :class:`algid.ContinuousEstimator`: :meth:`reset` restarts,
    :attr:`valid` is per DOF (n,), :attr:`ready` is every DOF valid, ``run()`` returns
    ``sample`` and ``time_s`` for every row. Indexing: DOF are 0-based like numpy
    (:meth:`theta` of DOF ``i`` holds ``m_{i+1}, c_{i+1}, k_{i+1}, k_{i+2}``); parameters keep
    their 1-based names (``m1``, ``k2``: :attr:`names`, the JSON of ``algid identify``), and
    :meth:`spring` takes that 1-based spring number (``spring(j) == stiffness[j - 1]``).

    Estimates after sample k describe the window ``[t0, t_k - delay_samples * dt]``
    (the quadrature centres its stencil). A non-finite sample, or one so large that the
    window's systems overflow, resets the estimator (status ``BadInput``); ``valid`` is never
    true for an estimate that is not a number.

    Threads: one estimator serves one thread at a time. ``run()`` releases the GIL; any call
    on the same object from another thread meanwhile raises ``RuntimeError`` (it would mix
    two records). Distinct estimators run in parallel threads exactly as one after the other.
    """

    def __init__(
        self, n: int, dt: float | None = None, boundary: str | None = None, config: ChainConfig | None = None, **options
    ) -> None:
        n = dofs(n)
        if dt is None and config is None:
            raise TypeError("ChainEstimator needs dt (or a config)")
        cfg = make_config(config if config is not None else ChainConfig(), dt, boundary, options)
        self._impl = estimator_class("Chain", n)(cfg, n)
        self.n, self.dt, self.boundary = n, float(cfg.dt), str(cfg.boundary)
        #: parameter names of the packed order ``m1..mn, c1..cn, k1..k{n+1}`` (1-based)
        self.names = parameter_names(n)

    @property
    def config(self) -> ChainConfig:
        """The configuration in force (a copy)."""
        return self._impl.config

    @property
    def delay_samples(self) -> int:
        """Samples by which the estimates lag the newest sample."""
        return int(self._impl.delay_samples)

    def update(self, accel, force) -> Status:
        """Consume one simultaneous sample: accelerations [m/s^2] and forces [N], shape (n,)."""
        a, u = as_sample(accel, force, self.n)
        return Status(self._impl.update(a, u))

    def reset(self) -> None:
        """Restart the window: the next sample is the new t0 (every estimate invalid until
        the window has grown again)."""
        self._impl.reseed()

    reseed = renamed_method("reseed", "reset")

    @property
    def mass(self) -> np.ndarray:
        """Eq. 7 masses m_i [kg] (NaN where not valid)."""
        return self._impl.mass

    @property
    def damping(self) -> np.ndarray:
        """Eq. 7 dampings c_i [N s/m]."""
        return self._impl.damping

    @property
    def stiffness(self) -> np.ndarray:
        """Fused springs k_1..k_{n+1} [N/m] (n = 1 with walls: k_1 = k_1 + k_2, k_2 NaN)."""
        return self._impl.stiffness

    def spring(self, j: int) -> float:
        """Spring ``k_j`` [N/m], ``j`` 1-based (1..n+1) as in :attr:`names` and the JSON."""
        return float(self.stiffness[spring_index(j, self.n)])

    @property
    def valid(self) -> np.ndarray:
        """(n,) per DOF: its eq. 7 estimates are trusted now (enough samples since t0, a
        well-conditioned system, finite values)."""
        return np.asarray(self._impl.valid, dtype=bool)

    @property
    def forced(self) -> np.ndarray:
        """(n,) per DOF: a non-zero force sample has arrived since t0. A DOF without force
        solves its equation for the ratios to its mass and takes its scale from the spring it
        shares with the nearest forced DOF, so one force gives every parameter of the chain
        (NaN and not :attr:`valid` while no forced DOF reaches it)."""
        return np.asarray(self._impl.forced, dtype=bool)

    @property
    def ready(self) -> bool:
        """Every DOF :attr:`valid`."""
        return bool(self.valid.all())

    @property
    def window(self) -> float:
        """Length [s] of the window the current estimates describe."""
        return float(self._impl.window)

    def theta(self, dof: int) -> np.ndarray:
        """Eq. 7 estimates of DOF ``dof`` (0-based, 0..n-1): ``[m, c, k_left, k_right]``,
        i.e. ``m{dof+1}, c{dof+1}, k{dof+1}, k{dof+2}`` in the 1-based names; both estimates
        of an interior spring are here (slot 3 of DOF i and slot 2 of DOF i+1)."""
        return self._impl.theta(int(dof))

    def theta_instant(self, dof: int) -> np.ndarray:
        """Instantaneous Cramer solution of eq. 5 for DOF ``dof`` (0-based)."""
        return self._impl.theta_instant(int(dof))

    def run(self, accel, force, full: bool = False) -> dict[str, np.ndarray]:
        """Feed a whole record through the C++ loop (GIL released).

        Parameters
        ----------
        accel, force : array_like, shape (T, n)
            Accelerations [m/s^2] and forces [N] sampled simultaneously every ``dt``.
        full : bool
            Also return ``theta`` and ``theta_instant`` (T, n, 4) and ``hadamard`` (T, n).

        Returns
        -------
        dict
            ``status`` (T,), ``mass`` (T, n), ``damping`` (T, n), ``stiffness`` (T, n+1),
            ``valid`` (T, n); ``sample`` (T,): the sample index whose window end the row
            describes (``k - delay_samples``) and ``time_s`` (T,) that instant ``sample * dt``
            [s]. The old key ``time_index`` still answers ``out["time_index"]`` (deprecated,
            it is ``sample``).
        """
        a, u = as_record(accel, force, self.n)
        out = dict(self._impl.run(a, u, bool(full)))
        out["sample"] = np.arange(a.shape[0]) - self.delay_samples
        out["time_s"] = out["sample"] * self.dt
        return Histories(out, {"time_index": "sample"})

    def _display_fields(self) -> dict:
        return {
            "n": self.n,
            "dt": number(self.dt),
            "boundary": repr(self.boundary),
            "window_s": number(self.window),
            "valid": validity(self.valid),
        }

    def _display_parameters(self) -> list[tuple]:
        return parameter_rows(self.names, np.concatenate([self.mass, self.damping, self.stiffness]))
