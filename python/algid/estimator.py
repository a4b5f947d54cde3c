"""Python face of the C++ estimator: ``ChainEstimator(n, dt, boundary)``.

The per-sample work runs in the header-only C++ core (``cpp/include/algid``); this module
only picks the fixed-size instantiation for ``n`` and checks arguments before they cross
into C++. ``update()`` is one sample (for notebooks and control loops), ``run()`` a whole
record with the GIL released.
"""

from __future__ import annotations

import importlib
import os

import numpy as np

from . import _core

#: Chain sizes compiled into the wheel (fixed-size C++ instantiations).
SIZES: tuple[int, ...] = tuple(_core.SIZES)

Status = _core.Status

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
            return importlib.import_module(f".{name}", __package__)
        except ImportError:
            if wanted is not None:
                raise RuntimeError(f"the {level} build of algid is not in this installation "
                                   "(only x86-64 machines with a recent compiler build it)") from None
    return _core


_chains = chain_core()

#: Instruction-set level of the chain estimators in use (see :func:`chain_core`).
ISA: str = str(_chains.ISA)


def as_sample(accel, force, n: int) -> tuple[np.ndarray, np.ndarray]:
    """One simultaneous sample as contiguous float arrays of n entries; ValueError otherwise."""
    a = np.ascontiguousarray(accel, dtype=float).reshape(-1)
    u = np.ascontiguousarray(force, dtype=float).reshape(-1)
    if a.size != n or u.size != n:
        raise ValueError(f"update() takes accel and force with {n} entries, got {a.size} and {u.size}")
    return a, u


def as_record(accel, force, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A whole record as contiguous float arrays of shape (T, n) (1-D accepted for n = 1)."""
    a = np.ascontiguousarray(accel, dtype=float)
    u = np.ascontiguousarray(force, dtype=float)
    if a.ndim == 1 and n == 1:
        a, u = a[:, None], u.reshape(-1, 1)
    if a.ndim != 2 or a.shape[1] != n or u.shape != a.shape:
        raise ValueError(f"run() takes accel and force of the same shape (T, {n}); got {a.shape} and {u.shape}")
    return a, u


class ChainEstimator:
    """On-line algebraic estimator of an n-DOF chain (eqs. 2-7 of the paper).

    Parameters
    ----------
    n : int
        Number of DOF (one of :data:`SIZES`).
    dt : float
        Sample period [s].
    boundary : {"fixed", "free"}
        Right end: a wall (k_{n+1} identified) or free (k_{n+1} = 0 known).
    min_samples : int
        Samples since t0 before any instantaneous solution is trusted.
    min_hadamard : float
        Lowest doubly equilibrated Hadamard ratio of the 4x4 system that is trusted
        (0 = singular, 1 = orthogonal); see the validity rule in ``dof_estimator.hpp``.

    Notes
    -----
    Estimates after sample k describe the window ``[t0, t_k - delay_samples * dt]``
    (the quadrature centres its stencil). A non-finite sample reseeds the estimator.
    """

    def __init__(self, n: int, dt: float, boundary: str = "fixed", min_samples: int = 16,
                 min_hadamard: float = 1e-9) -> None:
        n = int(n)
        if n not in SIZES:
            raise ValueError(f"n = {n} is not compiled in; available chain sizes: {SIZES}")
        if boundary not in ("fixed", "free"):
            raise ValueError(f"boundary must be 'fixed' or 'free', got {boundary!r}")
        self._impl = getattr(_chains, f"ChainEstimator{n}")(float(dt), boundary, int(min_samples),
                                                            float(min_hadamard))
        self.n, self.dt, self.boundary = n, float(dt), boundary

    @property
    def delay_samples(self) -> int:
        """Samples by which the estimates lag the newest sample."""
        return int(self._impl.delay_samples)

    def update(self, accel, force) -> Status:
        """Consume one simultaneous sample: accelerations [m/s^2] and forces [N], shape (n,)."""
        a, u = as_sample(accel, force, self.n)
        return Status(self._impl.update(a, u))

    def reseed(self) -> None:
        """Restart the window: the next sample is the new t0."""
        self._impl.reseed()

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

    @property
    def valid(self) -> np.ndarray:
        """Per-DOF validity of the eq. 7 estimates."""
        return np.asarray(self._impl.valid, dtype=bool)

    @property
    def window(self) -> float:
        """Length [s] of the window the current estimates describe."""
        return float(self._impl.window)

    def theta(self, dof: int) -> np.ndarray:
        """Eq. 7 ``[m_i, c_i, k_i, k_{i+1}]`` of DOF ``dof`` (0-based); both estimates of
        an interior spring are here (slot 3 of DOF i and slot 2 of DOF i+1)."""
        return self._impl.theta(self._dof(dof))

    def theta_instant(self, dof: int) -> np.ndarray:
        """Instantaneous Cramer solution of eq. 5 for DOF ``dof`` (0-based)."""
        return self._impl.theta_instant(self._dof(dof))

    def _dof(self, dof: int) -> int:
        if not 0 <= dof < self.n:
            raise IndexError(f"dof must be in 0..{self.n - 1}")
        return int(dof)

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
        dict with ``status`` (T,), ``mass`` (T, n), ``damping`` (T, n), ``stiffness``
        (T, n+1), ``valid`` (T, n) and ``time_index`` (T,): the sample index whose window
        end the row describes (``k - delay_samples``).
        """
        a, u = as_record(accel, force, self.n)
        out = dict(self._impl.run(a, u, bool(full)))
        out["time_index"] = np.arange(a.shape[0]) - self.delay_samples
        return out
