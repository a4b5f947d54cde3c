"""Damped modes of a chain: natural frequency, damping ratio and shape of every mode, with
their first-order uncertainty from the estimates' standard deviations.

The state ``s = [x; v]`` (2n,) [m, m/s] of eq. 1 obeys ``s' = A s + B u`` with

    A = [[0, I], [-M^-1 K, -M^-1 C]].

A complex pair of eigenvalues ``lambda = -zeta w_n +- i w_d`` is one *underdamped* mode:

    w_n = |lambda|  [rad/s],   zeta = -Re(lambda) / |lambda|,   w_d = Im(lambda) = w_n sqrt(1 - zeta^2),

reported as ``f_n = w_n / 2 pi`` and ``f_d = w_d / 2 pi`` [Hz]. Real eigenvalues come in pairs
too (2n eigenvalues, complex ones in conjugate pairs); two with the closest shapes make one
*overdamped* mode, ``w_n = sqrt(lambda_1 lambda_2)``, ``zeta = -(lambda_1 + lambda_2) / (2 w_n) >= 1``
(with non-proportional damping the pairing is a convention). A zero eigenvalue (no spring to
any wall, e.g. ``k = 0``) makes a *rigid-body* mode: ``f_n = 0``, damping ratio undefined (NaN).

A shape is the displacement part of the eigenvector (of ``lambda`` with ``Im > 0``), scaled
so that its largest entry is 1 (complex in general). With proportional damping
(``K M^-1 C = C M^-1 K``, Caughey's condition) the shapes are real: the undamped modes
``K phi = w^2 M phi``, normalised ``phi^T M phi = 1`` [kg^-1/2] (``real_shape``).

Uncertainty: ``sigma_q = sqrt(diag(J Sigma J^T))`` for every modal quantity ``q`` (``f_n``,
``zeta``, ``|shape|``), ``J`` its first-order Jacobian with respect to the parameters
``m, c, k`` (eigenvalue and eigenvector perturbation of ``A``, :func:`jacobian`; O(n^3), one
eigen-decomposition) and ``Sigma`` their covariance (``diag(sigma^2)`` from the estimates'
standard deviations).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .chain import Chain
from .network import Network, NetworkModel

KINDS = ("underdamped", "overdamped", "rigid")
#: Eigenvalues closer than this (relative) are repeated: no first-order uncertainty there.
REPEATED = 1e-6


@dataclass(frozen=True)
class Mode:
    """One mode of a chain.

    kind : "underdamped", "overdamped" or "rigid".
    frequency_hz : natural frequency ``f_n`` [Hz] (0 for a rigid-body mode).
    damping_ratio : ``zeta`` [-] (< 1 underdamped, >= 1 overdamped, NaN rigid).
    damped_frequency_hz : ``f_d = f_n sqrt(1 - zeta^2)`` [Hz] (0 unless underdamped).
    eigenvalues : the eigenvalues of ``A`` of this mode [1/s] (one of a complex pair).
    shape : (n,) complex displacement shape, largest entry 1.
    real_shape : (n,) mass-normalised real shape [kg^-1/2] with proportional damping, else None.
    sigma_* : one standard deviation of each (NaN without a covariance).
    """

    kind: str
    frequency_hz: float
    damping_ratio: float
    damped_frequency_hz: float
    eigenvalues: tuple
    shape: np.ndarray
    real_shape: np.ndarray | None = None
    sigma_frequency_hz: float = math.nan
    sigma_damping_ratio: float = math.nan
    sigma_shape: np.ndarray = field(default=None)

    def to_json(self) -> dict:
        """Plain JSON types (non-finite numbers as null)."""
        num = _num
        doc = {
            "kind": self.kind,
            "frequency_hz": num(self.frequency_hz),
            "sigma_frequency_hz": num(self.sigma_frequency_hz),
            "damping_ratio": num(self.damping_ratio),
            "sigma_damping_ratio": num(self.sigma_damping_ratio),
            "damped_frequency_hz": num(self.damped_frequency_hz),
            "eigenvalues": [[num(lam.real), num(lam.imag)] for lam in self.eigenvalues],
            "shape_magnitude": [num(v) for v in np.abs(self.shape)],
            "sigma_shape_magnitude": [num(v) for v in self.sigma_shape],
            "shape_phase_deg": [num(v) for v in np.degrees(np.angle(self.shape))],
        }
        if self.real_shape is not None:
            doc["real_shape"] = [num(v) for v in self.real_shape]
        return doc


@dataclass(frozen=True)
class ModalAnalysis:
    """The modes of a chain, sorted by natural frequency, and whether its damping is proportional."""

    modes: tuple
    proportional: bool

    @property
    def frequencies_hz(self) -> np.ndarray:
        """Natural frequencies ``f_n`` [Hz], ascending."""
        return np.array([m.frequency_hz for m in self.modes])

    @property
    def damping_ratios(self) -> np.ndarray:
        """Damping ratios ``zeta`` [-], in the order of the modes."""
        return np.array([m.damping_ratio for m in self.modes])

    def to_json(self) -> list:
        """One JSON object per mode (``mode`` 1-based)."""
        return [{"mode": i + 1, **m.to_json()} for i, m in enumerate(self.modes)]

    def table(self) -> str:
        """The modal table ``algid identify`` prints."""
        lines = ["modes" + (" (proportional damping: real shapes)" if self.proportional else "")]
        for i, m in enumerate(self.modes):
            f = f"{m.frequency_hz:10.5g}" + _pm(m.sigma_frequency_hz) + " Hz"
            z = "zeta n/a" if not math.isfinite(m.damping_ratio) else f"zeta {m.damping_ratio:.4g}"
            z += _pm(m.sigma_damping_ratio)
            shape = " ".join(f"{abs(s):.3g}" for s in m.shape)
            lines.append(f"  {i + 1:>3} {f}  {z}  {m.kind}  |shape| {shape}")
        return "\n".join(lines)


def _num(v: float):
    return float(v) if math.isfinite(v) else None


def _pm(sigma: float) -> str:
    return f" +- {sigma:.2g}" if math.isfinite(sigma) else ""


def state_matrix(chain: Chain) -> np.ndarray:
    """``A`` (2n, 2n) [1/s, 1/s^2] of ``s' = A s + B u`` for the state ``s = [x; v]``."""
    M, C, K = chain.matrices()
    n = chain.n
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = 0.0 - np.linalg.solve(M, K)  # 0.0 - : no negative zeros in the printed matrix
    A[n:, n:] = 0.0 - np.linalg.solve(M, C)
    return A


def _normalised(q: np.ndarray) -> np.ndarray:
    """``q`` divided by its largest entry (that entry becomes 1)."""
    return q / q[np.argmax(np.abs(q))]


def _real_modes(lams: np.ndarray, shapes: np.ndarray, zero: float) -> list[Mode]:
    """Overdamped and rigid-body modes from the real eigenvalues, paired by closest shapes."""
    order = list(np.argsort(np.abs(lams)))
    modes = []
    while order:
        i = order.pop(0)
        if not order:  # only after a numerically split pair: a mode of its own
            j = None
        else:
            unit = shapes / np.linalg.norm(shapes, axis=0)
            j = max(order, key=lambda c: abs(unit[:, i] @ unit[:, c]))
            order.remove(j)
        pair = (lams[i],) if j is None else (lams[i], lams[j])
        shape = _normalised(shapes[:, i].astype(complex))
        if min(abs(lam) for lam in pair) <= zero:
            modes.append(Mode("rigid", 0.0, math.nan, 0.0, tuple(complex(v) for v in pair), shape))
            continue
        wn = math.sqrt(abs(np.prod(pair))) if len(pair) == 2 else abs(pair[0])
        zeta = -sum(pair) / (2 * wn) if len(pair) == 2 else 1.0
        modes.append(Mode("overdamped", wn / (2 * np.pi), zeta, 0.0, tuple(complex(v) for v in pair), shape))
    return modes


def proportional(chain: Chain) -> bool:
    """Caughey's condition ``K M^-1 C = C M^-1 K`` (real, classical mode shapes)."""
    M, C, K = chain.matrices()
    lhs, rhs = K @ np.linalg.solve(M, C), C @ np.linalg.solve(M, K)
    return bool(np.allclose(lhs, rhs, rtol=1e-9, atol=1e-9 * max(np.abs(lhs).max(), np.abs(rhs).max(), 1e-300)))


def _real_shapes(chain: Chain) -> np.ndarray:
    """Undamped mode shapes (n, n) as columns, ascending frequency, ``Phi^T M Phi = I``."""
    from scipy.linalg import eigh

    M, _, K = chain.matrices()
    _, phi = eigh(K, M)  # generalised symmetric problem: M-orthonormal columns
    return phi * np.sign(phi[np.argmax(np.abs(phi), axis=0), np.arange(chain.n)])


def modes(chain: Chain) -> ModalAnalysis:
    """The modes of ``chain`` (no uncertainty), sorted by natural frequency."""
    A = state_matrix(chain)
    lam, vec = np.linalg.eig(A)
    n = chain.n
    scale = max(np.abs(A).max(), 1e-300)
    zero = 1e-6 * scale
    real = np.abs(lam.imag) <= 1e-7 * np.maximum(np.abs(lam), zero)
    out = [
        Mode(
            "underdamped",
            abs(lam[i]) / (2 * np.pi),
            -lam[i].real / abs(lam[i]),
            lam[i].imag / (2 * np.pi),
            (complex(lam[i]),),
            _normalised(vec[:n, i]),
        )
        for i in np.nonzero(~real & (lam.imag > 0))[0]
    ]
    out += _real_modes(lam[real].real, vec[:n, real].real, zero)
    out.sort(key=lambda m: (m.frequency_hz, np.nan_to_num(m.damping_ratio, nan=-1.0)))
    prop = proportional(chain)
    if prop and len(out) == n:
        phi = _real_shapes(chain)
        out = [replace(m, real_shape=phi[:, i]) for i, m in enumerate(out)]
    nan = np.full(n, np.nan)
    return ModalAnalysis(tuple(replace(m, sigma_shape=nan) for m in out), prop)


def rank_one_derivatives(chain: Chain, V: np.ndarray, Vinv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(a, b)``, each (2n+S, 2n): ``V^-1 (dA / dtheta_p) V = outer(a_p, b_p)`` for every
    parameter ``theta = m1..mn, c1..cn, k1..kS`` (a chain: S = n+1). Each derivative of ``A`` is rank one:
    mass ``i`` scales its row of ``[-M^-1 K, -M^-1 C]`` (``-A[n+i] / m_i``), damper ``i`` is
    ``-1/m_i`` on its diagonal, spring ``j`` adds ``-M^-1 d_j d_j^T`` (``d_j`` its row of the
    deformation matrix)."""
    n = chain.n
    A = state_matrix(chain)
    m = chain.mass
    D = chain.deformation_matrix()
    a = np.concatenate([Vinv[:, n:].T, Vinv[:, n:].T, (Vinv[:, n:] @ (-(D / m).T)).T])
    b = np.concatenate([-(A[n:] @ V) / m[:, None], -V[n:] / m[:, None], D @ V[:n]])
    return a, b


def _mode_derivatives(mode: Mode, i: int, lam: np.ndarray, dlam: np.ndarray, x: np.ndarray, dx: np.ndarray):
    """``(d f_n, d zeta, d |shape|)`` per parameter of ``mode``, whose eigenvalue ``i`` (and,
    if overdamped, its partner) moves by ``dlam`` (P, 2n) and shape ``x`` (n,) by ``dx`` (P, n)."""
    if mode.kind == "underdamped":
        ev, d = lam[i], dlam[:, i]
        wn = abs(ev)
        dwn = (np.conj(ev) * d).real / wn
        dzeta = -d.real / wn + ev.real * dwn / wn**2
    else:  # overdamped: w_n^2 = l1 l2, zeta = -(l1 + l2) / 2 w_n
        dist = np.abs(lam - mode.eigenvalues[1])
        dist[i] = np.inf
        j = int(np.argmin(dist))
        l1, l2, d1, d2 = lam[i].real, lam[j].real, dlam[:, i].real, dlam[:, j].real
        wn = np.sqrt(l1 * l2)
        dwn = (l2 * d1 + l1 * d2) / (2 * wn)
        dzeta = -(d1 + d2) / (2 * wn) - mode.damping_ratio * dwn / wn
    r = int(np.argmax(np.abs(x)))
    shape = x / x[r]
    dshape = dx / x[r] - np.outer(dx[:, r], x) / x[r] ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        dabs = (np.conj(shape)[None, :] * dshape).real / np.abs(shape)[None, :]
    dabs[:, r] = 0.0  # the normalising entry is 1 whatever the parameters
    return dwn / (2 * np.pi), dzeta, dabs


def jacobian(chain: Chain, ma: ModalAnalysis | None = None) -> np.ndarray:
    """First-order Jacobian of ``[f_n..., zeta..., |shape| ...]`` (mode by mode) with respect
    to ``m1..mn, c1..cn, k1..k{n+1}``, by perturbation of the diagonalisable
    ``A = V Lambda V^-1``: with ``G = V^-1 dA V = outer(a, b)`` (:func:`rank_one_derivatives`),
    ``d lambda_i = G_ii`` and ``d v_i = sum_{k != i} G_ki / (lambda_i - lambda_k) v_k`` (the
    part along ``v_i`` only rescales the shape, which the normalisation takes out). O(n^3)
    with one eigen-decomposition. Rows of rigid-body modes, and of modes with a repeated
    eigenvalue (:data:`REPEATED`: critical damping), are NaN: first order does not hold there."""
    ma = modes(chain) if ma is None else ma
    n = chain.n
    lam, V = np.linalg.eig(state_matrix(chain))
    a, b = rank_one_derivatives(chain, V, np.linalg.inv(V))  # (P, 2n) each
    dlam = a * b
    k = len(ma.modes)
    J = np.full((2 * k + k * n, a.shape[0]), np.nan)
    for m, mode in enumerate(ma.modes):
        i = int(np.argmin(np.abs(lam - mode.eigenvalues[0])))
        others = np.abs(np.delete(lam, i) - lam[i])
        if mode.kind == "rigid" or others.min() <= REPEATED * abs(lam[i]):
            continue  # not differentiable (a kind change, or a defective pair at critical damping)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            weights = np.where(np.arange(lam.size) == i, 0.0, 1.0 / (lam[i] - lam))  # (2n,)
            dx = ((a * weights) @ V[:n].T) * b[:, [i]]  # (P, n): sum_k V[:n, k] a_pk b_pi / (l_i - l_k)
            df, dz, ds = _mode_derivatives(mode, i, lam, dlam, V[:n, i], dx)
        J[m], J[k + m], J[2 * k + m * n : 2 * k + (m + 1) * n] = df, dz, ds.T
    return J


def modal_analysis(source, sigma=None, covariance=None) -> ModalAnalysis:
    """Modes of a chain with their uncertainties.

    Parameters
    ----------
    source : :class:`algid.Chain`, a :class:`~algid.model.network.NetworkModel`, an
        :class:`algid.Identification`, or an ``algid identify`` JSON document (dict or path);
        the last two carry their own standard deviations.
    sigma : (3n+1,) standard deviations of ``m1..mn, c1..cn, k1..k{n+1}`` [kg, N s/m, N/m]
        (a :class:`~algid.model.network.NetworkModel`: (2n+S,), ``k1..kS``), taken as
        independent; or
    covariance : (3n+1, 3n+1) their covariance (a network model: (2n+S, 2n+S)).

    Returns
    -------
    ModalAnalysis
        The modes; without ``sigma`` or ``covariance`` (and for a bare Chain) their
        ``sigma_*`` fields are NaN.
    """
    chain, packed_sigma = _chain_and_sigma(source)
    if sigma is None and covariance is None and packed_sigma is not None:
        sigma = packed_sigma
    ma = modes(chain)
    if covariance is None and sigma is None:
        return ma
    size = 2 * chain.n + chain.stiffness.size
    cov = np.diag(np.asarray(sigma, dtype=float) ** 2) if covariance is None else np.asarray(covariance, dtype=float)
    if cov.shape != (size, size):
        raise ValueError(f"the covariance must be ({size}, {size}) for n = {chain.n}, got {cov.shape}")
    J = jacobian(chain, ma)
    with np.errstate(invalid="ignore"):
        sd = np.sqrt(np.sum((J @ cov) * J, axis=1))  # diag(J Sigma J^T)
    k = len(ma.modes)
    shapes = sd[2 * k :].reshape(k, chain.n)
    out = tuple(
        replace(m, sigma_frequency_hz=float(sd[i]), sigma_damping_ratio=float(sd[k + i]), sigma_shape=shapes[i])
        for i, m in enumerate(ma.modes)
    )
    return ModalAnalysis(out, ma.proportional)


def _chain_and_sigma(source) -> tuple[Chain, np.ndarray | None]:
    """The chain and the standard deviations of its parameters (None if unknown)."""
    if isinstance(source, (Chain, NetworkModel)):
        return source, None
    if isinstance(source, (dict, str, Path)):
        doc = Chain.read_json(source)
        sigma = np.array(
            [np.nan if v is None else v for v in doc["sigma_mass"] + doc["sigma_damping"] + doc["sigma_stiffness"]],
            dtype=float,
        )
        if "springs" in doc:
            theta = [np.nan if v is None else v for v in doc["mass"] + doc["damping"] + doc["stiffness"]]
            return _network_and_sigma(Network.from_json(doc), theta, sigma)
        chain = Chain.from_json(doc)
    elif hasattr(source, "theta") and isinstance(getattr(source, "boundary", None), Network):
        return _network_and_sigma(source.boundary, source.theta, source.sigma)
    elif hasattr(source, "theta") and hasattr(source, "sigma"):
        chain = Chain.from_packed(source.theta, source.n, source.boundary)
        sigma = np.array(source.sigma, dtype=float)
    else:
        raise TypeError(
            f"expected a Chain, an Identification or an identify JSON document, got {type(source).__name__}"
        )
    known = known_parameters(chain.n, chain.boundary)
    sigma[known] = np.where(np.isfinite(sigma[known]), sigma[known], 0.0)
    return chain, sigma


def _network_and_sigma(net: Network, theta, sigma) -> tuple[NetworkModel, np.ndarray]:
    """The network model of packed estimates ``m1..mn, c1..cn, k1..kS``
    (:meth:`NetworkModel.from_packed`) and their standard deviations, those of the second and
    later springs of a parallel group 0 (known: their sum is in the first)."""
    model = NetworkModel.from_packed(theta, net)
    sigma = np.array(sigma, dtype=float)
    for group in net.parallel_groups():
        for s in group[1:]:
            sigma[2 * net.n + s - 1] = 0.0
    return model, sigma


def known_parameters(n: int, boundary: str) -> np.ndarray:
    """(3n+1,) parameters fixed by the topology, not estimated: ``k_{n+1} = 0`` at a free end;
    for n = 1 with walls ``k_2`` (its estimate is in ``k_1``, the sum)."""
    known = np.zeros(3 * n + 1, bool)
    known[-1] = boundary == "free" or n == 1
    return known


def identification_modes(result) -> tuple[ModalAnalysis | None, str]:
    """Modes of an :class:`algid.Identification` and ``""``, or ``None`` and the one-line
    reason there are none (a parameter without an admissible estimate)."""
    try:
        return modal_analysis(result), ""
    except ValueError as err:
        return None, str(err)


__all__ = [
    "KINDS",
    "ModalAnalysis",
    "Mode",
    "identification_modes",
    "jacobian",
    "known_parameters",
    "modal_analysis",
    "modes",
    "proportional",
    "state_matrix",
]
