"""The n-DOF mass-spring-damper chain of the paper's eq. 1 and its topology.

Spring ``j`` (1-based, ``j = 1 .. n+1``) joins DOF ``j-1`` and DOF ``j``; DOF 0 and
DOF ``n+1`` are the walls (``x_0 = x_{n+1} = 0``). Every mass has a viscous damper
to ground. With a *free* right end spring ``n+1`` is absent (``k_{n+1} = 0`` known).

    m_i x_i'' + c_i x_i' + k_i (x_i - x_{i-1}) + k_{i+1} (x_i - x_{i+1}) = u_i     (1)

The topology (the stiffness matrix, the packed parameter names, which springs enter
which DOF's equation, spring deformations) is built here and nowhere else.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .network import BOUNDARIES, Network, NetworkModel, checked_packed, read_model_json, set_parameters


def _walls(n: int) -> Network:
    """The chain with walls at both ends: every one of the n+1 springs of the packed vector
    (a free chain's ``k_{n+1}`` is 0 there)."""
    return Network.chain(n, "fixed")


def stiffness_matrix(k: np.ndarray) -> np.ndarray:
    """Stiffness matrix K (n, n) [N/m] of eq. 1 from the springs ``k_1 .. k_{n+1}`` (n+1,)."""
    return _walls(len(k) - 1).stiffness_matrix(k)


def parameter_names(n: int) -> list[str]:
    """``m1..mn, c1..cn, k1..k{n+1}``: the order of every packed parameter vector."""
    return _walls(n).parameter_names()


def dof_parameter_names(i: int) -> list[str]:
    """``m_i, c_i, k_i, k_{i+1}`` of DOF ``i`` (0-based): the packed parameters its equation holds."""
    return [f"m{i + 1}", f"c{i + 1}", f"k{i + 1}", f"k{i + 2}"]


def spring_columns(n: int, boundary: str) -> list[list[tuple[int, int]]]:
    """For every DOF equation e (0-based): list of (spring j (1-based), other DOF or -1).

    The column of spring j in equation e is ``x_e - x_other`` (x_other = 0 for a wall).
    For n = 1 the two springs act in parallel: one column (x_1) identifies k_1 + k_2 and
    is attributed to spring 1. With a free right end spring n+1 does not exist.
    """
    net = Network.chain(n, boundary)
    return [[(j, other - 1) for j, other in net.columns(e + 1)] for e in range(n)]


def springs(n: int, boundary: str) -> list[int]:
    """Springs (1-based) that exist and can be told apart: 1..n+1 (fixed), 1..n (free),
    only 1 for n = 1."""
    return Network.chain(n, boundary).identifiable_springs()


def equation_parameter_names(n: int, boundary: str, e: int) -> list[str]:
    """Names of the parameters of DOF ``e``'s own equation (0-based): ``m, c, k<j> ...``."""
    return ["m", "c"] + [f"k{j}" for j, _ in spring_columns(n, boundary)[e]]


def spring_sides(n: int, j: int) -> list[tuple[int, float]]:
    """(DOF equation (0-based), sign) pairs where a force of spring ``j`` (1-based) enters:
    DOF j (+), DOF j-1 (-); for n = 1 only DOF 1 (spring 1, the parallel pair's column)."""
    return [(i - 1, sign) for i, sign in _walls(n).sides(1 if n == 1 else j)]


def deformation_matrix(n: int) -> np.ndarray:
    """``D`` (n+1, n) with ``d = D x``: ``d_j = x_j - x_{j-1}`` [m] for every spring (walls at 0)."""
    return _walls(n).deformation_matrix()


def spring_deformation(x: np.ndarray, j: int, n: int) -> np.ndarray:
    """Deformation ``d_j = x_j - x_{j-1}`` (T,) [m] of spring ``j`` (1-based) from positions
    ``x`` (T, n) (walls at 0); for n = 1, ``x_1`` (both springs in parallel)."""
    return _walls(n).deformation(x, 1 if n == 1 else j)


@dataclass(frozen=True)
class Chain:
    """Physical parameters of an n-DOF chain.

    Parameters
    ----------
    mass : (n,) masses m_i [kg]
    damping : (n,) viscous dampings c_i to ground [N s/m]
    stiffness : (n+1,) spring stiffnesses k_1 .. k_{n+1} [N/m]; with
        ``boundary="free"`` the last entry must be 0.
    boundary : "fixed" (walls at both ends, the paper) or "free" (no right wall).
    """

    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    boundary: str = "fixed"

    def __post_init__(self) -> None:
        m = np.asarray(self.mass, dtype=float).reshape(-1)
        c = np.asarray(self.damping, dtype=float).reshape(-1)
        k = np.asarray(self.stiffness, dtype=float).reshape(-1)
        n = m.size
        if n < 1:
            raise ValueError("a chain needs at least one mass")
        if c.size != n:
            raise ValueError(f"damping has {c.size} entries, expected n = {n}")
        if k.size != n + 1:
            raise ValueError(f"stiffness has {k.size} entries, expected n + 1 = {n + 1}")
        if self.boundary not in BOUNDARIES:
            raise ValueError(f"boundary must be one of {BOUNDARIES}, got {self.boundary!r}")
        if self.boundary == "free":
            k = k.copy()
            if k[-1] != 0.0:
                raise ValueError("a free right end needs stiffness[n] == 0")
        set_parameters(self, m, c, k)

    @property
    def n(self) -> int:
        """Number of degrees of freedom."""
        return int(self.mass.size)

    @property
    def network(self) -> Network:
        """The chain's topology (:meth:`Network.chain`)."""
        return Network.chain(self.n, self.boundary)

    def deformation_matrix(self) -> np.ndarray:
        """``D`` (n+1, n) of all n+1 springs of the packed vector (``d = D x``)."""
        return deformation_matrix(self.n)

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mass, damping and stiffness matrices (M, C, K) of eq. 1."""
        return np.diag(self.mass), np.diag(self.damping), stiffness_matrix(self.stiffness)

    def natural_frequencies_hz(self) -> np.ndarray:
        """Undamped natural frequencies [Hz], ascending (eigenvalues of M^-1 K)."""
        M, _, K = self.matrices()
        lam = np.linalg.eigvals(np.linalg.solve(M, K)).real
        return np.sort(np.sqrt(np.clip(lam, 0.0, None))) / (2 * np.pi)

    def identifiable(self) -> np.ndarray:
        """The 3n+1 parameters the estimator reports, in the order
        ``m_1..m_n, c_1..c_n, k_1..k_{n+1}`` (for n = 1 with walls, k_1 holds the
        identifiable sum k_1 + k_2 and k_2 is NaN)."""
        k = self.stiffness.copy()
        if self.n == 1 and self.boundary == "fixed":
            k = np.array([k[0] + k[1], np.nan])
        return np.concatenate([self.mass, self.damping, k])

    @classmethod
    def from_packed(cls, theta, n: int, boundary: str = "fixed") -> Chain:
        """The chain of packed estimates ``m1..mn, c1..cn, k1..k{n+1}`` (3n+1,) as the estimators
        and ``algid identify`` report them: for n = 1 with walls ``k1`` holds ``k1 + k2`` (the
        springs act in parallel; ``k2`` NaN becomes 0), at a free end ``k{n+1}`` is 0. Raises a
        one-line ``ValueError`` naming every parameter without an estimate or with an inadmissible one."""
        theta = np.array(theta, dtype=float).reshape(-1)
        names = parameter_names(n)
        if theta.size != len(names):
            raise ValueError(f"{theta.size} packed parameters, expected 3n+1 = {len(names)} for n = {n}")
        if boundary == "free" or n == 1:
            theta[-1] = 0.0 if not np.isfinite(theta[-1]) else theta[-1]
        theta = checked_packed(names, theta, "chain")
        return cls(theta[:n], theta[n : 2 * n], theta[2 * n :], boundary)

    @staticmethod
    def read_json(source) -> dict:
        """An ``algid identify`` JSON document from a dict or a path
        (:func:`algid.model.network.read_model_json`)."""
        return read_model_json(source)

    @classmethod
    def from_json(cls, source) -> Chain:
        """The chain an ``algid identify`` result (dict or path of its JSON) describes.

        The JSON's lists ``mass``, ``damping``, ``stiffness`` hold ``m1..mn``, ``c1..cn``,
        ``k1..k{n+1}`` (spring ``j`` is ``stiffness[j-1]``); see :meth:`from_packed` for n = 1
        and free ends. A network's document (``springs``) is read only when its springs are
        those of :meth:`Network.chain` (fixed, or free); any other network raises a one-line
        ``ValueError`` pointing to :meth:`algid.NetworkModel.from_json`."""
        doc = cls.read_json(source)
        boundary = doc.get("boundary", "fixed")
        if "springs" in doc:
            boundary = _chain_boundary(doc, "model" if isinstance(source, dict) else str(source))
        packed = [np.nan if v is None else v for v in doc["mass"] + doc["damping"] + doc["stiffness"]]
        if boundary == "free" and "springs" in doc:
            packed.append(0.0)  # the network of a free chain has no spring n+1
        return cls.from_packed(packed, int(doc["n"]), boundary)

    def to_network(self) -> NetworkModel:
        """The chain as the :class:`NetworkModel` of :meth:`Network.chain` (a free end's
        ``k_{n+1} = 0`` is no spring of that network)."""
        net = self.network
        return NetworkModel(net, self.mass, self.damping, self.stiffness[: net.size])

    def modes(self, sigma=None, covariance=None):
        """Damped modes (:func:`algid.model.modal.modal_analysis`), with uncertainties from the
        standard deviations ``sigma`` (3n+1,) or the ``covariance`` of ``m, c, k`` if given."""
        from .modal import modal_analysis

        return modal_analysis(self, sigma=sigma, covariance=covariance)

    def state_space(self, output: str = "acceleration"):
        """``scipy.signal.StateSpace`` from the forces [N] to the displacements, velocities or
        accelerations (``output``) of every mass (:func:`algid.model.frf.state_space`)."""
        from .frf import state_space

        return state_space(self, output)

    def to_control(self, output: str = "acceleration"):
        """``control.StateSpace`` (python-control) of :meth:`state_space`."""
        from .frf import to_control

        return to_control(self, output)

    def frf(self, f_hz, output: str = "acceleration") -> np.ndarray:
        """Frequency response (F, n, n) at ``f_hz`` [Hz] (:func:`algid.model.frf.frf`)."""
        from .frf import frf

        return frf(self, f_hz, output)

    @staticmethod
    def random(n: int, rng: np.random.Generator, boundary: str = "fixed") -> Chain:
        """A chain with parameters drawn log-uniformly around Table 1's magnitudes."""
        m = rng.uniform(1.0, 4.0, n)
        c = rng.uniform(2.0, 8.0, n)
        k = rng.uniform(500.0, 1500.0, n + 1)
        if boundary == "free":
            k[-1] = 0.0
        return Chain(m, c, k, boundary)


def _chain_boundary(doc: dict, name: str) -> str:
    """The boundary of a network document whose springs are a chain's, else a one-line ``ValueError``."""
    springs = [tuple(p) for p in doc["springs"]]
    for boundary in BOUNDARIES:
        if springs == list(Network.chain(int(doc["n"]), boundary).springs):
            return boundary
    raise ValueError(
        f"{name}: a network of {doc['n']} masses and {len(springs)} springs is not a chain: "
        "read it with algid.NetworkModel.from_json"
    )


#: The paper's Table 1 system (3 DOF, walls at both ends).
TABLE1 = Chain(
    mass=np.array([2.0, 2.5, 3.0]),
    damping=np.array([5.5, 5.0, 4.5]),
    stiffness=np.array([1000.0, 900.0, 900.0, 700.0]),
)
